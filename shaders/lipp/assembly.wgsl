// Lipp's strand assembly (§3.1, Appendix B Code 1), shared by lipp.raster
// (raster.wgsl) and the deep opacity maps (dom_maps.wgsl): bundles and their
// layers, control points evaluated with styling, one 32-lane workgroup per
// strand with cooperative assembly by subgroup shuffles. Port of
// passes/src/lipp/strand.rs. A neighbour held by a lane of another subgroup
// (subgroups narrower than 32, e.g. lavapipe's 8) or by a lane whose shuffle
// partner is not its index neighbour is evaluated instead of shuffled; the
// bits are the same, so the result does not depend on the subgroup width.
// Composed with naga_oil:
//   #import strandgraph::lipp_assembly::{load_strand, pass_one, pass_two, ...}
// Every importer binds raster_args, bundle_lod, hairmesh.bundles and
// hairmesh.layers at 2-5 (their definitions list them second to fifth, after
// frame; passes/tests/wgsl_bindings.rs checks it).
#define_import_path strandgraph::lipp_assembly

#import strandgraph::hash::pcg
#import strandgraph::lipp::{LightFrame, light_frame_of, light_project, unit, safe_normalize, lerp_vec, bilinear, calc_tangent, strand_uv, strand_id, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, RASTER_GROUP, MAX_CONTROL_POINTS, SNAP, TAU, PI, ARGS_BUNDLES_LO, ARGS_BUNDLES_HI}

@group(0) @binding(2) var<storage, read> raster_args: array<u32>;
@group(0) @binding(3) var<storage, read> bundle_lod: array<u32>;
@group(0) @binding(4) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(5) var<storage, read> hairmesh_layers: array<vec4<f32>>;

// Lipp Code 1's smLayer: the base layers with finite-difference tangents.
var<workgroup> sm_pos: array<vec3<f32>, 16>;
var<workgroup> sm_tangent: array<vec3<f32>, 16>;
var<workgroup> sm_axis: array<vec3<f32>, 16>;
var<workgroup> sm_ao: array<f32, 16>;

// Points per lane: (MAX_CONTROL_POINTS - 1) / 32.
const MAX_STRIP: u32 = 4u;

struct Bundle {
    first_layer: u32,
    layers: u32,
    seed: u32,
    curl_radius: f32,
    curl_turns: f32,
    twist: f32,
    noise: f32,
}

fn load_bundle(b: u32) -> Bundle {
    let o = b * BUNDLE_WORDS;
    return Bundle(
        hairmesh_bundles[o],
        clamp(hairmesh_bundles[o + 1u], 2u, MAX_LAYERS),
        hairmesh_bundles[o + 8u],
        bitcast<f32>(hairmesh_bundles[o + 4u]),
        bitcast<f32>(hairmesh_bundles[o + 5u]),
        bitcast<f32>(hairmesh_bundles[o + 6u]),
        bitcast<f32>(hairmesh_bundles[o + 7u]),
    );
}

struct LayerPoint {
    pos: vec3<f32>,
    axis: vec3<f32>,
    ao: f32,
}

// strand::layer_point.
fn layer_point(b: Bundle, i: u32, uv: vec2<f32>) -> LayerPoint {
    let base = (b.first_layer + i) * LAYER_VEC4S;
    let k0 = hairmesh_layers[base];
    let k1 = hairmesh_layers[base + 2u];
    let k2 = hairmesh_layers[base + 4u];
    let k3 = hairmesh_layers[base + 6u];
    let w = hairmesh_layers[base + 1u].w;
    let angle = b.twist * TAU * w;
    let s = sin(angle);
    let co = cos(angle);
    let x = uv.x - 0.5;
    let y = uv.y - 0.5;
    let u = x * co - y * s + 0.5;
    let v = x * s + y * co + 0.5;
    let pos = bilinear(k0.xyz, k1.xyz, k2.xyz, k3.xyz, u, v);
    let axis = ((k1.xyz - k0.xyz) + (k2.xyz - k3.xyz)) * 0.5;
    let ao_b = k0.w + (k1.w - k0.w) * u;
    let ao_t = k3.w + (k2.w - k3.w) * u;
    return LayerPoint(pos, axis, ao_b + (ao_t - ao_b) * v);
}

