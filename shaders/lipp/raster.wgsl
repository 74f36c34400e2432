// lipp.raster (entries `raster`, `raster_sample_payload` for
// segment_payload off, and each with `_code1_strips` for strip_rounds
// off): Lipp §3.1 and Appendix B Code 1. One
// 32-lane workgroup per strand (indirect; workgroups stride over strands
// beyond 65535), the strand assembled cooperatively (assembly.wgsl, shared
// with the deep opacity maps in dom_maps.wgsl), then DDA rasterization into
// the centre and conservative 64-bit G-buffer layers with atomicMin.
// Port of passes/src/lipp/raster.rs. Needs SHADER_INT64 and
// SHADER_INT64_ATOMIC_MIN_MAX.

// Bindings 1 (frame), 6 (models) and 7 (lights) are declared in dom.wgsl.
#define FRAME_BINDING 1
#define MODELS_BINDING 6
#define LIGHTS_BINDING 7
#import strandgraph::lipp_dom::{frame, models, lights, light_frame, NO_HIT, OPACITY_SCALE}
#import strandgraph::layout::{FrameData, ModelData, LightData}
#import strandgraph::hash::pcg
#import strandgraph::clip::{transform, clip_to_screen, near_clip, clip_at, clip_at3}
#import strandgraph::lipp::{LightFrame, light_frame_of, light_project, unit, safe_normalize, lerp_vec, calc_tangent, strand_uv, strand_id, oct_encode, quantize, depth_bits, BUNDLE_WORDS, LOD_WORDS, LAYER_VEC4S, MAX_LAYERS, RASTER_GROUP, MAX_CONTROL_POINTS, SNAP, TAU, PI}
#import strandgraph::hiz::hiz_farthest
#import strandgraph::lipp_assembly::{raster_args, bundle_lod, hairmesh_bundles, hairmesh_layers, ControlPoint, Strand, Strip, load_strand, lanes_of, pass_one, pass_two, pass_two_round, strip_rounds, strand_at, strip_point, strip_tangent, strip_segments, snap, column_params, walk_column, walk_columns}

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
    // Ours: the tangent packed once per segment (raster::segment_payload);
    // it selects the entry point (`raster` or `raster_sample_payload`).
    segment_payload: u32,
    // Ours: segments behind the scene's Hi-Z are not walked
    // (raster::occlusion_cull).
    occlusion_cull: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: RasterParams;
@group(0) @binding(6) var scene_depth: texture_2d<f32>;
// Earlier grooms' depth (f32 bits), written by their filter passes.
@group(0) @binding(7) var<storage, read> hair_depth: array<u32>;
@group(0) @binding(8) var<storage, read_write> gbuffer: array<atomic<u64>>;
// The farthest scene depth of each 16x16 block (kulikov.depth_downsample).
@group(0) @binding(9) var hiz: texture_2d<f32>;

struct End {
    x: f32,
    y: f32,
    z: f32,
    tangent: vec3<f32>,
    w: f32,
    ao: f32,
}

// Target::project: one end of the part of segment (a, b) in front of the
// near plane, at its clip position c and parameter t along (a, b).
fn project_end(c: vec4<f32>, t: f32, a: ControlPoint, ta: vec3<f32>, b: ControlPoint, tb: vec3<f32>) -> End {
    let s = clip_to_screen(c, frame.screen.x, frame.screen.y);
    return End(snap(s.x), snap(s.y), s.z, clip_at3(ta, tb, t), clip_at(a.w, b.w, t), clip_at(a.ao, b.ao, t));
}

// payload::pack's tangent bits: octahedral x (high word) and y (low word,
// already shifted).
fn tangent_bits(tangent: vec3<f32>) -> vec2<u32> {
    let e = oct_encode(tangent);
    return vec2<u32>(quantize(e.y * 0.5 + 0.5, 255.0) << 24u, quantize(e.x * 0.5 + 0.5, 255.0));
}

// Target::segment_bits: what every sample of a segment with end tangents
// ta, tb shares in payload::pack's layout: the strand's u and v, and unless
// the tangent is packed per sample, the tangent at the segment's middle.
// `per_sample` is a constant of each entry point, so each compiles only its
// own side.
fn segment_bits(ta: vec3<f32>, tb: vec3<f32>, uv: vec2<f32>, per_sample: bool) -> vec2<u32> {
    var bits = vec2<u32>((quantize(uv.x, 63.0) << 18u) | (quantize(uv.y, 63.0) << 12u), 0u);
    if !per_sample {
        bits |= tangent_bits(safe_normalize(lerp_vec(ta, tb, 0.5)));
    }
    return bits;
}

// Segment m's bits (segment_bits), or nothing past the strip's segments.
fn strip_bits(strip: Strip, m: u32, uv: vec2<f32>, per_sample: bool) -> vec2<u32> {
    if m >= strip_segments(strip) {
        return vec2<u32>(0u);
    }
    return segment_bits(strip_tangent(strip, m), strip_tangent(strip, m + 1u), uv, per_sample);
}

