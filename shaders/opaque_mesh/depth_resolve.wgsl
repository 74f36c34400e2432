// scene.depth_resolve: scene.depth from the visibility buffer. Port of
// passes/src/opaque_mesh/depth_resolve.rs: the depth bits of each pixel's
// visibility word, or 1.0 (the far plane) where it is empty (all ones).
//
// Entry `resolve_hiz` is scene.depth_hiz: one workgroup per 16x16 block,
// which also writes the block's farthest depth to `hiz`, as
// kulikov/depth_downsample.wgsl does from scene.depth.
//
// Bindings (group 0): 0 = parameters, 1 = scene.visibility (read as word
// pairs, low word first), 2 = scene.depth (R32Float storage image),
// 3 = hiz (R32Float storage image, scene.depth_hiz only).

#import strandgraph::hiz::{hiz_block, hiz_block_pixel, hiz_bits}

struct DepthResolveParams {
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: DepthResolveParams;
@group(0) @binding(1) var<storage, read> scene_visibility: array<vec2<u32>>;
@group(0) @binding(2) var scene_depth: texture_storage_2d<r32float, write>;
@group(0) @binding(3) var hiz: texture_storage_2d<r32float, write>;

// depth_resolve::depth: the far plane where no triangle is.
fn resolved(i: u32) -> f32 {
    let v = scene_visibility[i];
    let empty = v.x == 0xFFFFFFFFu && v.y == 0xFFFFFFFFu;
    return select(bitcast<f32>(v.y), 1.0, empty);
}

@compute @workgroup_size(256)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.width * params.height {
        return;
    }
    textureStore(scene_depth, vec2<u32>(i % params.width, i / params.width), vec4<f32>(resolved(i), 0.0, 0.0, 1.0));
}

var<workgroup> farthest: atomic<u32>;

@compute @workgroup_size(256)
fn resolve_hiz(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    if lane == 0u {
        atomicStore(&farthest, 0u);
    }
    workgroupBarrier();
    let p = hiz_block_pixel(wg.x, lane, params.width);
    if p.x < params.width && p.y < params.height {
        let z = resolved(p.y * params.width + p.x);
        textureStore(scene_depth, p, vec4<f32>(z, 0.0, 0.0, 1.0));
        atomicMax(&farthest, hiz_bits(z));
    }
    workgroupBarrier();
    if lane == 0u {
        textureStore(hiz, hiz_block(wg.x, params.width), vec4<f32>(bitcast<f32>(atomicLoad(&farthest)), 0.0, 0.0, 1.0));
    }
}
