// scene.depth_prepass: opaque meshes (heads, bodies) into scene.depth.
//
// A depth-only raster pipeline; the CPU kernel is passes/src/scene/depth_prepass.rs.
// Pipeline state the backend sets: topology TriangleList, FrontFace::Ccw,
// CullMode::Back; depth attachment `scene.depth` (Depth32Float) cleared to 1.0,
// compare Less, writes on; no colour attachments. Draw 3 × triangles vertices,
// no vertex buffers: the vertex shader pulls corners from `mesh.triangles`.
//
// Bindings (group 0), in the order of the pass's bindings less its attachments,
// every record a storage buffer (as shaders/common/layout.wgsl assumes):
// 0 = frame, 1 = mesh.triangles.
//
// The structs mirror passes/src/layout.rs (and shaders/common/layout.wgsl)
// field for field; naga reports the same sizes and offsets as the Rust structs.

// FrameData (256 bytes).
struct FrameData {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    camera_pos: vec4<f32>,
    screen: vec4<f32>,
    near: f32,
    far: f32,
    model_count: u32,
    light_count: u32,
    pixels_per_unit: f32,
    _pad: array<u32, 19>,
}

// TriangleData (64 bytes). Each corner's w holds its
// octahedral-packed smooth normal as raw bits (unused here).
struct TriangleData {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    mesh: u32,
    _pad: array<u32, 3>,
}

@group(0) @binding(0) var<storage, read> frame: FrameData;
@group(0) @binding(1) var<storage, read> triangles: array<TriangleData>;

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
    let t = triangles[vertex / 3u];
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
