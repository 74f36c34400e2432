// Helpers the Lipp kernels share, ported operation for operation from
// passes/src/lipp/{mod,payload,strand}.rs. Composed with naga_oil:
//   #import strandgraph::lipp::{...}
#define_import_path strandgraph::lipp

#import strandgraph::hash::pcg
#import strandgraph::clip::transform

// Words per record (lipp::{BUNDLE_WORDS, LOD_WORDS}); vec4s per packed layer.
const BUNDLE_WORDS: u32 = 16u;
const LOD_WORDS: u32 = 4u;
const LAYER_VEC4S: u32 = 8u;
const MAX_LAYERS: u32 = 16u;
const RASTER_GROUP: u32 = 32u;
const MAX_CONTROL_POINTS: u32 = 129u;
const MAX_GROUPS_X: u32 = 65535u;
const LOD_CULLED: u32 = 1u;
const LOD_OTHER_GROOM: u32 = 2u;
// lipp::ARGS_BUNDLES_LO/HI: raster_args' words holding the scanned groom's bundles.
const ARGS_BUNDLES_LO: u32 = 11u;
const ARGS_BUNDLES_HI: u32 = 12u;
// payload::DEPTH_MAX, the sub-pixel snap grid.
const DEPTH_MAX: f32 = 16777215.0;
// payload::INV_DEPTH_MAX: 1 / DEPTH_MAX rounded once to f32 (0x33800001).
const INV_DEPTH_MAX: f32 = 0x1.000002p-24f;
const SNAP: f32 = 256.0;
const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const F32_MAX: f32 = 3.40282347e38;
const F32_MIN: f32 = -3.40282347e38;
// payload::EMPTY as the two words WGSL sees.
const EMPTY_WORD: u32 = 0xFFFFFFFFu;

// lipp::unit: 24 bits of a hash in [0, 1).
fn unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// lipp::normalize: zero for a zero vector.
fn safe_normalize(a: vec3<f32>) -> vec3<f32> {
    let l = sqrt(dot(a, a));
    if l > 0.0 {
        return a * (1.0 / l);
    }
    return vec3<f32>(0.0);
}

fn lerp_vec(a: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> {
    return a + (b - a) * t;
}

// strand::bilinear: the quad c0..c3 at (u, v), corner k at
// [(0,0), (1,0), (1,1), (0,1)][k].
fn bilinear(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, c3: vec3<f32>, u: f32, v: f32) -> vec3<f32> {
    let bottom = lerp_vec(c0, c1, u);
    let top = lerp_vec(c3, c2, u);
    return lerp_vec(bottom, top, v);
}

// Sign that is 1 at zero (oct_encode's sign_not_zero).
fn sign_nz(x: f32) -> f32 {
    return select(-1.0, 1.0, x >= 0.0);
}

fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if !(l1 > 0.0) {
        return vec2<f32>(0.0);
    }
    let px = n.x / l1;
    let py = n.y / l1;
    if n.z < 0.0 {
        return vec2<f32>((1.0 - abs(py)) * sign_nz(px), (1.0 - abs(px)) * sign_nz(py));
    }
    return vec2<f32>(px, py);
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - abs(e.x) - abs(e.y);
    var xy = e;
    if z < 0.0 {
        xy = vec2<f32>((1.0 - abs(e.y)) * sign_nz(e.x), (1.0 - abs(e.x)) * sign_nz(e.y));
    }
    return safe_normalize(vec3<f32>(xy.x, xy.y, z));
}

// payload::quantize.
fn quantize(x: f32, levels: f32) -> u32 {
    return u32(floor(clamp(x, 0.0, 1.0) * levels + 0.5));
}

// payload::depth_bits.
fn depth_bits(z: f32) -> u32 {
    return min(u32(floor(clamp(z, 0.0, 1.0) * DEPTH_MAX)), 0xFFFFFEu);
}

// payload::unpack.
struct Sample {
    depth: f32,
    tangent: vec3<f32>,
    uvw: vec3<f32>,
    ao: f32,
}

fn is_empty(p: vec2<u32>) -> bool {
    return p.x == EMPTY_WORD && p.y == EMPTY_WORD;
}

