// The deep opacity maps lipp.dom_depth and lipp.dom_opacity (entries
// `dom_depth_pass`, `dom_opacity_pass`; Lipp §3.4, Yuksel and Keyser 2008):
// each strand assembled as the raster assembles it (assembly.wgsl), its
// segments walked through every light's map. Port of passes/src/lipp/dom.rs.

// Bindings 1 (frame), 6 (models) and 7 (lights) are declared in dom.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 6
#define LIGHTS_BINDING 7
#import strandgraph::lipp_dom::{frame, models, lights, light_frame, NO_HIT, OPACITY_SCALE}
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::lipp::{LightFrame, light_frame_of, light_project, unit, safe_normalize, lerp_vec, calc_tangent, strand_uv, strand_id, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, RASTER_GROUP, MAX_CONTROL_POINTS, SNAP, TAU, PI}
#import strandgraph::lipp_assembly::{raster_args, bundle_lod, hairmesh_bundles, hairmesh_layers, ControlPoint, Strand, Strip, load_strand, lanes_of, pass_one, pass_two, strip_span, strip_point, strip_tangent, strip_segments, snap, walk_column, walk_columns}

// Bindings 0 and 8.. are the DOM entries' own.

struct DomParams {
    resolution: u32,
    layers: u32,
    layer_thickness: f32,
    strand_opacity: f32,
    density_compensation: u32,
    cooperative_assembly: u32,
    styling: u32,
    bundles: u32,
    shared_points: u32,
    test_first: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> dom_params: DomParams;
@group(0) @binding(8) var<storage, read_write> dom_depth: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read> dom_opacity_pass_dom_depth: array<u32>;
@group(0) @binding(9) var<storage, read_write> dom_points: array<u32>;
@group(0) @binding(9) var<storage, read> dom_opacity_pass_dom_points: array<u32>;
@group(0) @binding(10) var<storage, read_write> dom_layers: array<atomic<u32>>;

// dom::MAX_DOM_LIGHTS.
const MAX_DOM_LIGHTS: u32 = 4u;

// Number of lights the maps have room for (dom::light_frames).
fn dom_light_count(res: u32, map_words: u32) -> u32 {
    return min(min(frame.light_count, MAX_DOM_LIGHTS), min(arrayLength(&lights), map_words / max(res * res, 1u)));
}



// Light-space segment ends: texel coordinates snapped, normalised depth.
fn dom_end(lf: LightFrame, p: vec3<f32>, res: u32) -> vec3<f32> {
    let q = light_project(lf, p);
    let r = f32(res);
    return vec3<f32>(snap(q.x * r), snap(q.y * r), q.z);
}

// Ours, after Lipp §5 ("strand assembly is performed only once, while
// projection is executed per view"; dom::shared_points): dom_depth keeps
// the world-space control points it assembles in dom_points, and
// dom_opacity walks them instead of assembling each strand again. Word 0
// holds the points of room a strand had this frame (0: none kept); point k
// of strand s is at words POINTS_HEADER + (s * room + k) * 3. A strand of
// more points than the room is assembled by both passes.
const POINTS_HEADER: u32 = 4u;

// dom::points_room: the room per strand `words` of dom_points give `total`
// strands.
fn points_room(words: u32, total: u32) -> u32 {
    if words <= POINTS_HEADER || total == 0u {
        return 0u;
    }
    return min((words - POINTS_HEADER) / 3u / total, MAX_CONTROL_POINTS);
}

fn keep_point(i: u32, p: vec3<f32>) {
    let w = POINTS_HEADER + i * 3u;
    dom_points[w] = bitcast<u32>(p.x);
    dom_points[w + 1u] = bitcast<u32>(p.y);
    dom_points[w + 2u] = bitcast<u32>(p.z);
}

// The lane's strip points (pass_two's first..first + have) into strand
// slot `base` (s * room). When C - 1 is a multiple of the 32 lanes' strips
// (C = 33, 65, 129), the last point is no lane's own but the last lane's
// `next`, and that lane keeps it.
fn keep_points(strip: Strip, base: u32, lane: u32, c: u32) {
    let first = strip_span(c, lane, 4u).x;
    for (var m = 0u; m < strip.have; m++) {
        keep_point(base + first + m, strip_point(strip, m).pos);
    }
    if lane + 1u == RASTER_GROUP && strip.has_next {
        keep_point(base + first + strip.have, strip.next.pos);
    }
}

// Point i of the kept strands where `ok`, else nothing.
fn kept_point(i: u32, ok: bool) -> ControlPoint {
    if !ok {
        return ControlPoint(vec3<f32>(0.0), 0.0, 0.0);
    }
    let w = POINTS_HEADER + i * 3u;
    let p = vec3<f32>(
        bitcast<f32>(dom_opacity_pass_dom_points[w]),
        bitcast<f32>(dom_opacity_pass_dom_points[w + 1u]),
        bitcast<f32>(dom_opacity_pass_dom_points[w + 2u]),
    );
    return ControlPoint(p, 0.0, 0.0);
}

// pass_two's strip for the lane, from the points dom_depth kept: the same
// points, so the same walk. Only positions: the maps read nothing else.
fn kept_strip(base: u32, lane: u32, c: u32) -> Strip {
    let span = strip_span(c, lane, 4u);
    let at = base + span.x;
    let have = span.y;
    let has_next = have > 0u && span.x + have < c;
    let t = vec3<f32>(0.0);
    return Strip(
        kept_point(at, have > 0u),
        kept_point(at + 1u, have > 1u),
        kept_point(at + 2u, have > 2u),
        kept_point(at + 3u, have > 3u),
        t, t, t, t,
        have,
        kept_point(at + have, has_next),
        t,
        has_next,
    );
}

fn dom_amount(st: Strand) -> u32 {
    var thinning = 1.0;
    if dom_params.density_compensation != 0u {
        thinning = st.thinning;
    }
    return u32(floor(dom_params.strand_opacity * thinning * OPACITY_SCALE + 0.5));
}

// Ours: a strand of at most MAX_SHARED segments, one a lane and the rest
// of the 32 lanes idle, deals each segment's columns out to several lanes.
// A far view's camera-bound shadow LOD keeps few control points, whose
// segments cross tens of texels of the map, and a lane walking each alone
// set the passes' time. The same texels are written, and their atomics
// commute, so the maps are the same; the CPU kernel walks each segment
// whole.
const MAX_SHARED: u32 = 16u;
var<workgroup> shared_a: array<vec3<f32>, RASTER_GROUP>;
var<workgroup> shared_b: array<vec3<f32>, RASTER_GROUP>;

// A lane's part of the walk: the segment from a to b, its columns from the
// `first`th on, every `step`th.
struct Share {
    a: vec3<f32>,
    b: vec3<f32>,
    first: u32,
    step: u32,
}

// Whether strand `st` deals its segments out: at most MAX_SHARED of them,
// so one a lane (pass_two). The same for the whole workgroup.
fn shares(st: Strand) -> bool {
    return st.c >= 2u && st.c - 1u <= MAX_SHARED;
}

// With `shares`: lane j walks segment j % S, columns j / S, j / S + k, ...
// for k = 32 / S (S the segments); a lane past S * k walks nothing (step
// 0). Every lane calls it: it has a barrier.
fn share_segments(st: Strand, strip: Strip, lane: u32) -> Share {
    let share = shares(st);
    if share && lane + 1u < st.c {
        shared_a[lane] = strip_point(strip, 0u).pos;
        shared_b[lane] = strip_point(strip, 1u).pos;
    }
    workgroupBarrier();
    let segs = max(st.c, 2u) - 1u;
    let k = RASTER_GROUP / segs;
    if !share || lane >= segs * k {
        return Share(vec3<f32>(0.0), vec3<f32>(0.0), 0u, 0u);
    }
    return Share(shared_a[lane % segs], shared_b[lane % segs], lane / segs, k);
}

fn dom_segment_depth(a: vec3<f32>, b: vec3<f32>, l: u32, lf: LightFrame, first: u32, step: u32) {
    let res = dom_params.resolution;
    {
        let pa = dom_end(lf, a, res);
        let pb = dom_end(lf, b, res);
        let cols = walk_columns(pa, pb, res);
        let x_major = cols.z != 0.0;
        for (var col = cols.x + f32(first); col <= cols.y; col += f32(step)) {
            let span = walk_column(pa, pb, x_major, col);
            let z = span.z;
            if !(z >= 0.0 && z <= 1.0) {
                continue;
            }
            for (var row = max(span.x, 0.0); row <= min(span.y, f32(res) - 1.0); row += 1.0) {
                let xy = select(vec2<f32>(row, col), vec2<f32>(col, row), x_major);
                let texel = l * res * res + u32(xy.y) * res + u32(xy.x);
                // test_first: a plain load first (see dom.rs), which skips
                // most atomics.
                let bits = bitcast<u32>(z);
                if dom_params.test_first == 0u || bits < atomicLoad(&dom_depth[texel]) {
                    atomicMin(&dom_depth[texel], bits);
                }
            }
        }
    }
}

fn dom_segment_opacity(a: vec3<f32>, b: vec3<f32>, amount: u32, l: u32, lf: LightFrame, first: u32, step: u32) {
    let res = dom_params.resolution;
    {
        let pa = dom_end(lf, a, res);
        let pb = dom_end(lf, b, res);
        let cols = walk_columns(pa, pb, res);
        let x_major = cols.z != 0.0;
        for (var col = cols.x + f32(first); col <= cols.y; col += f32(step)) {
            let span = walk_column(pa, pb, x_major, col);
            let z = span.z;
            if !(z >= 0.0 && z <= 1.0) {
                continue;
            }
            for (var row = max(span.x, 0.0); row <= min(span.y, f32(res) - 1.0); row += 1.0) {
                let xy = select(vec2<f32>(row, col), vec2<f32>(col, row), x_major);
                let texel = u32(xy.y) * res + u32(xy.x);
                let first = dom_opacity_pass_dom_depth[l * res * res + texel];
                if first == NO_HIT {
                    continue;
                }
                // Depth behind the first hit, in layers.
                let d = (z - bitcast<f32>(first)) * lf.depth_extent / dom_params.layer_thickness;
                let k = min(u32(max(floor(d), 0.0)), dom_params.layers - 1u);
                atomicAdd(&dom_layers[(l * dom_params.layers + k) * res * res + texel], amount);
            }
        }
    }
}

@compute @workgroup_size(32)
fn dom_depth_pass(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let total = raster_args[3];
    let count = min(dom_params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(lane, sg_lane, sg_size, dom_params.cooperative_assembly != 0u);
    let lights_n = dom_light_count(dom_params.resolution, arrayLength(&dom_depth));
    let room = select(0u, points_room(arrayLength(&dom_points), total), dom_params.shared_points != 0u);
    if wg.x == 0u && lane == 0u {
        dom_points[0] = room;
    }
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, dom_params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        if st.c <= room {
            keep_points(strip, s * room, lane, st.c);
        }
        let share = share_segments(st, strip, lane);
        // Each light's view once per strand, the strip's segments in it.
        for (var li = 0u; li < lights_n; li++) {
            let lf = light_frame(li);
            if shares(st) {
                if share.step > 0u {
                    dom_segment_depth(share.a, share.b, li, lf, share.first, share.step);
                }
                continue;
            }
            for (var m = 0u; m < strip_segments(strip); m++) {
                dom_segment_depth(strip_point(strip, m).pos, strip_point(strip, m + 1u).pos, li, lf, 0u, 1u);
            }
        }
        workgroupBarrier();
    }
}

@compute @workgroup_size(32)
fn dom_opacity_pass(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let total = raster_args[3];
    let count = min(dom_params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(lane, sg_lane, sg_size, dom_params.cooperative_assembly != 0u);
    let lights_n = dom_light_count(dom_params.resolution, arrayLength(&dom_opacity_pass_dom_depth));
    // dom_depth's room this frame, where this pass reads its points.
    let room = select(0u, dom_opacity_pass_dom_points[0], dom_params.shared_points != 0u);
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, dom_params.styling != 0u);
        var strip: Strip;
        if st.c <= room {
            strip = kept_strip(s * room, lane, st.c);
        } else {
            pass_one(st, l);
            workgroupBarrier();
            strip = pass_two(st, l);
        }
        let share = share_segments(st, strip, lane);
        let amount = dom_amount(st);
        for (var li = 0u; li < lights_n; li++) {
            let lf = light_frame(li);
            if shares(st) {
                if share.step > 0u {
                    dom_segment_opacity(share.a, share.b, amount, li, lf, share.first, share.step);
                }
                continue;
            }
            for (var m = 0u; m < strip_segments(strip); m++) {
                dom_segment_opacity(strip_point(strip, m).pos, strip_point(strip, m + 1u).pos, amount, li, lf, 0u, 1u);
            }
        }
        workgroupBarrier();
    }
}
