// kulikov.store_history: this frame's camera and LOD kept for the next
// frame's motion (passes/src/kulikov/motion.rs). The per-vertex history
// itself is kept by kulikov.skin_motion (skin.wgsl).
//
// Bindings (group 0): 0 = HistoryParams, 1 = frame, 2 = lod_models,
// 3 = prev_frame, 4 = prev_lod_models.
#import strandgraph::layout::{FrameData, ModelLod}

// The pass has no parameters; the block keeps binding 0 the same for every pass.
struct HistoryParams {
    reserved: u32,
}

@group(0) @binding(0) var<uniform> params: HistoryParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> lod_models: array<ModelLod>;
@group(0) @binding(3) var<storage, read_write> prev_frame: FrameData;
@group(0) @binding(4) var<storage, read_write> prev_lod_models: array<ModelLod>;

@compute @workgroup_size(256)
fn store_history(@builtin(local_invocation_index) lane: u32) {
    _ = params.reserved;
    if lane == 0u {
        prev_frame = frame;
    }
    for (var m = lane; m < frame.model_count; m += 256u) {
        prev_lod_models[m] = lod_models[m];
    }
}
