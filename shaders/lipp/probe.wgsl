// Probe lighting for lipp.shade (Lipp §3.4): the GGX lobe standing in for
// R + TRT and the addressing of `env.prefiltered`. Port of
// passes/src/lipp/probe.rs (the layout, the lobe's choice and its citations
// are documented there). The importing shader binds the buffer and fetches
// the four texels probe_taps names (a module cannot read another's binding):
//   #import strandgraph::probe::{probe_lobe, probe_taps, probe_blend, ...}
#define_import_path strandgraph::probe

#import strandgraph::lipp::{PI, safe_normalize}

// probe::{LEVELS, WIDTH, HEIGHT, MIN_WIDTH, MIN_HEIGHT}.
const PROBE_LEVELS: u32 = 6u;
const PROBE_WIDTH: u32 = 128u;
const PROBE_HEIGHT: u32 = 64u;
const PROBE_MIN_WIDTH: u32 = 16u;
const PROBE_MIN_HEIGHT: u32 = 8u;

// probe::level_size.
fn probe_level_size(k: u32) -> vec2<u32> {
    return max(
        vec2<u32>(PROBE_WIDTH >> k, PROBE_HEIGHT >> k),
        vec2<u32>(PROBE_MIN_WIDTH, PROBE_MIN_HEIGHT),
    );
}

// probe::level_offset.
fn probe_level_offset(k: u32) -> u32 {
    var o = 0u;
    for (var i = 0u; i < k; i++) {
        let s = probe_level_size(i);
        o += s.x * s.y;
    }
    return o;
}

// probe::alpha_lod: the fractional level of GGX roughness α.
fn probe_alpha_lod(alpha: f32) -> f32 {
    return sqrt(clamp(alpha, 0.0, 1.0)) * f32(PROBE_LEVELS - 1u);
}

// probe::latlong_uv.
fn latlong_uv(d: vec3<f32>) -> vec2<f32> {
    let u = 0.5 + atan2(d.x, -d.z) / (2.0 * PI);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    return vec2<f32>(u, v);
}

// Four texel indices into env.prefiltered (x0y0, x1y0, x0y1, x1y1) and the
// bilinear fractions.
struct ProbeTaps {
    texel: vec4<u32>,
    t: vec2<f32>,
}

// probe::bilinear_taps at level k and lat-long (u, v) (latlong_uv, once for
// both levels), as indices: x wraps, y clamps. Every level's width is a
// power of two (probe.rs tests it), so x wraps with a mask. Four integer
// remainders a level by a width the compiler does not know, and the
// lat-long angles computed for each level, cost lipp.shade 14 µs at close
// on the H200 (benches/results/lipp-clear-blocks-h200.txt, item 7).
fn probe_taps(k: u32, uv: vec2<f32>) -> ProbeTaps {
    let size = probe_level_size(k);
    let fx = uv.x * f32(size.x) - 0.5;
    let fy = uv.y * f32(size.y) - 0.5;
    let x0f = floor(fx);
    let y0f = floor(fy);
    let tx = fx - x0f;
    let ty = fy - y0f;
    let w = i32(size.x);
    let h = i32(size.y);
    let x0 = i32(x0f);
    let y0 = i32(y0f);
    // x0 >= -1: -1 wraps to size.x - 1, as rem_euclid does.
    let xa = bitcast<u32>(x0) & (size.x - 1u);
    let xb = bitcast<u32>(x0 + 1) & (size.x - 1u);
    let ya = u32(clamp(y0, 0, h - 1));
    let yb = u32(clamp(y0 + 1, 0, h - 1));
    let o = probe_level_offset(k);
    let ra = o + ya * size.x;
    let rb = o + yb * size.x;
    return ProbeTaps(vec4<u32>(ra + xa, ra + xb, rb + xa, rb + xb), vec2<f32>(tx, ty));
}

// probe::blend.
fn probe_blend(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, c3: vec3<f32>, t: vec2<f32>) -> vec3<f32> {
    let top = c0 + (c1 - c0) * t.x;
    let bottom = c2 + (c3 - c2) * t.x;
    return top + (bottom - top) * t.y;
}

// probe::view_facing_normal.
fn view_facing_normal(t: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    var n = safe_normalize(v - t * dot(t, v));
    if dot(n, n) <= 0.0 {
        n = v;
    }
    return n;
}

// probe::SpecularLobe.
struct ProbeLobe {
    direction: vec3<f32>,
    alpha: f32,
    weight: vec3<f32>,
}

// probe::specular_lobe: one GGX lobe for R + TRT, from the view's
// directional albedo (chiang's FibrePaths: R in x, TRT in yzw).
fn probe_lobe(t: vec3<f32>, v: vec3<f32>, n: vec3<f32>, albedo: vec4<f32>, roughness: f32, alpha: f32) -> ProbeLobe {
    let sin_o = clamp(dot(t, v), -1.0, 1.0);
    let bm = clamp(roughness, 0.02, 1.0);
    let x0 = 0.726 * bm + 0.812 * bm * bm + 3.7 * pow(bm, 20.0);
    let v0 = x0 * x0;
    let w_r = albedo.x;
    let a_trt = albedo.yzw;
    let w_trt = (a_trt.x + a_trt.y + a_trt.z) / 3.0;
    // M_p's peaks in sin θ_i + sin θ_o (tangent root to tip): R +2α, TRT −4α.
    let s_r = 2.0 * alpha;
    let s_trt = -4.0 * alpha;
    let sum = w_r + w_trt;
    let mu = (w_r * s_r + w_trt * s_trt) / sum;
    let second = (w_r * (v0 + s_r * s_r) + w_trt * (4.0 * v0 + s_trt * s_trt)) / sum;
    let variance = max(second - mu * mu, 0.0);
    let sin_l = clamp(mu - sin_o, -1.0, 1.0);
    let cos_l = sqrt(max(1.0 - sin_l * sin_l, 0.0));
    let direction = safe_normalize(t * sin_l + n * cos_l);
    return ProbeLobe(direction, min(sqrt(0.5 * variance), 1.0), a_trt + w_r);
}