struct ControlPoint {
    pos: vec3<f32>,
    w: f32,
    ao: f32,
}

// strand::eval_cp over the layers in workgroup memory.
fn eval_cp(b: Bundle, id: vec3<f32>, k: u32, c: u32, styling: bool) -> ControlPoint {
    let n = b.layers;
    let w = f32(k) / f32(c - 1u);
    let f = w * f32(n - 1u);
    let i = min(u32(floor(f)), n - 2u);
    let t = f - f32(i);
    let p0 = sm_pos[i];
    let p1 = sm_pos[i + 1u];
    let t0 = sm_tangent[i];
    let t1 = sm_tangent[i + 1u];
    let d = p1 - p0;
    let len = sqrt(dot(d, d));
    let t2 = t * t;
    let t3 = t * t * t;
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + t;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    var pos = (p0 * h00 + t0 * (h10 * len)) + (p1 * h01 + t1 * (h11 * len));
    let ao = sm_ao[i] + (sm_ao[i + 1u] - sm_ao[i]) * t;
    if styling {
        let dir = safe_normalize(lerp_vec(t0, t1, t));
        let axis = lerp_vec(sm_axis[i], sm_axis[i + 1u], t);
        let b1 = safe_normalize(axis - dir * dot(axis, dir));
        let b2 = cross(dir, b1);
        let ramp = min(w * 8.0, 1.0);
        var off = vec3<f32>(0.0);
        if b.curl_radius > 0.0 {
            let a = TAU * (b.curl_turns * w + id.x);
            off = off + (b1 * cos(a) + b2 * sin(a)) * b.curl_radius;
        }
        if b.noise > 0.0 {
            let amp = b.noise * sin(PI * w * (1.0 + 2.0 * id.y));
            off = off + (id * 2.0 - vec3<f32>(1.0)) * amp;
        }
        pos = pos + off * ramp;
    }
    return ControlPoint(pos, w, ao);
}

// Snapped to the sub-pixel grid every backend uses (lipp::raster::SNAP).
fn snap(v: f32) -> f32 {
    return floor(v * SNAP + 0.5) / SNAP;
}
// lipp::bundle_range: the scanned groom's bundles [lo, hi), at most count.
fn bundle_range(count: u32) -> vec2<u32> {
    if arrayLength(&raster_args) <= ARGS_BUNDLES_HI {
        return vec2<u32>(0u, count);
    }
    let hi = min(raster_args[ARGS_BUNDLES_HI], count);
    return vec2<u32>(min(raster_args[ARGS_BUNDLES_LO], hi), hi);
}