fn unpack_payload(p: vec2<u32>) -> Sample {
    let lo = p.x;
    let hi = p.y;
    let e = vec2<f32>(f32(hi & 0xFFu) / 255.0 * 2.0 - 1.0, f32(lo >> 24u) / 255.0 * 2.0 - 1.0);
    return Sample(
        f32(hi >> 8u) * INV_DEPTH_MAX,
        oct_decode(e),
        vec3<f32>(f32((lo >> 18u) & 63u) / 63.0, f32((lo >> 12u) & 63u) / 63.0, f32((lo >> 6u) & 63u) / 63.0),
        f32(lo & 63u) / 63.0,
    );
}

// strand::strand_uv: the R2 sequence in 32-bit fixed point.
fn strand_uv(k: u32) -> vec2<f32> {
    return vec2<f32>(unit(0x80000000u + k * 3242174889u), unit(0x80000000u + k * 2447445414u));
}

// strand::strand_id.
fn strand_id(seed: u32, k: u32) -> vec3<f32> {
    let h = pcg(seed ^ pcg(k));
    let h2 = pcg(h);
    return vec3<f32>(unit(h), unit(h2), unit(pcg(h2)));
}

// strand::calc_tangent (Lipp Code 1).
fn calc_tangent(idx: u32, count: u32, prev: vec3<f32>, curr: vec3<f32>, next: vec3<f32>) -> vec3<f32> {
    if idx == 0u {
        return safe_normalize(next - curr);
    }
    if idx + 1u >= count {
        return safe_normalize(curr - prev);
    }
    return safe_normalize(next - prev);
}

// filter::linear_depth (glam perspective_rh, z in [0, 1]).
fn linear_depth(near: f32, far: f32, z: f32) -> f32 {
    return near * far / (far - z * (far - near));
}

// shade::world_position.
fn world_position(inv_view_proj: mat4x4<f32>, screen: vec4<f32>, x: u32, y: u32, z: f32) -> vec3<f32> {
    let ndc_x = (f32(x) + 0.5) * screen.z * 2.0 - 1.0;
    let ndc_y = 1.0 - (f32(y) + 0.5) * screen.w * 2.0;
    let p = transform(inv_view_proj, vec4<f32>(ndc_x, ndc_y, z, 1.0));
    return vec3<f32>(p.x / p.w, p.y / p.w, p.z / p.w);
}

struct LightFrame {
    right: vec3<f32>,
    up: vec3<f32>,
    forward: vec3<f32>,
    lo: vec3<f32>,
    inv: vec3<f32>,
    depth_extent: f32,
}

// dom::LightFrame::new: a light's orthographic frame around the bounds
// lo..hi, for a light with position_or_direction `pd`.
fn light_frame_of(lo: vec3<f32>, hi: vec3<f32>, pd: vec4<f32>) -> LightFrame {
    var forward = safe_normalize(pd.xyz);
    if pd.w != 0.0 {
        forward = safe_normalize((lo + hi) * 0.5 - pd.xyz);
    }
    if dot(forward, forward) <= 0.0 {
        forward = vec3<f32>(0.0, -1.0, 0.0);
    }
    var up0 = vec3<f32>(0.0, 1.0, 0.0);
    if abs(forward.y) > 0.99 {
        up0 = vec3<f32>(1.0, 0.0, 0.0);
    }
    let right = safe_normalize(cross(forward, up0));
    let up = cross(right, forward);
    var plo = vec3<f32>(3.40282347e38);
    var phi = vec3<f32>(-3.40282347e38);
    for (var i = 0u; i < 8u; i++) {
        let p = vec3<f32>(
            select(lo.x, hi.x, (i & 1u) != 0u),
            select(lo.y, hi.y, (i & 2u) != 0u),
            select(lo.z, hi.z, (i & 4u) != 0u),
        );
        let q = vec3<f32>(dot(p, right), dot(p, up), dot(p, forward));
        plo = min(plo, q);
        phi = max(phi, q);
    }
    let pad = max((phi - plo) * 0.01, vec3<f32>(1e-3));
    plo = plo - pad;
    phi = phi + pad;
    return LightFrame(right, up, forward, plo, vec3<f32>(1.0) / (phi - plo), phi.z - plo.z);
}

// dom::LightFrame::project: world point to the map's [0, 1]^3.
fn light_project(lf: LightFrame, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        (dot(p, lf.right) - lf.lo.x) * lf.inv.x,
        (dot(p, lf.up) - lf.lo.y) * lf.inv.y,
        (dot(p, lf.forward) - lf.lo.z) * lf.inv.z,
    );
}
