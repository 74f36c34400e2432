// kulikov.depth_downsample: the farthest scene depth of each 16x16 block.
// Port of passes/src/kulikov/depth_downsample.rs: one workgroup per block,
// one lane per texel, the maximum an atomicMax on the depth bits.

#import strandgraph::hiz::{hiz_block, hiz_block_pixel, hiz_bits}

// The screen size the CPU kernel reads from the scene quantities.
struct DepthDownsampleParams {
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: DepthDownsampleParams;
@group(0) @binding(1) var scene_depth: texture_2d<f32>;
@group(0) @binding(2) var hiz: texture_storage_2d<r32float, write>;

var<workgroup> farthest: atomic<u32>;

@compute @workgroup_size(256)
fn downsample(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane == 0u {
        atomicStore(&farthest, 0u);
    }
    workgroupBarrier();
    let p = hiz_block_pixel(wg.x, lane, params.width);
    if p.x < params.width && p.y < params.height {
        atomicMax(&farthest, hiz_bits(textureLoad(scene_depth, p, 0).x));
    }
    workgroupBarrier();
    if lane == 0u {
        let far = bitcast<f32>(atomicLoad(&farthest));
        textureStore(hiz, hiz_block(wg.x, params.width), vec4<f32>(far, 0.0, 0.0, 1.0));
    }
}
