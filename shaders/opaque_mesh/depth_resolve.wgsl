// scene.depth_resolve: scene.depth from the visibility buffer. Port of
// passes/src/opaque_mesh/depth_resolve.rs: the depth bits of each pixel's
// visibility word, or 1.0 (the far plane) where it is empty (all ones).
//
// Bindings (group 0): 0 = parameters, 1 = scene.visibility (read as word
// pairs, low word first), 2 = scene.depth (R32Float storage image).

struct DepthResolveParams {
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> params: DepthResolveParams;
@group(0) @binding(1) var<storage, read> scene_visibility: array<vec2<u32>>;
@group(0) @binding(2) var scene_depth: texture_storage_2d<r32float, write>;

@compute @workgroup_size(256)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.width * params.height {
        return;
    }
    let v = scene_visibility[i];
    let empty = v.x == 0xFFFFFFFFu && v.y == 0xFFFFFFFFu;
    let z = select(bitcast<f32>(v.y), 1.0, empty);
    textureStore(scene_depth, vec2<u32>(i % params.width, i / params.width), vec4<f32>(z, 0.0, 0.0, 1.0));
}
