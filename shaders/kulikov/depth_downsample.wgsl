// kulikov.depth_downsample: the farthest scene depth of each 16x16 block.
// Port of passes/src/kulikov/depth_downsample.rs: one workgroup per block,
// one lane per texel, the maximum an atomicMax on the depth bits.

#import strandgraph::hiz::HIZ_FACTOR

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
    let hw = (params.width + HIZ_FACTOR - 1u) / HIZ_FACTOR;
    let bx = wg.x % hw * HIZ_FACTOR;
    let by = wg.x / hw * HIZ_FACTOR;
    let x = bx + lane % HIZ_FACTOR;
    let y = by + lane / HIZ_FACTOR;
    if x < params.width && y < params.height {
        // Depths are in [0, 1]; clearing the sign keeps a -0.0 from winning.
        let bits = bitcast<u32>(textureLoad(scene_depth, vec2<u32>(x, y), 0).x) & 0x7FFFFFFFu;
        atomicMax(&farthest, bits);
    }
    workgroupBarrier();
    if lane == 0u {
        let far = bitcast<f32>(atomicLoad(&farthest));
        textureStore(hiz, vec2<u32>(wg.x % hw, wg.x / hw), vec4<f32>(far, 0.0, 0.0, 1.0));
    }
}
