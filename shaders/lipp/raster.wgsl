// lipp.raster (entry `raster`) and the deep opacity maps lipp.dom_depth and
// lipp.dom_opacity (entries `dom_depth`, `dom_opacity`), which share the
// strand assembly: Lipp §3.1 and Appendix B Code 1. One 32-lane workgroup per
// strand (indirect; workgroups stride over strands beyond 65535): cooperative
// strand assembly with subgroup shuffles, DDA rasterization into the centre
// and conservative 64-bit G-buffer layers with atomicMin.
// Port of passes/src/lipp/{raster,strand}.rs. A neighbour held by a lane of
// another subgroup (subgroups narrower than 32, e.g. lavapipe's 8) or by a
// lane whose shuffle partner is not its index neighbour is evaluated instead
// of shuffled; the bits are the same, so the result does not depend on the
// subgroup width. Needs SHADER_INT64 and SHADER_INT64_ATOMIC_MIN_MAX.

// Bindings 1 (frame), 6 (models) and 7 (lights) are declared in dom.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 6
#define LIGHTS_BINDING 7
#import strandgraph::lipp_dom::{frame, models, lights, light_frame, NO_HIT, OPACITY_SCALE}
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::hash::pcg
#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::lipp::{LightFrame, light_frame_of, light_project, unit, safe_normalize, lerp_vec, calc_tangent, strand_uv, strand_id, pack_payload, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, RASTER_GROUP, MAX_CONTROL_POINTS, SNAP, TAU, PI}

