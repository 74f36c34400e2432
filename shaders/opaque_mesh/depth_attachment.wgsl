// scene.depth_attachment: scene.depth (R32Float, written in compute) into
// the depth attachment the hardware-raster hair passes test against. Port of
// passes/src/opaque_mesh/depth_attachment.rs.
//
// One triangle covering the screen; each fragment writes the texel's depth
// with frag_depth (compare Always, writes on), so the copy is exact.
//
// Bindings (group 0), less the depth attachment `depth_buffer`:
// 0 = parameters (unused), 1 = scene.depth.

struct DepthAttachmentParams {
    unused: u32,
}

@group(0) @binding(0) var<uniform> params: DepthAttachmentParams;
@group(0) @binding(1) var scene_depth: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> @builtin(position) vec4<f32> {
    // Keeps the (empty) parameter block bound, as every pass's is.
    _ = params.unused;
    // (-1, -1), (3, -1), (-1, 3): counter-clockwise, covers the screen.
    let x = f32(vertex & 1u) * 4.0 - 1.0;
    let y = f32(vertex >> 1u) * 4.0 - 1.0;
    return vec4<f32>(x, y, 0.5, 1.0);
}

struct DepthOut {
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> DepthOut {
    var out: DepthOut;
    out.depth = textureLoad(scene_depth, vec2<i32>(position.xy), 0).x;
    return out;
}
