// hw_strands.mesh: the mesh-shader path of the hardware baseline (Bhokare
// et al. 2024, the pipeline Lipp Table 1 compares against). Port of
// passes/src/hw_strands/mesh.rs.
//
// - ts_main, one task workgroup per bundle: applies the LOD lipp.lod chose
//   for it (N_LOD strands of C control points, none when culled) by
//   launching one mesh workgroup per strand and chunk of MESH_SEGMENTS
//   segments.
// - ms_main, 32 lanes: assembles its strand with Lipp's Code 1 (the code
//   hw_strands.assemble and lipp.raster run), projects each control point,
//   and emits its chunk's segments as the same camera-facing quads
//   hw_strands.raster draws (4 vertices, 2 triangles each), with no buffer
//   between assembly and rasterization.
// - fs_main: hw_strands.raster's fragment (hw_strands/quad.wgsl).

enable wgpu_mesh_shader;

#define FRAME_BINDING 1
#define MODELS_BINDING 9
#define LIGHTS_BINDING 10
#define SCENE_DEPTH_BINDING 6
#define HAIR_DEPTH_BINDING 7
#define GBUFFER_BINDING 8
#import strandgraph::lipp_dom::frame
#import strandgraph::clip::transform
#import strandgraph::lipp::{LOD_WORDS, RASTER_GROUP, MAX_CONTROL_POINTS}
#import strandgraph::hw_strands_segment::segment_bits
#import strandgraph::hw_strands_quad::{QuadVertex, quad_corner_clipped, write_sample}
#import strandgraph::lipp_assembly::{raster_args, bundle_lod, ControlPoint, load_strand, bundle_range, lanes_of, pass_one, pass_two, strip_point, strip_tangent, strip_segments}

struct MeshParams {
    // Quad width in pixels (lipp.raster's centre_diameter).
    width_px: f32,
    width: u32,
    height: u32,
    model_index: u32,
    cooperative_assembly: u32,
    styling: u32,
    bundles: u32,
    _pad0: u32,
}

// hw_strands::mesh::MESH_SEGMENTS: segments per mesh workgroup, 4 vertices
// and 2 triangles each (256 vertices and 128 triangles: VK_EXT_mesh_shader
// guarantees maxMeshOutputVertices and maxMeshOutputPrimitives >= 256).
const MESH_SEGMENTS: u32 = 64u;

@group(0) @binding(0) var<uniform> params: MeshParams;

// What a bundle's task workgroup hands its mesh workgroups.
struct Task {
    first_strand: u32,
    chunks: u32,
}
var<task_payload> task: Task;

struct QuadIndices {
    @builtin(triangle_indices) indices: vec3<u32>,
}

struct MeshOutput {
    @builtin(vertices) vertices: array<QuadVertex, 256>,
    @builtin(primitives) primitives: array<QuadIndices, 128>,
    @builtin(vertex_count) vertex_count: u32,
    @builtin(primitive_count) primitive_count: u32,
}
var<workgroup> mesh_out: MeshOutput;

@task
@payload(task)
@workgroup_size(1)
fn ts_main(@builtin(workgroup_id) wg: vec3<u32>) -> @builtin(mesh_task_size) vec3<u32> {
    let b = wg.x;
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    // Only the drawn groom's bundles have this frame's records (lipp.lod_scan).
    let range = bundle_range(count);
    if b < range.x || b >= range.y {
        return vec3<u32>(0u, 1u, 1u);
    }
    let strands = bundle_lod[b * LOD_WORDS];
    let c = clamp(bundle_lod[b * LOD_WORDS + 1u], 2u, MAX_CONTROL_POINTS);
    task.first_strand = bundle_lod[b * LOD_WORDS + 2u];
    task.chunks = (c - 1u + MESH_SEGMENTS - 1u) / MESH_SEGMENTS;
    return vec3<u32>(strands * task.chunks, 1u, 1u);
}

@mesh(mesh_out)
@payload(task)
@workgroup_size(32)
fn ms_main(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let chunks = max(task.chunks, 1u);
    let chunk = wg.x % chunks;
    let s = task.first_strand + wg.x / chunks;
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let st = load_strand(count, s, params.styling != 0u);
    let l = lanes_of(lane, sg_lane, sg_size, params.cooperative_assembly != 0u);
    pass_one(st, l);
    workgroupBarrier();
    let strip = pass_two(st, l);
    // This chunk's segments; none past the strands lipp.lod counted.
    let lo = chunk * MESH_SEGMENTS;
    let hi = select(lo, min(lo + MESH_SEGMENTS, st.c - 1u), s < raster_args[3] && lo < st.c - 1u);
    let n = hi - lo;
    mesh_out.vertex_count = 4u * n;
    mesh_out.primitive_count = 2u * n;
    let size = vec2<f32>(f32(params.width), f32(params.height));
    // A lane's strip starts at control point lane * ceil((C - 1) / 32).
    let first = lane * ((st.c - 1u + RASTER_GROUP - 1u) / RASTER_GROUP);
    for (var m = 0u; m < strip_segments(strip); m++) {
        let g = first + m;
        if g < lo || g >= hi {
            continue;
        }
        let a = strip_point(strip, m);
        let b = strip_point(strip, m + 1u);
        let ca = transform(frame.view_proj, vec4<f32>(a.pos, 1.0));
        let cb = transform(frame.view_proj, vec4<f32>(b.pos, 1.0));
        let bits = segment_bits(a, strip_tangent(strip, m), b, strip_tangent(strip, m + 1u), st.uv);
        let v = 4u * (g - lo);
        for (var corner = 0u; corner < 4u; corner++) {
            let c = quad_corner_clipped(ca, cb, corner, params.width_px, size, frame.near);
            mesh_out.vertices[v + corner] = QuadVertex(c.position, c.t, bits.x, bits.y);
        }
        // hw_strands::CORNERS as indices: (a-, b-, a+) and (a+, b-, b+).
        let p = 2u * (g - lo);
        mesh_out.primitives[p].indices = vec3<u32>(v, v + 1u, v + 2u);
        mesh_out.primitives[p + 1u].indices = vec3<u32>(v + 2u, v + 1u, v + 3u);
    }
}

@fragment
@early_depth_test(force)
fn fs_main(v: QuadVertex, @builtin(sample_index) sample: u32) {
    write_sample(v.position, v.t, v.bits_a, v.bits_b, sample, params.width, params.height, params.model_index);
}