// RasterParams (booleans as 0/1).
struct RasterParams {
    cooperative_assembly: u32,
    styling: u32,
    centre_diameter: f32,
    conservative_layer: u32,
    // Scene quantities.
    bundles: u32,
    width: u32,
    height: u32,
    // MSAA reference mode: 2, 4 or 8 sample layers (0 or 1: off).
    msaa: u32,
    // The groom drawn, in the per-model block; grooms after the first also
    // test hair_depth (Lipp §3.5).
    model_index: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: RasterParams;
@group(0) @binding(2) var<storage, read> raster_args: array<u32>;
@group(0) @binding(3) var<storage, read> bundle_lod: array<u32>;
@group(0) @binding(4) var<storage, read> hairmesh_bundles: array<u32>;
@group(0) @binding(5) var<storage, read> hairmesh_layers: array<vec4<f32>>;
@group(0) @binding(6) var scene_depth: texture_depth_2d;
// Earlier grooms' depth (f32 bits), written by their filter passes.
@group(0) @binding(7) var<storage, read> hair_depth: array<u32>;
@group(0) @binding(8) var<storage, read_write> gbuffer: array<atomic<u64>>;

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

fn bilinear(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, c3: vec3<f32>, u: f32, v: f32) -> vec3<f32> {
    let bottom = lerp_vec(c0, c1, u);
    let top = lerp_vec(c3, c2, u);
    return lerp_vec(bottom, top, v);
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

struct End {
    x: f32,
    y: f32,
    z: f32,
    tangent: vec3<f32>,
    w: f32,
    ao: f32,
    ok: bool,
}

fn snap(v: f32) -> f32 {
    return floor(v * SNAP + 0.5) / SNAP;
}

fn project(cp: ControlPoint, tangent: vec3<f32>) -> End {
    let c = transform(frame.view_proj, vec4<f32>(cp.pos, 1.0));
    if c.w <= frame.near {
        return End(0.0, 0.0, 0.0, tangent, cp.w, cp.ao, false);
    }
    let s = clip_to_screen(c, frame.screen.x, frame.screen.y);
    return End(snap(s.x), snap(s.y), s.z, tangent, cp.w, cp.ao, true);
}

// Target::write.
fn write_sample(a: End, b: End, t: f32, x: i32, y: i32, layer: u32, uv: vec2<f32>) {
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return;
    }
    let z = a.z + (b.z - a.z) * t;
    if !(z >= 0.0 && z < 1.0) || z >= textureLoad(scene_depth, vec2<i32>(x, y), 0) {
        return;
    }
    let pixel = u32(y) * params.width + u32(x);
    if params.model_index > 0u && z >= bitcast<f32>(hair_depth[pixel]) {
        return;
    }
    let p = pack_payload(
        z,
        safe_normalize(lerp_vec(a.tangent, b.tangent, t)),
        vec3<f32>(uv.x, uv.y, a.w + (b.w - a.w) * t),
        a.ao + (b.ao - a.ao) * t,
    );
    let slot = layer * params.width * params.height + pixel;
    atomicMin(&gbuffer[slot], (u64(p.y) << 32u) | u64(p.x));
}

fn pixel_of(x_major: bool, m: i32, n: i32) -> vec2<i32> {
    return select(vec2<i32>(n, m), vec2<i32>(m, n), x_major);
}

// Target::segment: a DDA over the major axis, one column at a time.
fn draw_segment(a: End, b: End, uv: vec2<f32>) {
    let x_major = abs(b.x - a.x) >= abs(b.y - a.y);
    let ma = select(a.y, a.x, x_major);
    let na = select(a.x, a.y, x_major);
    let mb = select(b.y, b.x, x_major);
    let nb = select(b.x, b.y, x_major);
    let dm = mb - ma;
    let dn = nb - na;
    let limit = f32(select(params.height, params.width, x_major));
    let lo = floor(max(min(ma, mb), 0.0));
    let hi = floor(min(max(ma, mb), limit - 1.0));
    if lo > hi && dm != 0.0 {
        return;
    }
    let half = params.centre_diameter * 0.5;
    let len = sqrt(dm * dm + dn * dn);
    let cosa = select(1.0, abs(dm) / len, len > 0.0);
    for (var col = lo; col <= hi; col += 1.0) {
        let ci = i32(col);
        var t0 = 0.0;
        var t1 = 1.0;
        if dm != 0.0 {
            let ta = clamp((col - ma) / dm, 0.0, 1.0);
            let tb = clamp((col + 1.0 - ma) / dm, 0.0, 1.0);
            t0 = min(ta, tb);
            t1 = max(ta, tb);
        }
        let centre = col + 0.5;
        if dm != 0.0 && centre >= min(ma, mb) && centre < max(ma, mb) {
            let t = (centre - ma) / dm;
            let n = na + dn * t;
            let r = i32(floor(n - 0.5));
            for (var row = r; row <= r + 1; row++) {
                if abs((n - (f32(row) + 0.5)) * cosa) <= half {
                    let p = pixel_of(x_major, ci, row);
                    write_sample(a, b, t, p.x, p.y, 0u, uv);
                }
            }
        }
        if params.conservative_layer != 0u {
            let n0 = na + dn * t0;
            let n1 = na + dn * t1;
            let r0 = i32(floor(min(n0, n1)));
            let r1 = i32(floor(max(n0, n1)));
            let tm = 0.5 * (t0 + t1);
            for (var row = r0; row <= r1; row++) {
                let p = pixel_of(x_major, ci, row);
                write_sample(a, b, tm, p.x, p.y, 1u, uv);
            }
        }
    }
}

// raster::sample_positions: Direct3D's standard sample positions.
fn sample_offset(n: u32, s: u32) -> vec2<f32> {
    var two = array<vec2<i32>, 2>(vec2<i32>(4, 4), vec2<i32>(-4, -4));
    var four = array<vec2<i32>, 4>(vec2<i32>(-2, -6), vec2<i32>(6, -2), vec2<i32>(-6, 2), vec2<i32>(2, 6));
    var eight = array<vec2<i32>, 8>(
        vec2<i32>(1, -3), vec2<i32>(-1, 3), vec2<i32>(5, 1), vec2<i32>(-3, -5),
        vec2<i32>(-5, 5), vec2<i32>(-7, -1), vec2<i32>(3, 7), vec2<i32>(7, -7),
    );
    var g = vec2<i32>(0, 0);
    if n == 2u {
        g = two[s];
    } else if n == 4u {
        g = four[s];
    } else if n == 8u {
        g = eight[s];
    }
    return vec2<f32>(f32(g.x) / 16.0, f32(g.y) / 16.0);
}

// Target::segment_msaa: every sample within centre_diameter / 2 of the
// segment, in every pixel the segment touches.
fn draw_segment_msaa(a: End, b: End, uv: vec2<f32>) {
    let n = params.msaa;
    let layers = min(n, arrayLength(&gbuffer) / max(params.width * params.height, 1u));
    let half = params.centre_diameter * 0.5;
    let dx = b.x - a.x;
    let dy = b.y - a.y;
    let len2 = dx * dx + dy * dy;
    let x_major = abs(dx) >= abs(dy);
    let ma = select(a.y, a.x, x_major);
    let mb = select(b.y, b.x, x_major);
    let limit = f32(select(params.height, params.width, x_major));
    let lo = floor(max(min(ma, mb), 0.0));
    let hi = floor(min(max(ma, mb), limit - 1.0));
    let pa = vec3<f32>(a.x, a.y, 0.0);
    let pb = vec3<f32>(b.x, b.y, 0.0);
    for (var col = lo; col <= hi; col += 1.0) {
        let span = walk_column(pa, pb, x_major, col);
        for (var row = i32(span.x); row <= i32(span.y); row++) {
            let p = pixel_of(x_major, i32(col), row);
            for (var s = 0u; s < layers; s++) {
                let o = sample_offset(n, s);
                let px = f32(p.x) + 0.5 + o.x;
                let py = f32(p.y) + 0.5 + o.y;
                var t = 0.0;
                if len2 > 0.0 {
                    t = clamp(((px - a.x) * dx + (py - a.y) * dy) / len2, 0.0, 1.0);
                }
                let ex = a.x + dx * t - px;
                let ey = a.y + dy * t - py;
                if ex * ex + ey * ey <= half * half {
                    write_sample(a, b, t, p.x, p.y, s, uv);
                }
            }
        }
    }
}

fn draw(a: ControlPoint, ta: vec3<f32>, b: ControlPoint, tb: vec3<f32>, uv: vec2<f32>) {
    let pa = project(a, ta);
    let pb = project(b, tb);
    if pa.ok && pb.ok {
        if params.msaa > 1u {
            draw_segment_msaa(pa, pb, uv);
        } else {
            draw_segment(pa, pb, uv);
        }
    }
}

// The last bundle whose first strand is at most s (lipp::bundle_of_strand).
fn bundle_of_strand(count: u32, s: u32) -> u32 {
    var lo = 0u;
    var hi = count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if bundle_lod[mid * LOD_WORDS + 2u] <= s {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return max(lo, 1u) - 1u;
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
}

fn load_strand(count: u32, s: u32, styling: bool) -> Strand {
    let bi = bundle_of_strand(count, s);
    let drawn = max(bundle_lod[bi * LOD_WORDS], 1u);
    let c = clamp(bundle_lod[bi * LOD_WORDS + 1u], 2u, MAX_CONTROL_POINTS);
    let b = load_bundle(bi);
    let k = s - bundle_lod[bi * LOD_WORDS + 2u];
    let full = hairmesh_bundles[bi * BUNDLE_WORDS + 2u];
    return Strand(b, strand_id(b.seed, k), strand_uv(k), k, c, f32(full) / f32(drawn), styling);
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
// first point and tangent (Code 1 lines 30-50).
struct Strip {
    cps: array<ControlPoint, 4>,
    tangents: array<vec3<f32>, 4>,
    have: u32,
    next: ControlPoint,
    next_tangent: vec3<f32>,
    has_next: bool,
}

fn pass_two(st: Strand, l: Lanes) -> Strip {
    let b = st.bundle;
    let id = st.id;
    let c = st.c;
    let strip = (c - 1u + RASTER_GROUP - 1u) / RASTER_GROUP;
    let first = l.lane * strip;
    let have = min(select(0u, c - first, first < c), strip);
    var cps: array<ControlPoint, 4>;
    for (var m = 0u; m < have; m++) {
        cps[m] = eval_cp(b, id, first + m, c, st.styling);
    }
    let first_cp = cps[0];
    let last_cp = cps[max(have, 1u) - 1u];
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
    var tangents: array<vec3<f32>, 4>;
    for (var m = 0u; m < have; m++) {
        var p = cps[m].pos;
        if m > 0u {
            p = cps[m - 1u].pos;
        } else if first > 0u {
            p = prev.pos;
        }
        var q = cps[m].pos;
        if m + 1u < have {
            q = cps[m + 1u].pos;
        } else if has_next {
            q = next.pos;
        }
        tangents[m] = calc_tangent(first + m, c, p, cps[m].pos, q);
    }
    // The next lane's first tangent (Code 1 line 46).
    let down_t = subgroupShuffleDown(tangents[0], 1u);
    var tn = vec3<f32>(0.0);
    if has_next {
        if l.has_down {
            tn = down_t;
        } else {
            var after = next.pos;
            if end + 1u < c {
                after = eval_cp(b, id, end + 1u, c, st.styling).pos;
            }
            tn = calc_tangent(end, c, cps[have - 1u].pos, next.pos, after);
        }
    }
    return Strip(cps, tangents, have, next, tn, has_next);
}

// Segment m of a strip: (a, ta, b, tb); valid for m + 1 < have, or the last with has_next.
fn strip_segment_end(st: Strip, m: u32) -> ControlPoint {
    if m + 1u < st.have {
        return st.cps[m + 1u];
    }
    return st.next;
}

fn strip_segment_tangent(st: Strip, m: u32) -> vec3<f32> {
    if m + 1u < st.have {
        return st.tangents[m + 1u];
    }
    return st.next_tangent;
}

fn strip_segments(st: Strip) -> u32 {
    return select(max(st.have, 1u) - 1u, st.have, st.has_next);
}

@compute @workgroup_size(32)
fn raster(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
) {
    let total = raster_args[3];
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(lane, sg_lane, sg_size, params.cooperative_assembly != 0u);
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        for (var m = 0u; m < strip_segments(strip); m++) {
            draw(strip.cps[m], strip.tangents[m], strip_segment_end(strip, m), strip_segment_tangent(strip, m), st.uv);
        }
        // smLayer is rewritten by the next strand.
        workgroupBarrier();
    }
}

// ---------------------------------------------------------------------------
// Deep opacity maps (passes/src/lipp/dom.rs). Bindings 1-5 are the raster's;
// 0 and 6.. are the DOM entries' own.

struct DomParams {
    resolution: u32,
    layers: u32,
    layer_thickness: f32,
    strand_opacity: f32,
    density_compensation: u32,
    cooperative_assembly: u32,
    styling: u32,
    bundles: u32,
}

@group(0) @binding(0) var<uniform> dom_params: DomParams;
@group(0) @binding(8) var<storage, read_write> dom_depth: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read> dom_opacity_pass_dom_depth: array<u32>;
@group(0) @binding(9) var<storage, read_write> dom_layers: array<atomic<u32>>;

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

// One column of dom::walk: (first row, last row, depth), for column `col`.
fn walk_column(a: vec3<f32>, b: vec3<f32>, x_major: bool, col: f32) -> vec3<f32> {
    let ma = select(a.y, a.x, x_major);
    let na = select(a.x, a.y, x_major);
    let mb = select(b.y, b.x, x_major);
    let nb = select(b.x, b.y, x_major);
    let dm = mb - ma;
    let dn = nb - na;
    var t0 = 0.0;
    var t1 = 1.0;
    if dm != 0.0 {
        let ta = clamp((col - ma) / dm, 0.0, 1.0);
        let tb = clamp((col + 1.0 - ma) / dm, 0.0, 1.0);
        t0 = min(ta, tb);
        t1 = max(ta, tb);
    }
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

fn dom_amount(st: Strand) -> u32 {
    var thinning = 1.0;
    if dom_params.density_compensation != 0u {
        thinning = st.thinning;
    }
    return u32(floor(dom_params.strand_opacity * thinning * OPACITY_SCALE + 0.5));
}

fn dom_segment_depth(a: ControlPoint, b: ControlPoint, l: u32, lf: LightFrame) {
    let res = dom_params.resolution;
    {
        let pa = dom_end(lf, a.pos, res);
        let pb = dom_end(lf, b.pos, res);
        let cols = walk_columns(pa, pb, res);
        let x_major = cols.z != 0.0;
        for (var col = cols.x; col <= cols.y; col += 1.0) {
            let span = walk_column(pa, pb, x_major, col);
            let z = span.z;
            if !(z >= 0.0 && z <= 1.0) {
                continue;
            }
            for (var row = max(span.x, 0.0); row <= min(span.y, f32(res) - 1.0); row += 1.0) {
                let xy = select(vec2<f32>(row, col), vec2<f32>(col, row), x_major);
                let texel = l * res * res + u32(xy.y) * res + u32(xy.x);
                // A plain load first (see dom.rs): skips most atomics.
                let bits = bitcast<u32>(z);
                if bits < atomicLoad(&dom_depth[texel]) {
                    atomicMin(&dom_depth[texel], bits);
                }
            }
        }
    }
}

fn dom_segment_opacity(a: ControlPoint, b: ControlPoint, amount: u32, l: u32, lf: LightFrame) {
    let res = dom_params.resolution;
    {
        let pa = dom_end(lf, a.pos, res);
        let pb = dom_end(lf, b.pos, res);
        let cols = walk_columns(pa, pb, res);
        let x_major = cols.z != 0.0;
        for (var col = cols.x; col <= cols.y; col += 1.0) {
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
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, dom_params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        // Each light's view once per strand, the strip's segments in it.
        for (var li = 0u; li < lights_n; li++) {
            let lf = light_frame(li);
            for (var m = 0u; m < strip_segments(strip); m++) {
                dom_segment_depth(strip.cps[m], strip_segment_end(strip, m), li, lf);
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
    let stride = max(groups.x, 1u);
    for (var s = wg.x; s < total; s += stride) {
        let st = load_strand(count, s, dom_params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        let strip = pass_two(st, l);
        let amount = dom_amount(st);
        for (var li = 0u; li < lights_n; li++) {
            let lf = light_frame(li);
            for (var m = 0u; m < strip_segments(strip); m++) {
                dom_segment_opacity(strip.cps[m], strip_segment_end(strip, m), amount, li, lf);
            }
        }
        workgroupBarrier();
    }
}
