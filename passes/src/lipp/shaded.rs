//! `shaded`: what `lipp.shade` hands `lipp.filter`, one 8-byte record per
//! pixel and G-buffer layer, planar like the G-buffer (slot
//! `layer · pixels + pixel`).
//!
//! | word | bits  | field                                               |
//! |------|-------|-----------------------------------------------------|
//! | 0    | 31..0 | radiance, RGB9E5 (Vulkan's `E5B9G9R9_UFLOAT_PACK32`) |
//! | 1    | 31..8 | the sample's 24-bit NDC depth (the payload's)       |
//! | 1    | 2     | a flyaway: the conservative sample lies in front    |
//! | 1    | 1     | the pixel's conservative layer has a sample         |
//! | 1    | 0     | this layer has a sample                             |
//!
//! Why (ours; Lipp §3.3 does not say how the filter reads its inputs): the
//! filter's (2r + 1)² window is its whole cost, and each tap needs only the
//! neighbour's two hit flags, its depth and its colour. From the G-buffer
//! and an rgba32f colour that was three loads and 32 bytes a tap; from the
//! centre layer's record it is one load of 8. The centre layer's record is
//! written for every pixel (flags 0 where no strand is), so a tap outside
//! the tiles with hair reads this frame's emptiness; other layers' records
//! only where they hold a sample, and only the pixel itself reads them.
//!
//! RGB9E5 keeps 9 bits of mantissa under a shared exponent: a channel is
//! off by at most half a step of the brightest channel (2⁻¹⁰ of it), below
//! the 10-bit mantissa of the rgba16f target the filter blends into. The
//! exponent is read from the float's bits rather than `log2`, so CPU and
//! WGSL pack the same bits.

use super::filter::linear_depth;
use super::payload::EMPTY;
use crate::layout::FrameData;

/// Mantissa bits (N) and exponent bias (B) of RGB9E5.
const MANTISSA: i32 = 9;
const BIAS: i32 = 15;
/// The largest value RGB9E5 holds: (2⁹ − 1) / 2⁹ · 2^(31 − 15).
pub const RGB9E5_MAX: f32 = 65_408.0;

/// Word 1's flags.
pub const HIT: u32 = 1;
pub const CONS_HIT: u32 = 2;
/// The pixel has both samples and the conservative one lies at least
/// `lipp.shade`'s `front_threshold` (metres, linear depth) in front of the
/// centre one: a flyaway, whose reconstruction `lipp.filter` blends over
/// the centre colour (Lipp §3.3.2). The shade decides it because it then
/// knows which layers the filter reads ([`read_by_filter`]).
pub const FRONT: u32 = 4;

