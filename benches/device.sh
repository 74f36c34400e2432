#!/usr/bin/env bash
# Builds the bench for the GPU machine (/work/shared/DEVICE.md), copies what
# it needs into .devbin/, and prints the device-tool call that runs it on the
# H100 and leaves the table under $OUT.
#
#   bash benches/device.sh            # build, stage, print the call
#
# One process per backend: on NVIDIA's driver, creating some thirty Vulkan
# devices in one process (wgpu's and ash's cells together) ends in
# "vkCreateInstance: Unable to find a Vulkan driver"; each alone is fine.
#
# What travels (carry: .gl .devbin, under 64 MiB): the CLI, the criterion
# bench binaries, the Vulkan loader and GL debs, and the baked self-shadow
# SH cache for the distance views' groom when it fits. Scenes, graphs and
# shaders are in the copied working tree; the binaries find them relative to
# the repository root, where the device tool runs commands.
set -euo pipefail
cd "$(dirname "$0")/.."

# Once per machine: the Vulkan loader and GL libraries for the device.
if ! ls .gl/*.deb >/dev/null 2>&1; then
  grep -qx '/.gl/' .git/info/exclude 2>/dev/null || printf '/.gl/\n' >> .git/info/exclude
  mkdir -p .gl /tmp/amd64/partial
  o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
  apt-get $o update -qq
  (cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
grep -qx '/.devbin/' .git/info/exclude 2>/dev/null || printf '/.devbin/\n' >> .git/info/exclude

cargo build --release --locked -p strandgraph --bin strandgraph
benches=$(cargo bench --locked --no-run --message-format=json -p strandgraph 2>/dev/null |
  python3 -c '
import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("executable") and "bench" in m["target"]["kind"]:
        print(m["target"]["name"], m["executable"])
')
rm -rf .devbin && mkdir -p .devbin
cp target/release/strandgraph .devbin/
while read -r name exe; do
  [ -n "$name" ] && cp "$exe" ".devbin/$name"
done <<<"$benches"

# The baked SH of the views' groom, so the device does not bake it again
# (strandgraph-bake caches by content hash under $STRANDGRAPH_CACHE).
cache="${STRANDGRAPH_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/strandgraph}"
if [ -d "$cache" ]; then
  used=$(du -sm .devbin .gl | awk '{s+=$1} END {print s}')
  extra=$(du -sm "$cache" | awk '{print $1}')
  if ((used + extra < 60)); then
    cp -r "$cache" .devbin/cache
  else
    echo "note: the bake cache ($extra MiB) does not fit; the device bakes once (slower first prepare)" >&2
  fi
fi
echo "staged in .devbin ($(du -sh .devbin | cut -f1)):"; ls .devbin

cat <<'CALL'

Device-tool call (kind nvidia-h100-x1):
  carry: [".gl", ".devbin"]
  timeout_s: 600
  command:
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; export XDG_RUNTIME_DIR=/tmp VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json STRANDGRAPH_CACHE=$PWD/.devbin/cache; nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; for b in cpu wgpu ash; do mkdir -p $OUT/$b; timeout 180 .devbin/strandgraph bench --backend $b --frames 10 --warmup 2 --out $OUT/$b > $OUT/$b/stdout.txt 2>&1; echo "bench $b exit $?"; done; STRANDGRAPH_BENCH_SIZE=1920x1080 timeout 150 .devbin/frame --bench 'frame/(wgpu|ash)/' > $OUT/criterion_frame.txt 2>&1; cat $OUT/ash/bench.txt; grep -E '^frame/|time:' $OUT/criterion_frame.txt | tail -20
CALL
