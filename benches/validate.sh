#!/usr/bin/env bash
# Every shipped graph on ash under the Khronos validation layer with
# synchronization validation (STRANDGRAPH_VK_VALIDATION=1: any message fails
# the render), on the GPU machine. Stage with `bash benches/device.sh`
# (its .gl/ holds the layer's deb), then run through the device tool with
# carry [".gl", ".devbin"] and the command `bash benches/validate.sh`.
# Writes $OUT/validation.txt: one line per scene and graph with the exit
# status (benches/results/validation-h100.txt is the committed run).
set -u
cd "$(dirname "$0")/.."
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
gunzip -c .devbin/strandgraph.gz > /tmp/strandgraph && chmod +x /tmp/strandgraph
export XDG_RUNTIME_DIR=/tmp STRANDGRAPH_CACHE=/tmp/sg VK_LAYER_PATH=/usr/share/vulkan/explicit_layer.d
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/sg "$OUT"
log="$OUT/validation.txt"
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > "$log"
run() { # scene graph size
  local tag
  tag="$(basename "$1" .ron)_$(basename "$2" .ron)_$3"
  STRANDGRAPH_VK_VALIDATION=1 timeout 120 /tmp/strandgraph render "$1" --graph "$2" \
    --backend ash --size "$3" -o "/tmp/$tag.png" > "/tmp/$tag.log" 2>&1
  local rc=$?
  grep -q "validation: Khronos layer with synchronization validation" "/tmp/$tag.log" \
    || { echo "$tag: the layer was not enabled" >> "$log"; rc=1; }
  echo "$tag rc=$rc" >> "$log"
  [ "$rc" = 0 ] || tail -5 "/tmp/$tag.log" >> "$log"
}
for g in scenes/graphs/*.ron; do
  case $g in *roofline*) continue ;; esac
  run scenes/showcase.ron "$g" 960x540
done
for g in kulikov lipp scheuermann hw_strands kulikov_reference; do
  run scenes/crowd.ron "scenes/graphs/$g.ron" 960x540
done
for g in kulikov lipp hw_strands hw_mesh scheuermann kulikov_reference lipp_reference; do
  run scenes/adversarial/inside_hair.ron "scenes/graphs/$g.ron" 1920x1080
done
echo "$(grep -c ' rc=0$' "$log") of $(grep -c ' rc=' "$log") renders without a validation message" | tee -a "$log"
