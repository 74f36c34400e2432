// scene.depth_prepass: opaque meshes (heads, bodies) into scene.depth.
//
// A depth-only raster pipeline; the CPU kernel is passes/src/opaque_mesh/depth_prepass.rs.
// Pipeline state the backend sets: topology TriangleList, FrontFace::Ccw,
// CullMode::Back; depth attachment `scene.depth` (Depth32Float) cleared to 1.0,
// compare Less, writes on; no colour attachments. Draw 3 × triangles vertices,
// no vertex buffers: the vertex shader pulls corners from `mesh.triangles`.
//
// Bindings (group 0), in the order of the pass's bindings less its attachments,
// every record a storage buffer (as shaders/common/layout.wgsl assumes):
// 0 = the parameter block, 1 = frame, 2 = mesh.triangles.
//
#import strandgraph::layout::{FrameData, TriangleData}

// The pass has no parameters; the block keeps binding 0 the same for every pass.
struct DepthPrepassParams {
    unused: u32,
}

@group(0) @binding(0) var<uniform> params: DepthPrepassParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
@group(0) @binding(2) var<storage, read> mesh_triangles: array<TriangleData>;

struct VertexOut {
    // Invariant: scene.opaque recomputes the same position and tests depth
    // Equal, so both pipelines must produce bit-identical depth.
    @invariant @builtin(position) position: vec4<f32>,
}

fn clip_corner(t: TriangleData, k: u32) -> vec4<f32> {
    var p = t.a.xyz;
    if k == 1u {
        p = t.b.xyz;
    } else if k == 2u {
        p = t.c.xyz;
    }
    return frame.view_proj * vec4<f32>(p, 1.0);
}

@vertex
fn vs_main(@builtin(vertex_index) vertex: u32) -> VertexOut {
    // Keeps the (empty) parameter block bound, as every pass's is.
    _ = params.unused;
    let t = mesh_triangles[vertex / 3u];
    let clip_a = clip_corner(t, 0u);
    let clip_b = clip_corner(t, 1u);
    let clip_c = clip_corner(t, 2u);
    var out: VertexOut;
    // Like the CPU kernel, drop (rather than clip) a triangle with any corner
    // at or behind the near plane: collapse it to a point, which covers no
    // pixel. Heads never cross the near plane in our scenes.
    if min(clip_a.w, min(clip_b.w, clip_c.w)) <= frame.near {
        out.position = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return out;
    }
    out.position = clip_corner(t, vertex % 3u);
    return out;
}

// Depth only: the rasterizer writes depth, the fragment stage has nothing to add.
@fragment
fn fs_main() {
}
