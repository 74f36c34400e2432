// The GPU data layout every pass shares (mirrors passes/src/layout.rs and the
// 8-word records of passes/src/kulikov). Composed with naga_oil:
//   #import strandgraph::layout::{FrameData, ModelData}
// Every record is bound as a storage buffer, so std430 rules apply: the
// sizes below equal size_of::<T>() of the Rust structs (checked by
// passes/tests/wgsl_shared.rs).
#define_import_path strandgraph::layout

// `frame`: camera and screen (256 bytes).
struct FrameData {
    // Column-major world -> clip.
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    // xyz, 1.
    camera_pos: vec4<f32>,
    // width, height, 1/width, 1/height.
    screen: vec4<f32>,
    near: f32,
    far: f32,
    model_count: u32,
    light_count: u32,
    // Pixels per world unit at view depth 1.
    pixels_per_unit: f32,
    // Seconds since the animation's start and since the last frame.
    time: f32,
    delta_time: f32,
    // 1: the simulation starts over from the rest pose.
    sim_reset: u32,
    _pad: array<u32, 16>,
}

// `models`: one hair model (256 bytes).
struct ModelData {
    world: mat4x4<f32>,
    bounds_min: vec4<f32>,
    bounds_max: vec4<f32>,
    strand_first: u32,
    strand_count: u32,
    points_per_strand: u32,
    vertex_first: u32,
    segment_first: u32,
    skinned: u32,
    triangle_first: u32,
    // Bit 0: LOD enabled; bit 1: facial hair.
    flags: u32,
    // Rows of the parent mesh's local -> world rotation (w unused).
    mesh_rotation: array<vec4<f32>, 3>,
    color: vec4<f32>,
    fedora_min: vec4<f32>,
    fedora_max: vec4<f32>,
    fedora_sphere: vec4<f32>,
    min_fraction: f32,
    // Cuticle tilt α, radians (the material's highlight_shift_deg).
    highlight_shift: f32,
    // Strand thickness in metres (the groom's first vertex's).
    thickness: f32,
    _pad: u32,
}

const MODEL_LOD_ENABLED: u32 = 1u;
const MODEL_FACIAL_HAIR: u32 = 2u;

// `lights` (64 bytes).
struct LightData {
    position_or_direction: vec4<f32>,
    radiance: vec4<f32>,
    _pad: array<u32, 8>,
}

// `mesh.triangles` (64 bytes); each corner's w holds its octahedral normal bits.
struct TriangleData {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    mesh: u32,
    // Each corner's albedo: 8-bit square roots of linear RGB, alpha 255; 0 = unset.
    albedo: array<u32, 3>,
}

// `lod_models`: the LOD decision per model (kulikov::ModelLod, 8 words).
// Readers treat a vertex_step of 0 as 1, as ModelLod::load does.
struct ModelLod {
    strands: u32,
    vertex_step: u32,
    thickness_scale: f32,
    segments_per_strand: u32,
    strand_prefix: u32,
    depth_near: f32,
    depth_far: f32,
    // Drawn segments of all earlier models (kulikov::cull::nth_drawn).
    segment_prefix: u32,
}

// `atlas_tiles`: one model's part of the atlas (kulikov::tile_alloc::ModelTiles, 8 words).
// Readers treat a downscale of 0 as 1, as ModelTiles::load does.
struct ModelTiles {
    first_tile: u32,
    grid_w: u32,
    grid_h: u32,
    origin_x: u32,
    origin_y: u32,
    downscale: u32,
    valid: u32,
    _pad: u32,
}
