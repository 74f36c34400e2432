#!/usr/bin/env bash
# Builds the bench for the GPU machine (/work/shared/DEVICE.md), copies what
# it needs into .devbin/, and prints the device-tool call that runs it on the
# H100 and leaves the table under $OUT.
#
#   bash benches/device.sh            # build, stage, print the call
#
# The whole bench on both GPU backends runs past the device tool's 10-minute
# call limit, so it runs as two calls, one per backend (BACKEND=ash, then
# BACKEND=wgpu in the printed command), and
#   python3 benches/merge_runs.py ash/bench.json wgpu/bench.json > benches/results/h100.json
# joins them; `strandgraph tables README.md` carries the result into README.
#
# What travels (carry: .gl .devbin, with the tracked tree under 64 MiB): the
# CLI (stripped, gzipped), the Vulkan loader and GL debs, and the baked
# self-shadow SH cache of the distance views' groom (xz) when it fits. Scenes, graphs and
# shaders are in the copied working tree; the binaries find them relative to
# the repository root, where the device tool runs commands.
set -euo pipefail
cd "$(dirname "$0")/.."

# Once per machine: the Vulkan loader, the validation layer (benches/validate.sh)
# and GL libraries for the device.
if ! ls .gl/*.deb >/dev/null 2>&1; then
  grep -qx '/.gl/' .git/info/exclude 2>/dev/null || printf '/.gl/\n' >> .git/info/exclude
  mkdir -p .gl /tmp/amd64/partial
  o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
  apt-get $o update -qq
  (cd .gl && apt-get $o download libvulkan1 vulkan-validationlayers libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
grep -qx '/.devbin/' .git/info/exclude 2>/dev/null || printf '/.devbin/\n' >> .git/info/exclude

cargo build --release --locked -p strandgraph --bin strandgraph
rm -rf .devbin && mkdir -p .devbin
# Line tables make the binary ~100 MiB; stripped and gzipped it is ~6 MiB.
strip -o .devbin/strandgraph target/release/strandgraph
gzip -9 .devbin/strandgraph

# The baked SH of the views' groom, so the device does not bake it again
# (strandgraph-bake caches by content hash under $STRANDGRAPH_CACHE).
cache="${STRANDGRAPH_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/strandgraph}"
if [ -d "$cache" ]; then
  tar -C "$cache" -cf - . | xz -6 -T2 > .devbin/cache.tar.xz
  tracked=$(git ls-files -z | du -cm --files0-from=- | tail -1 | cut -f1)
  used=$(du -sm .devbin .gl | awk '{s+=$1} END {print s}')
  if ((tracked + used >= 63)); then
    rm .devbin/cache.tar.xz
    echo "note: the bake cache does not fit; the device bakes once (slower first prepare)" >&2
  fi
fi
echo "staged in .devbin ($(du -sh .devbin | cut -f1)):"; ls .devbin

cat <<'CALL'

Device-tool call (kind nvidia-h100-x1), once with BACKEND=ash, once with BACKEND=wgpu:
  carry: [".gl", ".devbin"]
  timeout_s: 600
  command:
BACKEND=ash; for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; gunzip -c .devbin/strandgraph.gz > /tmp/strandgraph && chmod +x /tmp/strandgraph; mkdir -p /tmp/sg; [ -f .devbin/cache.tar.xz ] && xz -dc .devbin/cache.tar.xz | tar -C /tmp/sg -xf -; export XDG_RUNTIME_DIR=/tmp VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json STRANDGRAPH_CACHE=/tmp/sg; nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; mkdir -p $OUT/$BACKEND; timeout 575 /tmp/strandgraph bench --backend $BACKEND --frames 10 --warmup 2 --out $OUT/$BACKEND > $OUT/$BACKEND/stdout.txt 2>&1; echo "bench exit $?"; head -60 $OUT/$BACKEND/bench.txt
CALL
