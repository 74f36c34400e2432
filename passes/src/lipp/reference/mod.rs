//! The ground truth for Lipp's pipeline (`scenes/graphs/lipp_reference.ron`,
//! docs/reference.md): the strands the hair mesh generates, every one at
//! full resolution, as ribbons of the groom's thickness, shaded with Lipp's
//! own model (§3.4: Chiang lobes, deep-opacity-map shadows, probe lighting)
//! and resolved by the reference's exact per-pixel blending
//! ([`crate::reference`]).
//!
//! Two passes of its own, on every backend:
//! 1. [`strands::STRANDS`]: per kept strand, Lipp's assembly (Code 1, the
//!    same as `lipp.raster`'s), every control point into `reference_points`
//!    and every segment's ribbon into `reference_ribbons`, counted in the
//!    8 × 8 tiles it may reach (what `reference.count` does for a groom);
//! 2. [`shade::SHADE`]: `lipp.shade`'s shading at every control point, into
//!    `vertex_lighting`.
//!
//! Then `reference.scan`, `reference.fill_strands` and `reference.resolve`
//! as for Kulikov.
//!
//! Strand `s` (numbered as the LOD keeps them) owns [`SLOTS`] consecutive
//! slots: point k of it is slot `s · SLOTS + k`, and so is its segment from
//! point k to k + 1. Slots past its C points (and past its C − 1 segments)
//! are left as the graph cleared them: not drawn.
//!
//! Where this differs from `lipp.ron` on purpose: the shading is evaluated
//! at the control points and interpolated along each segment, where
//! `lipp.shade` shades each pixel's sample; both evaluate the same function
//! at the same kind of point (position, tangent, strand identity, AO), and a
//! full-resolution segment spans a few pixels at the close view.

pub mod shade;
pub mod strands;

use crate::kernel::Words;
use crate::lipp::MAX_CONTROL_POINTS;

/// Slots per strand: one per control point.
pub const SLOTS: u32 = MAX_CONTROL_POINTS;

/// Words of a point's record in `reference_points`.
pub const POINT_WORDS: usize = 8;

/// The record's model index sits above the strand's (u, v).
pub const MODEL_SHIFT: u32 = 12;

/// Marks a written point (the graph clears the buffer).
pub const VALID: u32 = 1 << 31;

/// A strand's control point as the reference shades it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointRecord {
    pub pos: [f32; 3],
    pub ao: f32,
    pub tangent: [f32; 3],
    /// The strand's (u, v) in 1/63 steps (what the G-buffer keeps).
    pub strand: [u32; 2],
    /// Index into `models` (the material).
    pub model: u32,
}

impl PointRecord {
    pub fn store(&self, w: &Words<'_>, slot: usize) {
        let b = slot * POINT_WORDS;
        for (i, v) in self.pos.into_iter().chain([self.ao]).enumerate() {
            w.store_f32(b + i, v);
        }
        for (i, v) in self.tangent.into_iter().enumerate() {
            w.store_f32(b + 4 + i, v);
        }
        w.store(b + 7, self.packed());
    }

    /// The point at `slot`, `None` where none was written.
    pub fn load(w: &Words<'_>, slot: usize) -> Option<Self> {
        let b = slot * POINT_WORDS;
        let packed = w.load(b + 7);
        if packed & VALID == 0 {
            return None;
        }
        let f = |i: usize| w.load_f32(b + i);
        Some(Self {
            pos: [f(0), f(1), f(2)],
            ao: f(3),
            tangent: [f(4), f(5), f(6)],
            strand: [packed & 63, (packed >> 6) & 63],
            model: (packed & !VALID) >> MODEL_SHIFT,
        })
    }

    fn packed(&self) -> u32 {
        (self.strand[0] & 63) | (self.strand[1] & 63) << 6 | self.model << MODEL_SHIFT | VALID
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_survives_its_record_and_an_empty_slot_reads_as_none() {
        use std::sync::atomic::{AtomicU32, AtomicU64};
        let words: Vec<AtomicU32> = (0..2 * POINT_WORDS).map(|_| AtomicU32::new(0)).collect();
        let oob = AtomicU64::new(0);
        let w = Words::new(&words, &oob);
        let p = PointRecord {
            pos: [0.1, 1.5, -0.2],
            ao: 0.75,
            tangent: [0.0, -1.0, 0.0],
            strand: [63, 7],
            model: 3,
        };
        p.store(&w, 1);
        assert_eq!(PointRecord::load(&w, 1), Some(p));
        assert_eq!(PointRecord::load(&w, 0), None);
    }
}
