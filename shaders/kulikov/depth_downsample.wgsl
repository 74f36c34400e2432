// kulikov.depth_downsample: the farthest scene depth of each 16x16 block.
// Port of passes/src/kulikov/depth_downsample.rs.

#import strandgraph::kulikov::HIZ_FACTOR

// The screen size the CPU kernel reads from the scene quantities.
struct DepthDownsampleParams {
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: DepthDownsampleParams;
@group(0) @binding(1) var scene_depth: texture_2d<f32>;
@group(0) @binding(2) var hiz: texture_storage_2d<r32float, write>;

@compute @workgroup_size(64)
fn downsample(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let w = params.width;
    let h = params.height;
    let hw = (w + HIZ_FACTOR - 1u) / HIZ_FACTOR;
    let hh = (h + HIZ_FACTOR - 1u) / HIZ_FACTOR;
    let i = wg.x * 64u + lane;
    if i >= hw * hh {
        return;
    }
    let bx = i % hw * HIZ_FACTOR;
    let by = i / hw * HIZ_FACTOR;
    var far = 0.0;
    for (var y = by; y < min(by + HIZ_FACTOR, h); y++) {
        for (var x = bx; x < min(bx + HIZ_FACTOR, w); x++) {
            far = max(far, textureLoad(scene_depth, vec2<u32>(x, y), 0).x);
        }
    }
    textureStore(hiz, vec2<u32>(i % hw, i / hw), vec4<f32>(far, 0.0, 0.0, 1.0));
}
