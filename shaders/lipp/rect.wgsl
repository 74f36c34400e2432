// The groom's screen rectangle (ours): lipp.lod bounds each bundle, the scan
// unites them, lipp.shade skips the pixels outside and tells lipp.filter
// which it shaded. Port of passes/src/lipp/rect.rs (why and the bounds'
// derivation there). A rectangle is vec4<u32>(x0, y0, x1, y1), x1 and y1
// exclusive.
#define_import_path strandgraph::lipp_rect

#import strandgraph::clip::{transform, clip_to_screen}
#import strandgraph::lipp::{bilinear, MAX_GROUPS_X}
#import strandgraph::lipp_tiles::TILE

// rect::ARGS_RECT_LO/HI, ARGS_RUNS, ARGS_CLEAR and FILTER_RECT_LO/HI; a run
// is a tile (tiles.wgsl).
const ARGS_RECT_LO: u32 = 6u;
const ARGS_RECT_HI: u32 = 7u;
const ARGS_RUNS: u32 = 8u;
const ARGS_CLEAR: u32 = 13u;
const RUN: u32 = TILE;
const FILTER_RECT_LO: u32 = 4u;
const FILTER_RECT_HI: u32 = 5u;
const TWIST_REACH: f32 = 0.25;
const HERMITE_BULGE: f32 = 0.3;
const NOISE_REACH: f32 = 1.75;
const PAD: f32 = 2.0;

fn rect_is_empty(r: vec4<u32>) -> bool {
    return r.z <= r.x || r.w <= r.y;
}

// Rect::union.
fn rect_union(a: vec4<u32>, b: vec4<u32>) -> vec4<u32> {
    if rect_is_empty(a) {
        return b;
    }
    if rect_is_empty(b) {
        return a;
    }
    return vec4<u32>(min(a.xy, b.xy), max(a.zw, b.zw));
}

// rect::granularity.
fn granularity(w: u32, h: u32) -> u32 {
    var g = 8u;
    while (max(w, h) + g - 1u) / g > 255u {
        g *= 2u;
    }
    return g;
}

// Rect::pack_tiles.
fn pack_tiles(r: vec4<u32>, w: u32, h: u32) -> u32 {
    if rect_is_empty(r) {
        return 0u;
    }
    let g = granularity(w, h);
    let lo = r.xy / g;
    let hi = (r.zw + g - 1u) / g;
    return lo.x | (lo.y << 8u) | (hi.x << 16u) | (hi.y << 24u);
}

// Rect::unpack_tiles.
fn unpack_tiles(word: u32, w: u32, h: u32) -> vec4<u32> {
    let g = granularity(w, h);
    let size = vec4<u32>(w, h, w, h);
    let tiles = vec4<u32>(word & 0xFFu, (word >> 8u) & 0xFFu, (word >> 16u) & 0xFFu, word >> 24u);
    return min(tiles * g, size);
}

// Rect::args.
fn rect_args(r: vec4<u32>) -> vec2<u32> {
    return vec2<u32>(r.x | (r.y << 16u), r.z | (r.w << 16u));
}

// Rect::from_args.
fn rect_from_args(lo: u32, hi: u32) -> vec4<u32> {
    return vec4<u32>(lo & 0xFFFFu, lo >> 16u, hi & 0xFFFFu, hi >> 16u);
}

// Rect::runs: (first run, count) of RUN pixels.
fn rect_runs(r: vec4<u32>, w: u32) -> vec2<u32> {
    if rect_is_empty(r) {
        return vec2<u32>(0u);
    }
    let first = (r.y * w + r.x) / RUN;
    let last = ((r.w - 1u) * w + r.z - 1u) / RUN;
    return vec2<u32>(first, last - first + 1u);
}

// Rect::run_dispatch's x: a workgroup per `per` of `runs` runs.
fn run_groups(runs: u32, per: u32) -> u32 {
    let p = max(per, 1u);
    return min((runs + p - 1u) / p, MAX_GROUPS_X);
}

// Rect::runs_of_group: the block [lo, hi) of the `count` runs that
// workgroup `wg` of `groups` takes (one run each with as many workgroups).
fn group_runs(count: u32, wg: u32, groups: u32) -> vec2<u32> {
    let per = (count + groups - 1u) / max(groups, 1u);
    let lo = min(wg * per, count);
    return vec2<u32>(lo, min(lo + per, count));
}

// Rect::touches_run.
fn touches_run(r: vec4<u32>, first: u32, len: u32, w: u32) -> bool {
    let last = first + max(len, 1u) - 1u;
    let ya = first / w;
    let yb = last / w;
    if yb < r.y || ya >= r.w {
        return false;
    }
    return ya != yb || (last % w >= r.x && first % w < r.z);
}

// rect::extended_corner of the layer quad c0..c3.
fn extended_corner(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, c3: vec3<f32>, k: u32) -> vec3<f32> {
    let u = select(-TWIST_REACH, 1.0 + TWIST_REACH, k == 1u || k == 2u);
    let v = select(-TWIST_REACH, 1.0 + TWIST_REACH, k >= 2u);
    return bilinear(c0, c1, c2, c3, u, v);
}

// rect::bundle_box's growth: the styling reach and the Hermite bulge.
fn box_pad(curl_radius: f32, noise: f32, chord: f32) -> f32 {
    return abs(curl_radius) + NOISE_REACH * abs(noise) + HERMITE_BULGE * chord;
}

// rect::screen_rect.
fn screen_rect(view_proj: mat4x4<f32>, screen: vec2<f32>, near: f32, lo: vec3<f32>, hi: vec3<f32>) -> vec4<u32> {
    var s_lo = vec2<f32>(3.40282347e38);
    var s_hi = vec2<f32>(-3.40282347e38);
    for (var i = 0u; i < 8u; i++) {
        let p = select(lo, hi, vec3<bool>((i & 1u) != 0u, (i & 2u) != 0u, (i & 4u) != 0u));
        let c = transform(view_proj, vec4<f32>(p, 1.0));
        if !(c.w > near) {
            return vec4<u32>(0u, 0u, u32(screen.x), u32(screen.y));
        }
        let s = clip_to_screen(c, screen.x, screen.y);
        s_lo = min(s_lo, s.xy);
        s_hi = max(s_hi, s.xy);
    }
    let size = vec4<f32>(screen, screen);
    let e = clamp(vec4<f32>(floor(s_lo - PAD), ceil(s_hi + PAD)), vec4<f32>(0.0), size);
    return vec4<u32>(e);
}
