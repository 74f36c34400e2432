//! A hair segment as the reference sees it: the camera-facing ribbon of the
//! strand's thickness around its projected centreline, with round joins.
//!
//! A cylinder of radius r seen from the camera covers, at each point of its
//! axis, a disk of the projected radius: the union of those disks along a
//! segment is a capsule whose radius varies linearly from one end to the
//! other. The reference tests samples against that swept disk, so
//! consecutive segments of a strand meet without gaps or seams at a bend;
//! at the root and the tip the end is cut flat (no cap beyond the strand).
//! The same arithmetic, in the same order, is `shaders/reference/ribbon.wgsl`.

use crate::common::clip::{at, near_clip};
use crate::kernel::Words;
use crate::kulikov::clip_to_screen;
use crate::layout::FrameData;

/// One segment in screen pixels (y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ribbon {
    pub a: [f32; 2],
    pub b: [f32; 2],
    /// Half widths in pixels at `a` and `b`.
    pub ha: f32,
    pub hb: f32,
    /// View depths (clip w) at `a` and `b`.
    pub wa: f32,
    pub wb: f32,
    /// Whether the strand continues beyond `a` / `b` (a round join there).
    pub join_a: bool,
    pub join_b: bool,
    /// The parameters of `a` and `b` along the segment: `[0, 1]` unless
    /// the near plane cuts one end (`common::clip`).
    pub range: [f32; 2],
}

/// Pixels per sample grid cell are never finer than this: 16 × 16.
pub const MAX_SAMPLES_PER_AXIS: u32 = 16;

/// Words of a segment's record in `reference_ribbons`: the ribbon, its end
/// vertices, flags (bit 0 drawn, bit 1 joined at `a`, bit 2 at `b`, bit 3
/// `a` cut by the near plane, bit 4 `b` cut) and the cut end's parameter.
pub const RECORD_WORDS: usize = 12;

/// A drawn segment's ribbon and end vertices, as `reference.count` stores
/// them for the passes after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    pub ribbon: Ribbon,
    pub vertices: [u32; 2],
}

impl Record {
    /// Stores `record` (or, for `None`, a segment that is not drawn) at `id`.
    pub fn store(record: Option<&Record>, w: &Words<'_>, id: usize) {
        let b = id * RECORD_WORDS;
        let Some(Record {
            ribbon: r,
            vertices,
        }) = record
        else {
            (b..b + RECORD_WORDS).for_each(|i| w.store(i, 0));
            return;
        };
        for (i, v) in [r.a[0], r.a[1], r.b[0], r.b[1], r.ha, r.hb, r.wa, r.wb]
            .into_iter()
            .enumerate()
        {
            w.store_f32(b + i, v);
        }
        w.store(b + 8, vertices[0]);
        w.store(b + 9, vertices[1]);
        // The near plane cuts at most one end.
        let (cut_a, cut_b) = (r.range[0] != 0.0, r.range[1] != 1.0);
        w.store(
            b + 10,
            1 | u32::from(r.join_a) << 1
                | u32::from(r.join_b) << 2
                | u32::from(cut_a) << 3
                | u32::from(cut_b) << 4,
        );
        let cut = if cut_a {
            r.range[0]
        } else if cut_b {
            r.range[1]
        } else {
            0.0
        };
        w.store_f32(b + 11, cut);
    }

    /// The record of segment `id`, `None` when it is not drawn.
    pub fn load(w: &Words<'_>, id: usize) -> Option<Record> {
        let b = id * RECORD_WORDS;
        let flags = w.load(b + 10);
        if flags & 1 == 0 {
            return None;
        }
        let f = |i: usize| w.load_f32(b + i);
        Some(Record {
            ribbon: Ribbon {
                a: [f(0), f(1)],
                b: [f(2), f(3)],
                ha: f(4),
                hb: f(5),
                wa: f(6),
                wb: f(7),
                join_a: flags & 2 != 0,
                join_b: flags & 4 != 0,
                range: [
                    if flags & 8 != 0 { f(11) } else { 0.0 },
                    if flags & 16 != 0 { f(11) } else { 1.0 },
                ],
            },
            vertices: [w.load(b + 8), w.load(b + 9)],
        })
    }
}

