#!/usr/bin/env bash
# Builds the bench for the GPU machine (/work/shared/DEVICE.md), copies what
# it needs into .devbin/, and prints the device-tool call that runs it on the
# H100 and leaves the table under $OUT.
#
#   bash benches/device.sh            # build, stage, print the call
#
# ash and wgpu run in one process (the driver is held loaded, see
# strandgraph_ash::keep_driver_loaded), so one bench.json holds both; copy it
# to benches/results/h100.json and run `strandgraph tables` to carry it into
# README.
#
# What travels (carry: .gl .devbin, under 64 MiB): the CLI (stripped), the
# Vulkan loader and GL debs, and the baked self-shadow
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
rm -rf .devbin && mkdir -p .devbin
cp target/release/strandgraph .devbin/
# Line tables make the binary ~100 MiB; the device carries 64 MiB in all.
strip .devbin/strandgraph

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
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; export XDG_RUNTIME_DIR=/tmp VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json STRANDGRAPH_CACHE=$PWD/.devbin/cache; nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; mkdir -p $OUT/gpu; timeout 560 .devbin/strandgraph bench --backend ash,wgpu --frames 10 --warmup 2 --out $OUT/gpu > $OUT/gpu/stdout.txt 2>&1; echo "bench exit $?"; head -60 $OUT/gpu/bench.txt
CALL
