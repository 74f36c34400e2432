// The `shaded` record lipp.shade writes and lipp.filter reads: RGB9E5
// radiance, then the sample's 24-bit depth over two hit flags. Port of
// passes/src/lipp/shaded.rs (layout and why there). The exponent comes from
// the float's bits, as on the CPU, so both pack the same bits.
#define_import_path strandgraph::lipp_shaded

#import strandgraph::lipp::{INV_DEPTH_MAX, is_empty, linear_depth}

const RGB9E5_MAX: f32 = 65408.0;
// Word 1's flags: this layer has a sample; the pixel's conservative layer
// has one; it lies in front of the centre one (shaded::FRONT).
const HIT: u32 = 1u;
const CONS_HIT: u32 = 2u;
const FRONT: u32 = 4u;

// shaded::exp2i: 2^k, exactly.
fn exp2i(k: i32) -> f32 {
    return bitcast<f32>(u32(k + 127) << 23u);
}

// shaded::floor_log2.
fn floor_log2(x: f32) -> i32 {
    return i32((bitcast<u32>(x) >> 23u) & 0xFFu) - 127;
}

// shaded::pack_rgb9e5 (NaN and negatives to 0).
fn pack_rgb9e5(color: vec3<f32>) -> u32 {
    let c = min(max(vec3<f32>(0.0), color), vec3<f32>(RGB9E5_MAX));
    let m = max(c.x, max(c.y, c.z));
    var e = max(floor_log2(m), -16) + 16;
    if floor(m * exp2i(24 - e) + 0.5) >= 512.0 {
        e += 1;
    }
    let q = vec3<u32>(floor(c * exp2i(24 - e) + vec3<f32>(0.5)));
    return q.x | (q.y << 9u) | (q.z << 18u) | (u32(e) << 27u);
}

fn unpack_rgb9e5(w: u32) -> vec3<f32> {
    let scale = exp2i(i32(w >> 27u) - 24);
    return vec3<f32>(f32(w & 511u), f32((w >> 9u) & 511u), f32((w >> 18u) & 511u)) * scale;
}

// shaded::record.
fn shaded_record(color: vec3<f32>, payload_hi: u32, flags: u32) -> vec2<u32> {
    return vec2<u32>(pack_rgb9e5(color), (payload_hi & 0xFFFFFF00u) | flags);
}

// shaded::depth.
fn record_depth(word1: u32) -> f32 {
    return f32(word1 >> 8u) * INV_DEPTH_MAX;
}

// shaded::pixel_flags: CONS_HIT and FRONT from the pixel's two payloads.
fn pixel_flags(near: f32, far: f32, centre: vec2<u32>, cons: vec2<u32>, front_threshold: f32) -> u32 {
    if is_empty(cons) {
        return 0u;
    }
    var front = false;
    if !is_empty(centre) {
        front = linear_depth(near, far, record_depth(cons.y)) <= linear_depth(near, far, record_depth(centre.y)) - front_threshold;
    }
    return CONS_HIT | select(0u, FRONT, front);
}

// shaded::read_by_filter.
fn read_by_filter(layer: u32, layers: u32, centre_hit: bool, flags: u32) -> bool {
    return layer != 1u || layers > 2u || !centre_hit || (flags & FRONT) != 0u;
}
