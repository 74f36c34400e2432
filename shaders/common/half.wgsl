// Half floats without the f16 capability (pack2x16float and
// unpack2x16float need naga's SHADER_FLOAT16_IN_FLOAT32), and the rgba16f
// radiance entries of `vertex_lighting` built from them. Composed with
// naga_oil:
//   #import strandgraph::half::{pack_radiance, unpack_radiance}
#define_import_path strandgraph::half

// half::f16::from_f32 (round to nearest even) without the f16 capability
// pack2x16float needs.
fn f16_bits(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    let sign = (b >> 16u) & 0x8000u;
    let e = i32((b >> 23u) & 0xFFu);
    var m = b & 0x7FFFFFu;
    if e == 255 {
        return sign | 0x7C00u | select(0u, 0x200u | (m >> 13u), m != 0u);
    }
    let he = e - 112;
    if he >= 31 {
        return sign | 0x7C00u;
    }
    if he <= 0 {
        if he < -10 {
            return sign;
        }
        m = m | 0x800000u;
        let shift = u32(14 - he);
        var hm = m >> shift;
        let rem = m & ((1u << shift) - 1u);
        let half = 1u << (shift - 1u);
        if rem > half || (rem == half && (hm & 1u) != 0u) {
            hm += 1u;
        }
        return sign | hm;
    }
    var h = (u32(he) << 10u) | (m >> 13u);
    let rem = m & 0x1FFFu;
    if rem > 0x1000u || (rem == 0x1000u && (h & 1u) != 0u) {
        h += 1u;
    }
    return sign | h;
}

// A half float's bits as f32 (debug_resolve::load_rgba16f; infinities and
// NaNs as the largest half, which lighting never reaches).
fn f16_to_f32(h: u32) -> f32 {
    let s = select(1.0, -1.0, (h & 0x8000u) != 0u);
    let e = (h >> 10u) & 0x1Fu;
    let m = f32(h & 0x3FFu);
    if e == 0u {
        return s * m * 5.9604645e-8;
    }
    if e == 31u {
        return s * 65504.0;
    }
    return s * (1.0 + m / 1024.0) * exp2(f32(e) - 15.0);
}

// One vertex_lighting entry (rgba16f) as linear RGB radiance.
fn unpack_radiance(w: vec2<u32>) -> vec3<f32> {
    return vec3<f32>(f16_to_f32(w.x & 0xFFFFu), f16_to_f32(w.x >> 16u), f16_to_f32(w.y & 0xFFFFu));
}

// One vertex_lighting entry (rgba16f, alpha 1) from linear RGB radiance.
fn pack_radiance(c: vec3<f32>) -> vec2<u32> {
    return vec2<u32>(f16_bits(c.x) | (f16_bits(c.y) << 16u), f16_bits(c.z) | (0x3C00u << 16u));
}