// The last bundle whose first strand is at most s among `bundles`
// (lipp::bundle_of_strand).
fn bundle_of_strand(bundles: vec2<u32>, s: u32) -> u32 {
    var lo = bundles.x;
    var hi = bundles.y;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if bundle_lod[mid * LOD_WORDS + 2u] <= s {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return max(max(lo, 1u) - 1u, bundles.x);
}

// One strand's assembly state (Code 1), shared by the raster and the DOM entries.
struct Strand {
    bundle: Bundle,
    id: vec3<f32>,
    uv: vec2<f32>,
    k: u32,
    c: u32,
    // N / N_LOD of the strand's bundle (the DOM's density compensation).
    thinning: f32,
    styling: bool,
    // The strand's bundle (its record in bundle_lod and hairmesh.bundles).
    bundle_index: u32,
}

fn load_strand(count: u32, s: u32, styling: bool) -> Strand {
    let bi = bundle_of_strand(bundle_range(count), s);
    let drawn = max(bundle_lod[bi * LOD_WORDS], 1u);
    let c = clamp(bundle_lod[bi * LOD_WORDS + 1u], 2u, MAX_CONTROL_POINTS);
    let k = s - bundle_lod[bi * LOD_WORDS + 2u];
    let full = hairmesh_bundles[bi * BUNDLE_WORDS + 2u];
    return strand_at(bi, k, c, f32(full) / f32(drawn), styling);
}

// Strand k of bundle bi at C points, from its bundle's record. lipp.raster
// calls it again each round of pass_two_round, so that a round keeps
// nothing of the last one; it passes thinning 1.0, which only the DOM's
// density compensation reads.
fn strand_at(bi: u32, k: u32, c: u32, thinning: f32, styling: bool) -> Strand {
    let b = load_bundle(bi);
    return Strand(b, strand_id(b.seed, k), strand_uv(k), k, c, thinning, styling, bi);
}

// Whether this lane's shuffle partners are its index neighbours.
struct Lanes {
    lane: u32,
    has_up: bool,
    has_down: bool,
}

fn lanes_of(lane: u32, sg_lane: u32, sg_size: u32, coop: bool) -> Lanes {
    let up_lane = subgroupShuffleUp(lane, 1u);
    let down_lane = subgroupShuffleDown(lane, 1u);
    return Lanes(
        lane,
        coop && sg_lane > 0u && up_lane + 1u == lane,
        coop && sg_lane + 1u < sg_size && down_lane == lane + 1u && lane + 1u < RASTER_GROUP,
    );
}

// Pass 1 (Code 1 lines 14-28): one layer per lane into smLayer. The caller
// puts a workgroupBarrier after it.
fn pass_one(st: Strand, l: Lanes) {
    let b = st.bundle;
    let n = b.layers;
    let lane = l.lane;
    var mine = LayerPoint(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    if lane < n {
        mine = layer_point(b, lane, st.uv);
    }
    let up_pos = subgroupShuffleUp(mine.pos, 1u);
    let down_pos = subgroupShuffleDown(mine.pos, 1u);
    if lane < n {
        var prev = mine.pos;
        if lane > 0u {
            prev = select(layer_point(b, lane - 1u, st.uv).pos, up_pos, l.has_up);
        }
        var next = mine.pos;
        if lane + 1u < n {
            next = select(layer_point(b, lane + 1u, st.uv).pos, down_pos, l.has_down);
        }
        sm_pos[lane] = mine.pos;
        sm_tangent[lane] = calc_tangent(lane, n, prev, mine.pos, next);
        sm_axis[lane] = mine.axis;
        sm_ao[lane] = mine.ao;
    }
}

// A lane's strip of control points with final tangents, and the next lane's
// first point and tangent (Code 1 lines 30-50). The points are fields, not
// an array, and are read with constant indices only (`pick_*`): a
// dynamically indexed array lives in local memory, which on the H100 put
// 384 bytes per lane there (VK_KHR_pipeline_executable_properties).
struct Strip {
    point_a: ControlPoint,
    point_b: ControlPoint,
    point_c: ControlPoint,
    point_d: ControlPoint,
    tangent_a: vec3<f32>,
    tangent_b: vec3<f32>,
    tangent_c: vec3<f32>,
    tangent_d: vec3<f32>,
    have: u32,
    next: ControlPoint,
    next_tangent: vec3<f32>,
    has_next: bool,
}

// Point k (< 4) of p0..p3.
fn pick_cp(p0: ControlPoint, p1: ControlPoint, p2: ControlPoint, p3: ControlPoint, k: u32) -> ControlPoint {
    switch k {
        case 0u: {
            return p0;
        }
        case 1u: {
            return p1;
        }
        case 2u: {
            return p2;
        }
        default: {
            return p3;
        }
    }
}

fn pick_vec(t0: vec3<f32>, t1: vec3<f32>, t2: vec3<f32>, t3: vec3<f32>, k: u32) -> vec3<f32> {
    switch k {
        case 0u: {
            return t0;
        }
        case 1u: {
            return t1;
        }
        case 2u: {
            return t2;
        }
        default: {
            return t3;
        }
    }
}

// The tangent at the lane's point m (< have), from its neighbours: the
// point before the strip (`before`), the strip's points, the point after it
// (`after`).
fn strip_tangent_at(first: u32, c: u32, m: u32, have: u32, p0: ControlPoint, p1: ControlPoint, p2: ControlPoint, p3: ControlPoint, before: vec3<f32>, after: vec3<f32>) -> vec3<f32> {
    let here = pick_cp(p0, p1, p2, p3, m).pos;
    var p = before;
    if m > 0u {
        p = pick_cp(p0, p1, p2, p3, m - 1u).pos;
    }
    var q = after;
    if m + 1u < have {
        q = pick_cp(p0, p1, p2, p3, m + 1u).pos;
    }
    return calc_tangent(first + m, c, p, here, q);
}

fn pass_two(st: Strand, l: Lanes) -> Strip {
    return pass_two_round(st, l, 0u, 4u);
}

// strand::strip_len: S = ceil((C - 1) / 32) points a lane (Code 1), at most
// `max_strip`.
fn strip_len(c: u32, max_strip: u32) -> u32 {
    return min((c - 1u + RASTER_GROUP - 1u) / RASTER_GROUP, max_strip);
}

// The points of lane slot `slot` (round * 32 + lane) in strips of
// strip_len(c, max_strip): (first, have), have 0 past the strand's end.
fn strip_span(c: u32, slot: u32, max_strip: u32) -> vec2<u32> {
    let len = strip_len(c, max_strip);
    let first = slot * len;
    return vec2<u32>(first, min(select(0u, c - first, first < c), len));
}

// strand::strip_rounds: the rounds of strips of strip_len(c, max_strip)
// points that cover C points (1 when max_strip is 4: every C <= 129).
fn strip_rounds(c: u32, max_strip: u32) -> u32 {
    let span = RASTER_GROUP * strip_len(c, max_strip);
    return (c - 1u + span - 1u) / span;
}

// pass_two for round `round` of strips of at most `max_strip` (a constant
// of each caller: 1, 2 or 4) points: lane l's points start at
// (round * 32 + l) * S. A smaller max_strip keeps fewer points live in
// registers (lipp.raster's strip_rounds); the first lane of a round
// evaluates its predecessor and the last its successor itself, as a lane
// without a shuffle partner does.
fn pass_two_round(st: Strand, l: Lanes, round: u32, max_strip: u32) -> Strip {
    let b = st.bundle;
    let id = st.id;
    let c = st.c;
    let span = strip_span(c, round * RASTER_GROUP + l.lane, max_strip);
    let first = span.x;
    let have = span.y;
    let none = ControlPoint(vec3<f32>(0.0), 0.0, 0.0);
    var p0 = none;
    var p1 = none;
    var p2 = none;
    var p3 = none;
    if have > 0u {
        p0 = eval_cp(b, id, first, c, st.styling);
    }
    // `max_strip > k` is a constant: the slots past it stay `none`, and
    // hold no registers.
    if max_strip > 1u && have > 1u {
        p1 = eval_cp(b, id, first + 1u, c, st.styling);
    }
    if max_strip > 2u && have > 2u {
        p2 = eval_cp(b, id, first + 2u, c, st.styling);
    }
    if max_strip > 3u && have > 3u {
        p3 = eval_cp(b, id, first + 3u, c, st.styling);
    }
    let first_cp = p0;
    let last_cp = pick_cp(p0, p1, p2, p3, max(have, 1u) - 1u);
    let up_cp_pos = subgroupShuffleUp(last_cp.pos, 1u);
    let up_cp_w = subgroupShuffleUp(last_cp.w, 1u);
    let up_cp_ao = subgroupShuffleUp(last_cp.ao, 1u);
    let down_cp_pos = subgroupShuffleDown(first_cp.pos, 1u);
    let down_cp_w = subgroupShuffleDown(first_cp.w, 1u);
    let down_cp_ao = subgroupShuffleDown(first_cp.ao, 1u);
    let end = first + have;
    var prev = first_cp;
    if have > 0u && first > 0u {
        if l.has_up {
            prev = ControlPoint(up_cp_pos, up_cp_w, up_cp_ao);
        } else {
            prev = eval_cp(b, id, first - 1u, c, st.styling);
        }
    }
    let has_next = have > 0u && end < c;
    var next = last_cp;
    if has_next {
        if l.has_down {
            next = ControlPoint(down_cp_pos, down_cp_w, down_cp_ao);
        } else {
            next = eval_cp(b, id, end, c, st.styling);
        }
    }
    // The first point's predecessor is itself at the root, the last one's
    // successor itself at the tip.
    let before = select(p0.pos, prev.pos, first > 0u);
    let after = select(last_cp.pos, next.pos, has_next);
    var t0 = vec3<f32>(0.0);
    var t1 = vec3<f32>(0.0);
    var t2 = vec3<f32>(0.0);
    var t3 = vec3<f32>(0.0);
    if have > 0u {
        t0 = strip_tangent_at(first, c, 0u, have, p0, p1, p2, p3, before, after);
    }
    if max_strip > 1u && have > 1u {
        t1 = strip_tangent_at(first, c, 1u, have, p0, p1, p2, p3, before, after);
    }
    if max_strip > 2u && have > 2u {
        t2 = strip_tangent_at(first, c, 2u, have, p0, p1, p2, p3, before, after);
    }
    if max_strip > 3u && have > 3u {
        t3 = strip_tangent_at(first, c, 3u, have, p0, p1, p2, p3, before, after);
    }
    // The next lane's first tangent (Code 1 line 46).
    let down_t = subgroupShuffleDown(t0, 1u);
    var tn = vec3<f32>(0.0);
    if has_next {
        if l.has_down {
            tn = down_t;
        } else {
            var after_next = next.pos;
            if end + 1u < c {
                after_next = eval_cp(b, id, end + 1u, c, st.styling).pos;
            }
            tn = calc_tangent(end, c, last_cp.pos, next.pos, after_next);
        }
    }
    return Strip(p0, p1, p2, p3, t0, t1, t2, t3, have, next, tn, has_next);
}

// Point k (<= have) of the strip: its own, then the next lane's first.
fn strip_point(st: Strip, k: u32) -> ControlPoint {
    if k < st.have {
        return pick_cp(st.point_a, st.point_b, st.point_c, st.point_d, k);
    }
    return st.next;
}

fn strip_tangent(st: Strip, k: u32) -> vec3<f32> {
    if k < st.have {
        return pick_vec(st.tangent_a, st.tangent_b, st.tangent_c, st.tangent_d, k);
    }
    return st.next_tangent;
}

// Segment m of a strip runs from point m to point m + 1.
fn strip_segments(st: Strip) -> u32 {
    return select(max(st.have, 1u) - 1u, st.have, st.has_next);
}

// The DDA column walk of a segment (lipp::walk), shared by the raster and
// the deep opacity maps.
// walk::Dda: the segment's parameter range (t0, t1) inside column `col` of
// its major axis, from the major coordinate `ma` at t = 0 and its change
// `dm` (all of it when the segment does not move along the axis).
fn column_params(ma: f32, dm: f32, col: f32) -> vec2<f32> {
    if dm == 0.0 {
        return vec2<f32>(0.0, 1.0);
    }
    let ta = clamp((col - ma) / dm, 0.0, 1.0);
    let tb = clamp((col + 1.0 - ma) / dm, 0.0, 1.0);
    return vec2<f32>(min(ta, tb), max(ta, tb));
}

// One column of dom::walk: (first row, last row, depth), for column `col`.
fn walk_column(a: vec3<f32>, b: vec3<f32>, x_major: bool, col: f32) -> vec3<f32> {
    let ma = select(a.y, a.x, x_major);
    let na = select(a.x, a.y, x_major);
    let mb = select(b.y, b.x, x_major);
    let nb = select(b.x, b.y, x_major);
    let dm = mb - ma;
    let dn = nb - na;
    let t = column_params(ma, dm, col);
    let t0 = t.x;
    let t1 = t.y;
    let n0 = na + dn * t0;
    let n1 = na + dn * t1;
    let tm = 0.5 * (t0 + t1);
    return vec3<f32>(floor(min(n0, n1)), floor(max(n0, n1)), a.z + (b.z - a.z) * tm);
}

// The columns dom::walk visits: (first, last, x_major as 0/1).
fn walk_columns(a: vec3<f32>, b: vec3<f32>, res: u32) -> vec3<f32> {
    let x_major = abs(b.x - a.x) >= abs(b.y - a.y);
    let ma = select(a.y, a.x, x_major);
    let mb = select(b.y, b.x, x_major);
    let limit = f32(res);
    return vec3<f32>(floor(max(min(ma, mb), 0.0)), floor(min(max(ma, mb), limit - 1.0)), select(0.0, 1.0, x_major));
}