// Target::put: payload::pack of a depth-tested sample at t, from the
// segment's shared bits.
fn put(a: End, b: End, t: f32, z: f32, pixel: u32, layer: u32, seg_bits: vec2<u32>, per_sample: bool) {
    var p = seg_bits;
    if per_sample {
        p |= tangent_bits(safe_normalize(lerp_vec(a.tangent, b.tangent, t)));
    }
    p.x |= (quantize(a.w + (b.w - a.w) * t, 63.0) << 6u) | quantize(a.ao + (b.ao - a.ao) * t, 63.0);
    p.y |= depth_bits(z) << 8u;
    let slot = layer * params.width * params.height + pixel;
    atomicMin(&gbuffer[slot], (u64(p.y) << 32u) | u64(p.x));
}

// Target::write_pixel: the sample at tc into layer `layer` (if `centre`)
// and the conservative layer's at tm (if `cons`) into pixel (x, y), with
// one read of the depth both are tested against.
fn write_pixel(a: End, b: End, x: i32, y: i32, centre: bool, tc: f32, layer: u32, cons: bool, tm: f32, seg_bits: vec2<u32>, per_sample: bool) {
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return;
    }
    let pixel = u32(y) * params.width + u32(x);
    var limit = textureLoad(scene_depth, vec2<i32>(x, y), 0).x;
    if params.model_index > 0u {
        limit = min(limit, bitcast<f32>(hair_depth[pixel]));
    }
    let zc = a.z + (b.z - a.z) * tc;
    if centre && zc >= 0.0 && zc < 1.0 && zc < limit {
        put(a, b, tc, zc, pixel, layer, seg_bits, per_sample);
    }
    let zm = a.z + (b.z - a.z) * tm;
    if cons && zm >= 0.0 && zm < 1.0 && zm < limit {
        put(a, b, tm, zm, pixel, 1u, seg_bits, per_sample);
    }
}

// raster::column_rows: the union of the centre and conservative rows
// (lo, hi) of a column (each empty when lo > hi).
fn column_rows(centre: vec2<i32>, cons: vec2<i32>) -> vec2<i32> {
    if centre.x > centre.y {
        return cons;
    }
    if cons.x > cons.y {
        return centre;
    }
    return vec2<i32>(min(centre.x, cons.x), max(centre.y, cons.y));
}

fn pixel_of(x_major: bool, m: i32, n: i32) -> vec2<i32> {
    return select(vec2<i32>(n, m), vec2<i32>(m, n), x_major);
}

// Target::segment: a DDA over the major axis, one column at a time. A
// column's centre rows and conservative rows are visited in one loop
// (Target::column_rows), each pixel once.
fn draw_segment(a: End, b: End, bits: vec2<u32>, per_sample: bool) {
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
    let cons_on = params.conservative_layer != 0u;
    for (var col = lo; col <= hi; col += 1.0) {
        let ci = i32(col);
        let t = column_params(ma, dm, col);
        let centre = col + 0.5;
        var c_lo = 1;
        var c_hi = 0;
        var tc = 0.0;
        var nc = 0.0;
        if dm != 0.0 && centre >= min(ma, mb) && centre < max(ma, mb) {
            tc = (centre - ma) / dm;
            nc = na + dn * tc;
            c_lo = i32(floor(nc - 0.5));
            c_hi = c_lo + 1;
        }
        var r0 = 1;
        var r1 = 0;
        if cons_on {
            let n0 = na + dn * t.x;
            let n1 = na + dn * t.y;
            r0 = i32(floor(min(n0, n1)));
            r1 = i32(floor(max(n0, n1)));
        }
        let tm = 0.5 * (t.x + t.y);
        let rows = column_rows(vec2<i32>(c_lo, c_hi), vec2<i32>(r0, r1));
        for (var row = rows.x; row <= rows.y; row++) {
            let cen = row >= c_lo && row <= c_hi && abs((nc - (f32(row) + 0.5)) * cosa) <= half;
            let con = row >= r0 && row <= r1;
            if cen || con {
                let p = pixel_of(x_major, ci, row);
                write_pixel(a, b, p.x, p.y, cen, tc, 0u, con, tm, bits, per_sample);
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
fn draw_segment_msaa(a: End, b: End, bits: vec2<u32>, per_sample: bool) {
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
                    write_pixel(a, b, p.x, p.y, true, t, s, false, 0.0, bits, per_sample);
                }
            }
        }
    }
}

// Target::hidden (raster::occlusion_cull): whether every pixel segment
// (a, b) can write lies behind the scene. The walk's rows reach a pixel past
// the segment's box, hence the box grown by one.
fn hidden(a: End, b: End) -> bool {
    let w = f32(params.width) - 1.0;
    let h = f32(params.height) - 1.0;
    let bounds = vec4<u32>(
        u32(clamp(min(a.x, b.x) - 1.0, 0.0, w)),
        u32(clamp(min(a.y, b.y) - 1.0, 0.0, h)),
        u32(clamp(max(a.x, b.x) + 1.0, 0.0, w)),
        u32(clamp(max(a.y, b.y) + 1.0, 0.0, h)),
    );
    return min(a.z, b.z) >= hiz_farthest(hiz, bounds);
}