impl Ribbon {
    /// The part in front of the near plane ([`near_clip`]) of the segment
    /// from clip position `c0` to `c1` with world thicknesses `t0`, `t1`;
    /// `None` when no part is (the skinning pass leaves skipped vertices at
    /// w = 0). A cut end is flat: no join beyond the plane.
    pub fn new(
        frame: &FrameData,
        c0: [f32; 4],
        c1: [f32; 4],
        t0: f32,
        t1: f32,
        join_a: bool,
        join_b: bool,
    ) -> Option<Self> {
        let part = near_clip(c0, c1, frame.near)?;
        let (c0, c1) = (part.a, part.b);
        let [t0, t1] = part.ends(t0, t1);
        let (sa, sb) = (
            clip_to_screen(c0, frame.screen[0], frame.screen[1]),
            clip_to_screen(c1, frame.screen[0], frame.screen[1]),
        );
        Some(Self {
            a: [sa[0], sa[1]],
            b: [sb[0], sb[1]],
            ha: 0.5 * t0 * frame.pixels_per_unit / c0[3],
            hb: 0.5 * t1 * frame.pixels_per_unit / c1[3],
            wa: c0[3],
            wb: c1[3],
            join_a: join_a && part.ta == 0.0,
            join_b: join_b && part.tb == 1.0,
            range: [part.ta, part.tb],
        })
    }

    /// Where `p` projects on the axis, 0 at `a` and 1 at `b` (0 for a
    /// segment seen end-on).
    pub fn axis(&self, p: [f32; 2]) -> f32 {
        let d = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        if len2 > 1e-12 {
            ((p[0] - self.a[0]) * d[0] + (p[1] - self.a[1]) * d[1]) / len2
        } else {
            0.0
        }
    }

    /// Squared distance from `p` to the axis point at `t` (in [0, 1]) and
    /// the radius there.
    fn gap(&self, p: [f32; 2], t: f32) -> (f32, f32) {
        let q = [
            self.a[0] + t * (self.b[0] - self.a[0]),
            self.a[1] + t * (self.b[1] - self.a[1]),
        ];
        let (dx, dy) = (p[0] - q[0], p[1] - q[1]);
        (dx * dx + dy * dy, self.ha + t * (self.hb - self.ha))
    }

    /// The axis parameter (in [0, 1]) where the ribbon covers `p`, or `None`.
    pub fn covers(&self, p: [f32; 2]) -> Option<f32> {
        let t = self.axis(p);
        if (t < 0.0 && !self.join_a) || (t > 1.0 && !self.join_b) {
            return None;
        }
        let t = t.clamp(0.0, 1.0);
        let (d2, r) = self.gap(p, t);
        (d2 < r * r).then_some(t)
    }

    /// Whether the ribbon may reach the square of half edge `half` centred
    /// at `c` (conservative: the square's circumscribed disk).
    pub fn may_touch(&self, c: [f32; 2], half: f32) -> bool {
        let t = self.axis(c).clamp(0.0, 1.0);
        let (d2, _) = self.gap(c, t);
        let reach = self.ha.max(self.hb) + half * std::f32::consts::SQRT_2;
        d2 <= reach * reach
    }

    /// Screen bounds `[x0, y0, x1, y1]` of everything the ribbon can cover.
    pub fn bounds(&self) -> [f32; 4] {
        let r = self.ha.max(self.hb);
        [
            self.a[0].min(self.b[0]) - r,
            self.a[1].min(self.b[1]) - r,
            self.a[0].max(self.b[0]) + r,
            self.a[1].max(self.b[1]) + r,
        ]
    }

    /// View depth at screen-space axis parameter `t`: 1/w is linear in
    /// screen space (perspective-correct).
    pub fn depth_at(&self, t: f32) -> f32 {
        1.0 / ((1.0 - t) / self.wa + t / self.wb)
    }

    /// The perspective-correct parameter along the world segment at
    /// screen-space parameter `t`, for interpolating vertex attributes
    /// (through `range` when the near plane cut an end).
    pub fn world_t(&self, t: f32) -> f32 {
        let (ia, ib) = ((1.0 - t) / self.wa, t / self.wb);
        at(self.range[0], self.range[1], ib / (ia + ib))
    }
}

/// A small integer hash (two rounds of a PCG-style mix).
pub fn hash2(a: u32, b: u32) -> u32 {
    let mut h = a.wrapping_mul(0x8da6_b343) ^ b.wrapping_mul(0xd816_3841);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^ (h >> 15)
}

