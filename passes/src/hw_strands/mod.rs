//! Hardware-rasterized strands: the baseline Lipp et al. measure their
//! software rasterizer against (their Table 1 compares with the mesh-shader
//! pipeline of Bhokare et al. 2024 at MSAA 1, 2, 4 and 8).
//!
//! The strands are Lipp's: the same LOD prepass (`lipp.lod`), the same
//! cooperative assembly (Code 1, [`crate::lipp::assemble`]), the same
//! G-buffer payload, shading (`lipp.shade`) and resolve (`lipp.filter` in
//! its MSAA mode), so between `scenes/graphs/hw_strands.ron` and
//! `scenes/graphs/lipp_msaa.ron` only visibility differs:
//!
//! - [`assemble`]: one workgroup per strand the LOD keeps writes its
//!   segments, projected once per control point, as [`Segment`] records and
//!   counts them into an indirect draw;
//! - [`raster`]: the hardware rasterizer draws each segment as a
//!   camera-facing quad `width` pixels wide, at as many samples as the
//!   depth attachment has (the graph's `strand_depth.samples`), with early
//!   depth tests; the fragment shader writes each covered sample's G-buffer
//!   layer with 64-bit `atomicMin`, as Lipp's MSAA reference mode does.
//!
//! - [`mesh`]: the same quads generated in mesh shaders (a task workgroup
//!   per bundle applying its LOD, strands assembled in mesh workgroups),
//!   the pipeline shape of Bhokare et al. 2024 (`hw_mesh.ron`).
//!
//! Deviation: Bhokare et al. shade forward; both paths here write Lipp's
//! G-buffer, so only visibility differs from Lipp's pipeline. The CPU
//! kernels emulate the hardware with [`crate::hardware_raster`] at the
//! standard sample locations.

pub mod assemble;
pub mod mesh;
pub mod raster;
#[cfg(test)]
mod raster_tests;

use glam::{Vec2, Vec4};

/// Words per segment record (`hw_segments`): end a's clip position, end
/// b's, then two words of payload bits ([`Segment`]).
pub const SEGMENT_WORDS: usize = 10;
/// Most segments one strand has (Lipp's largest control-point count − 1).
pub const MAX_SEGMENTS: u32 = crate::lipp::MAX_CONTROL_POINTS - 1;
/// Vertices the draw spends per segment (two triangles, no index buffer).
pub const VERTICES_PER_SEGMENT: u32 = 6;

/// One segment as the hardware rasterizer draws it. `bits_a` is
/// `payload::pack`'s low word at end a (octahedral tangent y, u, v, w, AO);
/// `bits_b` holds the tangent's x (bits 0-7) and end b's w (8-13) and AO
/// (14-19); the fragment shader interpolates w and AO and adds the depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub a: Vec4,
    pub b: Vec4,
    pub bits_a: u32,
    pub bits_b: u32,
}

impl Segment {
    pub fn words(&self) -> [u32; SEGMENT_WORDS] {
        let mut w = [0; SEGMENT_WORDS];
        for k in 0..4 {
            w[k] = self.a[k].to_bits();
            w[4 + k] = self.b[k].to_bits();
        }
        w[8] = self.bits_a;
        w[9] = self.bits_b;
        w
    }

    pub fn from_words(w: &[u32]) -> Self {
        let v = |o: usize| Vec4::from_array([0, 1, 2, 3].map(|k| f32::from_bits(w[o + k])));
        Self {
            a: v(0),
            b: v(4),
            bits_a: w[8],
            bits_b: w[9],
        }
    }

    /// The payload of a fragment at parameter `t` and NDC depth `z`
    /// (`payload::pack`'s layout).
    pub fn payload(&self, t: f32, z: f32) -> u64 {
        use crate::lipp::payload::{depth_bits, quantize};
        let lerp6 = |a: u32, b: u32| {
            let (a, b) = ((a & 63) as f32, (b & 63) as f32);
            quantize((a + (b - a) * t) / 63.0, 63.0)
        };
        let w = lerp6(self.bits_a >> 6, self.bits_b >> 8);
        let ao = lerp6(self.bits_a, self.bits_b >> 14);
        let lo = (self.bits_a & 0xFFFF_F000) | (w << 6) | ao;
        let hi = (depth_bits(z) << 8) | (self.bits_b & 255);
        (u64::from(hi) << 32) | u64::from(lo)
    }
}

/// Which end (bit 0: b) and side (bit 1: +) each of a segment's six
/// vertices takes: triangles (a−, b−, a+) and (a+, b−, b+).
pub const CORNERS: [u32; 6] = [0, 1, 2, 2, 1, 3];

/// Corner `corner` of the quad of segment (a, b) in clip space: `half`
/// pixels either side of the projected segment and past each end (square
/// caps, so the quads of a bent strand leave no gaps).
pub fn quad_corner(a: Vec4, b: Vec4, corner: u32, half: f32, size: Vec2) -> Vec4 {
    let pixels = |c: Vec4| Vec2::new(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5) * size;
    let d = pixels(b) - pixels(a);
    let len = d.length();
    let dir = if len > 1e-6 { d / len } else { Vec2::X };
    let normal = Vec2::new(-dir.y, dir.x);
    let along = if corner & 1 != 0 { half } else { -half };
    let across = if corner & 2 != 0 { half } else { -half };
    let offset = dir * along + normal * across;
    let c = if corner & 1 != 0 { b } else { a };
    let ndc = Vec2::new(offset.x * 2.0 / size.x, -offset.y * 2.0 / size.y);
    Vec4::new(c.x + ndc.x * c.w, c.y + ndc.y * c.w, c.z, c.w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip_and_payloads_interpolate_w_and_ao() {
        let s = Segment {
            a: Vec4::new(0.1, -0.2, 0.3, 1.5),
            b: Vec4::new(-0.4, 0.5, 0.6, 2.5),
            // w 0 at end a, AO 63.
            bits_a: (7 << 24) | (5 << 18) | (9 << 12) | 63,
            bits_b: 200 | (63 << 8),
        };
        assert_eq!(Segment::from_words(&s.words()), s);
        let at = |t: f32| crate::lipp::payload::unpack(s.payload(t, 0.25));
        assert!(at(0.0).uvw[2] < 0.01 && at(1.0).uvw[2] > 0.99);
        assert!(at(0.0).ao > 0.99 && at(1.0).ao < 0.01);
        assert!((at(0.5).uvw[2] - 0.5).abs() < 0.02);
        assert!((at(0.5).depth - 0.25).abs() < 1e-6);
    }

    #[test]
    fn quads_face_the_camera_with_the_requested_width() {
        let size = Vec2::new(100.0, 50.0);
        // A horizontal segment from pixel (20, 25) to (80, 25), w = 2.
        let a = Vec4::new(-0.6 * 2.0, 0.0, 0.5, 2.0);
        let b = Vec4::new(0.6 * 2.0, 0.0, 0.5, 2.0);
        let px = |c: Vec4| Vec2::new(c.x / c.w * 0.5 + 0.5, 0.5 - c.y / c.w * 0.5) * size;
        let corners: Vec<Vec2> = (0..4)
            .map(|k| px(quad_corner(a, b, k, 0.5, size)))
            .collect();
        for (k, c) in corners.iter().enumerate() {
            let end = if k & 1 != 0 { 80.5 } else { 19.5 };
            let side = if k & 2 != 0 { 25.5 } else { 24.5 };
            assert!(
                (c.x - end).abs() < 1e-4 && (c.y - side).abs() < 1e-4,
                "{k}: {c}"
            );
        }
    }
}