fn draw(a: ControlPoint, ta: vec3<f32>, b: ControlPoint, tb: vec3<f32>, bits: vec2<u32>, per_sample: bool) {
    let part = near_clip(transform(frame.view_proj, vec4<f32>(a.pos, 1.0)),
        transform(frame.view_proj, vec4<f32>(b.pos, 1.0)), frame.near);
    if part.valid {
        let pa = project_end(part.a, part.ta, a, ta, b, tb);
        let pb = project_end(part.b, part.tb, a, ta, b, tb);
        if params.occlusion_cull != 0u && hidden(pa, pb) {
            return;
        }
        if params.msaa > 1u {
            draw_segment_msaa(pa, pb, bits, per_sample);
        } else {
            draw_segment(pa, pb, bits, per_sample);
        }
    }
}

// Segment m's bits of the four a lane's strip holds.
fn pick_bits(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>, d: vec2<u32>, m: u32) -> vec2<u32> {
    return select(select(select(d, c, m == 2u), b, m == 1u), a, m == 0u);
}

// The strands of this workgroup; `per_sample`: the tangent packed per
// sample (raster::segment_payload off); `max_strip`: points a lane holds,
// 1 in rounds (raster::strip_rounds) or 4, Code 1's single round.
fn raster_strands(ids: Ids, per_sample: bool, max_strip: u32) {
    let total = raster_args[3];
    let count = min(params.bundles, arrayLength(&bundle_lod) / LOD_WORDS);
    let l = lanes_of(ids.lane, ids.sg_lane, ids.sg_size, params.cooperative_assembly != 0u);
    let stride = max(ids.groups.x, 1u);
    for (var s = ids.wg.x; s < total; s += stride) {
        let st = load_strand(count, s, params.styling != 0u);
        pass_one(st, l);
        workgroupBarrier();
        if max_strip >= 4u {
            // Code 1: one round covers every C <= 129.
            raster_strip(pass_two(st, l), st.uv, per_sample, max_strip);
        } else {
            // Each round reads its strand again rather than hold the
            // bundle's values through the last round's walk: 61 registers a
            // lane instead of 69 on the H200 (raster::strip_rounds).
            let bi = st.bundle_index;
            let k = st.k;
            let c = st.c;
            for (var round = 0u; round < strip_rounds(c, max_strip); round++) {
                let again = strand_at(bi, k, c, 1.0, params.styling != 0u);
                raster_strip(pass_two_round(again, l, round, max_strip), again.uv, per_sample, max_strip);
            }
        }
        // smLayer is rewritten by the next strand.
        workgroupBarrier();
    }
}

// A lane's strip of segments.
fn raster_strip(strip: Strip, uv: vec2<f32>, per_sample: bool, max_strip: u32) {
    // Every segment's payload bits before the walk: past this point the
    // shipped entry needs no tangent, and their registers are free. Slots
    // past `max_strip` (a constant) are never drawn.
    let bits_a = strip_bits(strip, 0u, uv, per_sample);
    var bits_b = vec2<u32>(0u);
    var bits_c = vec2<u32>(0u);
    var bits_d = vec2<u32>(0u);
    if max_strip > 1u {
        bits_b = strip_bits(strip, 1u, uv, per_sample);
    }
    if max_strip > 2u {
        bits_c = strip_bits(strip, 2u, uv, per_sample);
        bits_d = strip_bits(strip, 3u, uv, per_sample);
    }
    for (var m = 0u; m < strip_segments(strip); m++) {
        let bits = pick_bits(bits_a, bits_b, bits_c, bits_d, m);
        draw(strip_point(strip, m), strip_tangent(strip, m), strip_point(strip, m + 1u), strip_tangent(strip, m + 1u), bits, per_sample);
    }
}

// Entries: segment_payload on / off (raster_sample_payload), each with
// strip_rounds on (1 point a lane) or off (the `_code1_strips` entries).
struct Ids {
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(subgroup_invocation_id) sg_lane: u32,
    @builtin(subgroup_size) sg_size: u32,
}

@compute @workgroup_size(32)
fn raster(ids: Ids) {
    raster_strands(ids, false, 1u);
}

@compute @workgroup_size(32)
fn raster_sample_payload(ids: Ids) {
    raster_strands(ids, true, 1u);
}

@compute @workgroup_size(32)
fn raster_code1_strips(ids: Ids) {
    raster_strands(ids, false, 4u);
}

@compute @workgroup_size(32)
fn raster_sample_payload_code1_strips(ids: Ids) {
    raster_strands(ids, true, 4u);
}