/// Sample `s` of the `n × n` stratified pattern of pixel `(x, y)`, in
/// screen pixels: one jittered sample per cell of an n × n grid, the jitter
/// hashed from the pixel and the cell so every backend places it alike.
pub fn sample_position(x: u32, y: u32, width: u32, n: u32, s: u32) -> [f32; 2] {
    let h = hash2(y * width + x, s);
    let (jx, jy) = (
        (h & 0xFFFF) as f32 * (1.0 / 65536.0),
        (h >> 16) as f32 * (1.0 / 65536.0),
    );
    let inv = 1.0 / n as f32;
    [
        x as f32 + ((s % n) as f32 + jx) * inv,
        y as f32 + ((s / n) as f32 + jy) * inv,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(a: [f32; 2], b: [f32; 2], h: f32) -> Ribbon {
        Ribbon {
            a,
            b,
            ha: h,
            hb: h,
            wa: 1.0,
            wb: 1.0,
            range: [0.0, 1.0],
            join_a: false,
            join_b: false,
        }
    }

    #[test]
    fn covers_a_band_of_the_thickness_and_cuts_unjoined_ends() {
        let r = flat([10.0, 10.0], [30.0, 10.0], 0.5);
        assert_eq!(r.covers([20.0, 10.4]), Some(0.5));
        assert_eq!(r.covers([20.0, 10.6]), None);
        // Past the tip: cut flat, unless the strand goes on.
        assert_eq!(r.covers([30.2, 10.0]), None);
        let joined = Ribbon { join_b: true, ..r };
        assert_eq!(joined.covers([30.2, 10.0]), Some(1.0));
        assert_eq!(joined.covers([30.6, 10.0]), None);
    }

    #[test]
    fn a_segment_seen_end_on_is_a_disk() {
        let r = Ribbon {
            join_a: true,
            ..flat([5.0, 5.0], [5.0, 5.0], 1.0)
        };
        assert_eq!(r.covers([5.5, 5.5]), Some(0.0));
        assert_eq!(r.covers([6.0, 6.0]), None);
    }

    #[test]
    fn stratified_samples_fill_their_cells() {
        let n = 8;
        let mut cells = vec![false; (n * n) as usize];
        for s in 0..n * n {
            let p = sample_position(3, 7, 100, n, s);
            assert!(p[0] >= 3.0 && p[0] < 4.0 && p[1] >= 7.0 && p[1] < 8.0);
            let (cx, cy) = (((p[0] - 3.0) * 8.0) as usize, ((p[1] - 7.0) * 8.0) as usize);
            cells[cy * n as usize + cx] = true;
        }
        assert!(cells.iter().all(|&c| c), "a cell has no sample");
        assert_ne!(
            sample_position(3, 7, 100, n, 0),
            sample_position(4, 7, 100, n, 0)
        );
    }

    #[test]
    fn depth_and_attributes_interpolate_perspective_correctly() {
        let r = Ribbon {
            wa: 1.0,
            wb: 3.0,
            ..flat([0.0, 0.0], [10.0, 0.0], 1.0)
        };
        // Halfway on screen is a quarter of the way in the world.
        assert!((r.world_t(0.5) - 0.25).abs() < 1e-6);
        assert!((r.depth_at(0.5) - 1.5).abs() < 1e-6);
        assert_eq!(r.depth_at(0.0), 1.0);
    }

    #[test]
    fn the_near_plane_cuts_a_crossing_segment_flat() {
        use bytemuck::Zeroable;
        let mut f = FrameData::zeroed();
        f.screen = [100.0, 100.0, 0.01, 0.01];
        f.near = 0.5;
        f.pixels_per_unit = 100.0;
        // From w = 2.5 in front to w = -1.5 behind: the plane cuts at t = 1/2.
        let (front, behind) = ([0.0, 0.0, 1.0, 2.5], [1.0, 0.0, -1.0, -1.5]);
        let r = Ribbon::new(&f, front, behind, 0.01, 0.03, true, true).unwrap();
        assert_eq!((r.range, r.wa, r.wb), ([0.0, 0.5], 2.5, 0.5));
        assert!(r.join_a && !r.join_b, "the cut end has no join");
        // Thickness 0.02 at the cut, 0.5 px per 0.01 at w = 0.5.
        assert!((r.hb - 0.5 * 0.02 * 100.0 / 0.5).abs() < 1e-6, "{}", r.hb);
        // Attributes run over the part in front: its cut end is halfway.
        assert_eq!(r.world_t(1.0), 0.5);
        let back = Ribbon::new(&f, behind, front, 0.03, 0.01, true, true).unwrap();
        assert_eq!(back.range, [0.5, 1.0]);
        assert!(!back.join_a && back.join_b);
        // Records keep the cut: the store and load round-trip it.
        use std::sync::atomic::{AtomicU32, AtomicU64};
        let (words, oob) = (
            (0..RECORD_WORDS)
                .map(|_| AtomicU32::new(0))
                .collect::<Vec<_>>(),
            AtomicU64::new(0),
        );
        let w = Words::new(&words, &oob);
        for ribbon in [r, back] {
            let rec = Record {
                ribbon,
                vertices: [3, 4],
            };
            Record::store(Some(&rec), &w, 0);
            assert_eq!(Record::load(&w, 0), Some(rec));
        }
        assert_eq!(
            Ribbon::new(&f, behind, [0.0, 0.0, 0.0, 0.2], 0.01, 0.01, true, true),
            None
        );
    }
}