/// 2^k as an f32, exactly (k in −126..=127).
fn exp2i(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// floor(log2(x)) of a non-negative normal x (or zero), from its exponent bits.
fn floor_log2(x: f32) -> i32 {
    ((x.to_bits() >> 23) & 0xFF) as i32 - 127
}

/// EXT_texture_shared_exponent's packing: negative and NaN channels are 0,
/// larger ones [`RGB9E5_MAX`].
pub fn pack_rgb9e5(c: [f32; 3]) -> u32 {
    // `max` returns the other operand for NaN: NaN becomes 0.
    let c = c.map(|v| 0.0f32.max(v).min(RGB9E5_MAX));
    let m = c[0].max(c[1]).max(c[2]);
    // Zero's bits give −127: the smallest exponent, as for anything below 2⁻¹⁶.
    let mut e = floor_log2(m).max(-BIAS - 1) + 1 + BIAS;
    if ((m * exp2i(BIAS + MANTISSA - e)) + 0.5).floor() >= 512.0 {
        e += 1;
    }
    let scale = exp2i(BIAS + MANTISSA - e);
    let q = c.map(|v| ((v * scale) + 0.5).floor() as u32);
    q[0] | (q[1] << 9) | (q[2] << 18) | ((e as u32) << 27)
}

pub fn unpack_rgb9e5(w: u32) -> [f32; 3] {
    let scale = exp2i((w >> 27) as i32 - BIAS - MANTISSA);
    [w & 511, (w >> 9) & 511, (w >> 18) & 511].map(|q| q as f32 * scale)
}

/// The record of a layer's sample: colour, the payload's high word (its
/// depth in bits 31..8) and the flags.
pub fn record(color: [f32; 3], payload_hi: u32, flags: u32) -> [u32; 2] {
    [pack_rgb9e5(color), (payload_hi & !0xFF) | flags]
}

/// A record's NDC depth.
pub fn depth(word1: u32) -> f32 {
    (word1 >> 8) as f32 * super::payload::INV_DEPTH_MAX
}

/// The pixel's flags in every record of it: [`CONS_HIT`] and [`FRONT`],
/// from its centre and conservative payloads.
pub fn pixel_flags(f: &FrameData, centre: u64, cons: u64, front_threshold: f32) -> u32 {
    if cons == EMPTY {
        return 0;
    }
    let front = centre != EMPTY && {
        let d = |p: u64| linear_depth(f, depth((p >> 32) as u32));
        d(cons) <= d(centre) - front_threshold
    };
    CONS_HIT | if front { FRONT } else { 0 }
}

/// Whether `lipp.filter` reads the colour of sample layer `layer` of
/// `layers` at a pixel with `flags` whose centre layer has a sample or not
/// (filter::filter_pixel): a conservative sample only where it is promoted
/// (no centre sample, §3.3.2) or lies in front; every sample of the MSAA
/// reference's layers.
pub fn read_by_filter(layer: u32, layers: u32, centre_hit: bool, flags: u32) -> bool {
    layer != 1 || layers > 2 || !centre_hit || flags & FRONT != 0
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn rgb9e5_round_trips_within_half_a_step_of_the_brightest_channel() {
        for c in [
            [1.0, 0.5, 0.25],
            [0.013, 0.0071, 0.0029],
            [3.7, 0.0, 120.0],
            [0.0, 0.0, 0.0],
            [1e-7, 2e-6, 0.0],
            [65_000.0, 1.0, 0.5],
        ] {
            let u = unpack_rgb9e5(pack_rgb9e5(c));
            let m = c[0].max(c[1]).max(c[2]);
            let e = floor_log2(m).max(-16) + 1;
            let half_step = exp2i(e - MANTISSA - 1);
            for k in 0..3 {
                assert!((u[k] - c[k]).abs() <= half_step * 1.0001, "{c:?} -> {u:?}");
            }
        }
    }

    #[test]
    fn rgb9e5_matches_the_specs_bits() {
        // 1.0: exponent 16 (2^(16-15-9) = 2^-8 a step), mantissa 256.
        assert_eq!(pack_rgb9e5([1.0, 0.0, 0.0]), 256 | (16 << 27));
        // A mantissa that rounds up to 512 moves to the next exponent.
        let w = pack_rgb9e5([0.9995, 0.0, 0.0]);
        assert_eq!((w >> 27, w & 511), (16, 256));
        assert_eq!(unpack_rgb9e5(pack_rgb9e5([RGB9E5_MAX; 3])), [RGB9E5_MAX; 3]);
        assert_eq!(
            unpack_rgb9e5(pack_rgb9e5([-1.0, f32::NAN, 1e9])),
            [0.0, 0.0, RGB9E5_MAX]
        );
    }

    /// A payload at `metres` of linear view depth (any tangent and uvw).
    pub(crate) fn payload_at(f: &FrameData, metres: f32) -> u64 {
        use super::super::filter::ndc_depth;
        use super::super::payload::{Sample, pack};
        pack(&Sample {
            depth: ndc_depth(f, metres),
            tangent: [1.0, 0.0, 0.0],
            uvw: [0.5; 3],
            ao: 1.0,
        })
    }

    /// A conservative sample 1 cm (the default threshold) or more in front
    /// of the centre one is a flyaway; nearer, behind or alone it is not.
    #[test]
    fn front_is_set_by_the_linear_depth_gap() {
        let f = super::super::raster::tests::frame();
        let at = |metres| payload_at(&f, metres);
        let flags = |centre, cons| pixel_flags(&f, centre, cons, 0.01);
        assert_eq!(flags(at(0.7), at(0.68)), CONS_HIT | FRONT);
        assert_eq!(flags(at(0.7), at(0.695)), CONS_HIT);
        assert_eq!(flags(at(0.7), at(0.75)), CONS_HIT);
        assert_eq!(flags(EMPTY, at(0.5)), CONS_HIT);
        assert_eq!(flags(at(0.7), EMPTY), 0);
        // The filter reads a conservative colour where promoted or in front.
        assert!(read_by_filter(1, 2, false, CONS_HIT));
        assert!(read_by_filter(1, 2, true, CONS_HIT | FRONT));
        assert!(!read_by_filter(1, 2, true, CONS_HIT));
        assert!(read_by_filter(1, 4, true, CONS_HIT) && read_by_filter(0, 2, true, 0));
    }

    #[test]
    fn record_keeps_the_payloads_depth_and_the_flags() {
        let hi = (0x12_3456 << 8) | 0xAB;
        let r = record([0.5, 0.25, 0.125], hi, HIT | CONS_HIT);
        assert_eq!(r[1] >> 8, 0x12_3456);
        assert_eq!(r[1] & 0xFF, HIT | CONS_HIT);
        assert_eq!(unpack_rgb9e5(r[0]), [0.5, 0.25, 0.125]);
        assert!((depth(r[1]) - 0x12_3456 as f32 / 16_777_215.0).abs() < 1e-7);
    }
}
