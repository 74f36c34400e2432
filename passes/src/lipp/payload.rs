//! Lipp §3.1.2, the compressed 64-bit G-buffer payload. "24 bits are used for
//! depth" in the high bits so that `atomicMin` keeps the nearest strand; the
//! position is reconstructed from depth; the shading parameters are replaced
//! by the strand's uvw; the tangent is octahedral; "all float values except
//! for depth are quantized as either uint8 or uint6".
//!
//! Layout (bit 63 first):
//!
//! | bits   | field                                   |
//! |--------|-----------------------------------------|
//! | 63..40 | NDC depth z in [0, 1), 24-bit unorm     |
//! | 39..32 | octahedral tangent x, 8-bit unorm       |
//! | 31..24 | octahedral tangent y, 8-bit unorm       |
//! | 23..18 | u (strand position in the bundle), 6-bit |
//! | 17..12 | v, 6-bit                                |
//! | 11..6  | w (root 0 .. tip 1), 6-bit              |
//! | 5..0   | baked AO (Lipp §3.4), 6-bit             |
//!
//! The G-buffer holds two such layers per pixel, planar: slot `i` is the
//! centre-sample layer of pixel `i`, slot `pixels + i` the conservative one.
//! The clear value (all ones) is "empty"; no payload reaches it because depth
//! 1.0 (the far plane) is never written.

use super::{oct_decode, oct_encode};

pub const EMPTY: u64 = u64::MAX;
/// 2^24 − 1.
pub const DEPTH_MAX: f32 = 16_777_215.0;
/// `1 / DEPTH_MAX`, rounded once: depth unpacks as a multiplication on the
/// CPU and in WGSL (`INV_DEPTH_MAX`, the same bits), because a GPU compiler
/// may turn `x / DEPTH_MAX` into `x · rcp(DEPTH_MAX)` (the H100's does),
/// one rounding more than the CPU's division.
pub const INV_DEPTH_MAX: f32 = 1.0 / DEPTH_MAX;

/// What a strand writes into a pixel, before quantisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// NDC depth in [0, 1).
    pub depth: f32,
    /// World-space unit tangent.
    pub tangent: [f32; 3],
    pub uvw: [f32; 3],
    pub ao: f32,
}

/// `floor(x * levels + 0.5)` clamped to `0..=levels`: the same on every
/// backend (WGSL's `round` rounds halves to even, Rust's away from zero).
pub fn quantize(x: f32, levels: f32) -> u32 {
    (x.clamp(0.0, 1.0) * levels + 0.5).floor() as u32
}

/// The 24-bit depth of NDC depth `z` (truncated, so nearer never rounds up).
pub fn depth_bits(z: f32) -> u32 {
    ((z.clamp(0.0, 1.0) * DEPTH_MAX).floor() as u32).min(0xFF_FFFE)
}

pub fn pack(s: &Sample) -> u64 {
    let e = oct_encode(s.tangent);
    let hi = (depth_bits(s.depth) << 8) | quantize(e[0] * 0.5 + 0.5, 255.0);
    let lo = (quantize(e[1] * 0.5 + 0.5, 255.0) << 24)
        | (quantize(s.uvw[0], 63.0) << 18)
        | (quantize(s.uvw[1], 63.0) << 12)
        | (quantize(s.uvw[2], 63.0) << 6)
        | quantize(s.ao, 63.0);
    (u64::from(hi) << 32) | u64::from(lo)
}

pub fn unpack(p: u64) -> Sample {
    let (hi, lo) = ((p >> 32) as u32, p as u32);
    let e = [
        (hi & 0xFF) as f32 / 255.0 * 2.0 - 1.0,
        (lo >> 24) as f32 / 255.0 * 2.0 - 1.0,
    ];
    let six = |shift: u32| ((lo >> shift) & 63) as f32 / 63.0;
    Sample {
        depth: (hi >> 8) as f32 * INV_DEPTH_MAX,
        tangent: oct_decode(e),
        uvw: [six(18), six(12), six(6)],
        ao: six(0),
    }
}

/// The payload of the two words WGSL sees (`vec2<u32>(low, high)`).
pub fn from_words(lo: u32, hi: u32) -> u64 {
    u64::from(lo) | (u64::from(hi) << 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_orders_payloads_and_fields_round_trip() {
        let a = Sample {
            depth: 0.25,
            tangent: [0.0, -1.0, 0.0],
            uvw: [0.2, 0.9, 0.5],
            ao: 0.7,
        };
        let b = Sample { depth: 0.2501, ..a };
        assert!(pack(&a) < pack(&b), "nearer must win atomicMin");
        let u = unpack(pack(&a));
        assert!((u.depth - 0.25).abs() < 1e-6);
        assert!(super::super::length(super::super::sub(u.tangent, a.tangent)) < 0.02);
        for k in 0..3 {
            assert!((u.uvw[k] - a.uvw[k]).abs() <= 0.5 / 63.0 + 1e-6);
        }
        assert!((u.ao - 0.7).abs() <= 0.5 / 63.0 + 1e-6);
        assert_ne!(pack(&Sample { depth: 1.0, ..a }), EMPTY);
    }
}
