// lipp.reference_strands: the ground truth's strands from the hair mesh. One
// workgroup per kept strand assembles it exactly as lipp.raster does (Lipp
// Code 1, assembly.wgsl), then writes every control point for
// lipp.reference_shade and every segment's ribbon (of the groom's thickness,
// not snapped) with +1 in each 8x8 tile it may reach, as reference.count
// does for a groom. Port of passes/src/lipp/reference/strands.rs.

#define REFERENCE_COUNTS_BINDING 7
#define REFERENCE_RIBBONS_BINDING 8
#import strandgraph::layout::{FrameData, ModelData}
#import strandgraph::clip::transform
#import strandgraph::lipp::{quantize, LOD_WORDS, BUNDLE_WORDS, MAX_CONTROL_POINTS}
#import strandgraph::lipp_assembly::{raster_args, bundle_lod, hairmesh_bundles, ControlPoint, Strand, Strip, load_strand, lanes_of, pass_one, pass_two, strip_point, strip_tangent, strip_segments}
#import strandgraph::reference::ribbon_of
#import strandgraph::reference_bins::store_ribbon

// StrandsGpu in passes/src/lipp/reference/strands.rs.
struct StrandsParams {
    bundles: u32,
    width: u32,
    height: u32,
    tiles_x: u32,
    styling: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: StrandsParams;
@group(0) @binding(1) var<storage, read> frame: FrameData;
// Bindings 2-5 (raster_args, bundle_lod, hairmesh.bundles, hairmesh.layers)
// are declared in assembly.wgsl.
@group(0) @binding(6) var<storage, read> models: array<ModelData>;
// Bindings 7 (reference_counts) and 8 (reference_ribbons) are bins.wgsl's.
@group(0) @binding(9) var<storage, read_write> reference_points: array<vec4<u32>>;

// strands::{MODEL_SHIFT, VALID}: the point record's model index above
// (u, v), and the bit that marks a written point (the buffer is cleared).
const MODEL_SHIFT: u32 = 12u;
const VALID: u32 = 0x80000000u;

// strands::Meta: the strand's model, its (u, v) in 1/63 steps, and its
// thickness (the model's).
struct Meta {
    packed: u32,
    thickness: f32,
}

fn strand_meta(st: Strand) -> Meta {
    let model = min(hairmesh_bundles[st.bundle_index * BUNDLE_WORDS + 3u], arrayLength(&models) - 1u);
    let packed = quantize(st.uv.x, 63.0) | (quantize(st.uv.y, 63.0) << 6u) | (model << MODEL_SHIFT) | VALID;
    return Meta(packed, models[model].thickness);
}

// strands::store_point: 8 words (position, AO, tangent, packed).
fn store_point(slot: u32, p: ControlPoint, t: vec3<f32>, packed: u32) {
    reference_points[2u * slot] = bitcast<vec4<u32>>(vec4<f32>(p.pos, p.ao));
    reference_points[2u * slot + 1u] = vec4<u32>(bitcast<vec3<u32>>(t), packed);
}

fn clip_of(p: ControlPoint) -> vec4<f32> {
    return transform(frame.view_proj, vec4<f32>(p.pos, 1.0));
}

// strands::segment: the ribbon of segment m (of c - 1) between slots
// `slot` and `slot + 1`, stored and counted in its tiles.
fn store_segment(slot: u32, a: ControlPoint, b: ControlPoint, m: u32, c: u32, thickness: f32) {
    let r = ribbon_of(
        clip_of(a), clip_of(b), thickness, thickness,
        m > 0u, m + 2u < c, slot, slot + 1u,
        frame.near, frame.screen.xy, frame.pixels_per_unit,
    );
    store_ribbon(slot, r, params.width, params.height, params.tiles_x);
}

@compute @workgroup_size(32)
fn reference_strands(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let total = raster_args[3];
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(lane, sg_lane, sg_size, true);
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        let m = strand_meta(st);
        // assembly::pass_two: this lane's points start at lane * S.
        let first = lane * ((st.c - 1u + 31u) / 32u);
        let base = s * MAX_CONTROL_POINTS + first;
        for (var k = 0u; k < strip.have; k++) {
            store_point(base + k, strip_point(strip, k), strip_tangent(strip, k), m.packed);
        }
        for (var k = 0u; k < strip_segments(strip); k++) {
            store_segment(base + k, strip_point(strip, k), strip_point(strip, k + 1u), first + k, st.c, m.thickness);
        }
        // smLayer is rewritten by the next strand.
        workgroupBarrier();
    }
}
