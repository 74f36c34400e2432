#!/usr/bin/env bash
# Runs every test on a fresh Debian machine: installs what the tests need
# (Graphviz for the DOT export check; Chromium for the HTML report's; Xvfb
# for the viewer's window; a Vulkan driver, lavapipe, and the Vulkan loader
# for the wgpu differential test when no Vulkan device is installed), then
# the workspace tests, a quick pass of the criterion benches so they keep
# building and running, and a smoke run of every fuzz target.
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
command -v dot >/dev/null 2>&1 || missing+=(graphviz)
# tests/report.rs opens the HTML report in headless Chromium and fails
# without it.
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
# tests/diff_wgpu.rs needs a Vulkan adapter and fails without one. Any ICD
# manifest counts (lavapipe's is lvp_icd*.json, NVIDIA's nvidia_icd.json).
icds=$(ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json 2>/dev/null || true)
[ -n "$icds" ] || missing+=(mesa-vulkan-drivers)
ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' || missing+=(libvulkan1)
# The ash tests run under the Khronos validation layer (synchronization
# validation on) and fail, not skip, without it.
ls /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json >/dev/null 2>&1 || missing+=(vulkan-validationlayers)
# tests/view.rs opens the viewer's window under Xvfb; winit loads the X
# libraries at run time.
command -v xvfb-run >/dev/null 2>&1 || missing+=(xvfb)
for lib in xauth libx11-xcb1 libxcursor1 libxi6 libxrandr2 libxkbcommon-x11-0; do
  dpkg -s "$lib" >/dev/null 2>&1 || missing+=("$lib")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" = 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

cargo fmt --all -- --check
cargo test --workspace --release --locked
# The Table-1 bench on every backend that opens here (cpu, and wgpu and
# ash on lavapipe): 320x180, 2 frames per cell, the mid view only. The
# three views differ only in the camera's distance (which the LOD tests
# cover) and took 600 s here on 2 cores, the mid view alone 190 s. The
# binary `cargo test` built for the CLI tests (`cargo run` would rebuild
# the workspace with the root package's features alone).
target/release/strandgraph bench --quick --backend all scenes/distances/mid.ron
# Benches report, they do not assert; --quick keeps this to seconds.
cargo bench --locked --bench graph_compile -- --quick
# An installed binary renders from any directory: `cargo install` into a
# scratch root (reusing this build's artifacts), then the built-in demo
# scene from an empty directory (the binary holds its shaders, the scene
# and the graph).
install_root=$(mktemp -d)
empty_dir=$(mktemp -d)
cargo install --path . --root "$install_root" --locked --target-dir target --quiet
(cd "$empty_dir" && "$install_root/bin/strandgraph" render --demo --size 320x180 -o demo.png && test -s demo.png)
rm -rf "$install_root" "$empty_dir"
echo "installed binary: rendered the demo scene from an empty directory"
# Every fuzz target for 10 s over its committed corpus, under the
# campaigns' memory and time limits (nightly and cargo-fuzz; fuzz/README.md).
bash scripts/fuzz_smoke.sh
