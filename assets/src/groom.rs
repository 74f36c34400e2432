//! The strand groom: structure-of-arrays strands of varying point counts.

use glam::{Vec2, Vec3};

use crate::bounds::Aabb;
use crate::transform::Transform;

/// A groom as structure-of-arrays. Strand `s` owns points
/// `strand_offsets[s]..strand_offsets[s + 1]`; `strand_offsets` has `strands + 1` entries.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Groom {
    /// Point positions in metres, in the groom's local space.
    pub positions: Vec<Vec3>,
    /// Per-point strand thickness (diameter) in metres.
    pub thickness: Vec<f32>,
    /// Optional per-point linear RGB colour.
    pub colors: Option<Vec<Vec3>>,
    /// Optional per-point transparency (cyHair), 0 = opaque.
    pub transparency: Option<Vec<f32>>,
    /// Optional per-strand UV (for example the scalp texture coordinate of the root).
    pub strand_uvs: Option<Vec<Vec2>>,
    /// Prefix offsets into the point arrays; `strands + 1` entries, starting at 0.
    pub strand_offsets: Vec<u32>,
    /// Local-to-world placement.
    pub transform: Transform,
}

/// Default strand thickness when a file gives none: 80 micrometres.
pub const DEFAULT_THICKNESS: f32 = 80e-6;

impl Groom {
    /// Builds a groom from per-strand point lists with a constant thickness.
    pub fn from_strands<I, S>(strands: I, thickness: f32) -> Groom
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[Vec3]>,
    {
        let mut g = Groom {
            strand_offsets: vec![0],
            ..Default::default()
        };
        for s in strands {
            g.positions.extend_from_slice(s.as_ref());
            g.strand_offsets.push(g.positions.len() as u32);
        }
        g.thickness = vec![thickness; g.positions.len()];
        g
    }

    pub fn strand_count(&self) -> usize {
        self.strand_offsets.len().saturating_sub(1)
    }
    pub fn point_count(&self) -> usize {
        self.positions.len()
    }
    /// Segments: each strand of n points has n - 1.
    pub fn segment_count(&self) -> usize {
        self.point_count().saturating_sub(self.strand_count())
    }
    /// The point range of strand `s`.
    pub fn strand_range(&self, s: usize) -> std::ops::Range<usize> {
        self.strand_offsets[s] as usize..self.strand_offsets[s + 1] as usize
    }
    pub fn strand(&self, s: usize) -> &[Vec3] {
        &self.positions[self.strand_range(s)]
    }
    /// The number of points per strand if all strands have the same count.
    pub fn uniform_points_per_strand(&self) -> Option<usize> {
        let n = self.strand_range(0).len();
        (0..self.strand_count())
            .all(|s| self.strand_range(s).len() == n)
            .then_some(n)
    }
    /// The most points of any strand (0 for a groom without strands).
    pub fn max_points_per_strand(&self) -> u32 {
        self.strand_offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0)
    }
    pub fn roots(&self) -> Vec<Vec3> {
        (0..self.strand_count())
            .map(|s| self.positions[self.strand_offsets[s] as usize])
            .collect()
    }

    /// Local-space bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
    /// World-space bounding box (local box under the groom transform).
    pub fn world_bounds(&self) -> Aabb {
        self.bounds().transformed(&self.transform.matrix())
    }

    /// Bytes held by the arrays.
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * 12
            + self.thickness.len() * 4
            + self.colors.as_ref().map_or(0, |c| c.len() * 12)
            + self.transparency.as_ref().map_or(0, |c| c.len() * 4)
            + self.strand_uvs.as_ref().map_or(0, |c| c.len() * 8)
            + self.strand_offsets.len() * 4
    }

    /// Checks the structural invariants; returns a description of the first violation.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.positions.len();
        if self.strand_offsets.first() != Some(&0) {
            return Err("strand_offsets must start at 0".into());
        }
        if self.strand_offsets.windows(2).any(|w| w[1] <= w[0]) {
            return Err("every strand needs at least one point".into());
        }
        if self.strand_offsets.last().map(|&l| l as usize) != Some(n) {
            return Err("strand_offsets must end at the point count".into());
        }
        if self.thickness.len() != n {
            return Err("thickness length differs from point count".into());
        }
        if self.colors.as_ref().is_some_and(|c| c.len() != n)
            || self.transparency.as_ref().is_some_and(|c| c.len() != n)
        {
            return Err("per-point array length differs from point count".into());
        }
        if self
            .strand_uvs
            .as_ref()
            .is_some_and(|c| c.len() != self.strand_count())
        {
            return Err("strand UV count differs from strand count".into());
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("point {i} is not finite"));
        }
        Ok(())
    }

    /// Multiplies positions and thickness by `s` (unit conversion).
    pub fn scale_units(&mut self, s: f32) {
        self.positions.iter_mut().for_each(|p| *p *= s);
        self.thickness.iter_mut().for_each(|t| *t *= s);
    }

    /// A stable, seeded random permutation of the strand indices.
    /// Kulikov: "randomizing strands order ... take only a section of strands buffer" for LOD.
    /// Uses PCG32 and Lemire's bounded integers directly so the order never changes
    /// with the version of `rand`.
    pub fn shuffled_order(&self, seed: u64) -> Vec<u32> {
        stable_permutation(self.strand_count(), seed)
    }

    /// The groom with its strands in the order of `order` (a permutation or a subset).
    pub fn reordered(&self, order: &[u32]) -> Groom {
        let mut g = Groom {
            strand_offsets: Vec::with_capacity(order.len() + 1),
            transform: self.transform,
            ..Default::default()
        };
        g.strand_offsets.push(0);
        let mut colors = self.colors.as_ref().map(|_| Vec::new());
        let mut transp = self.transparency.as_ref().map(|_| Vec::new());
        for &s in order {
            let r = self.strand_range(s as usize);
            g.positions.extend_from_slice(&self.positions[r.clone()]);
            g.thickness.extend_from_slice(&self.thickness[r.clone()]);
            if let (Some(dst), Some(src)) = (colors.as_mut(), self.colors.as_ref()) {
                dst.extend_from_slice(&src[r.clone()]);
            }
            if let (Some(dst), Some(src)) = (transp.as_mut(), self.transparency.as_ref()) {
                dst.extend_from_slice(&src[r.clone()]);
            }
            g.strand_offsets.push(g.positions.len() as u32);
        }
        g.colors = colors;
        g.transparency = transp;
        g.strand_uvs = self
            .strand_uvs
            .as_ref()
            .map(|uv| order.iter().map(|&s| uv[s as usize]).collect());
        g
    }

    /// The groom with its strands shuffled by `shuffled_order(seed)`.
    pub fn shuffled(&self, seed: u64) -> Groom {
        self.reordered(&self.shuffled_order(seed))
    }

    /// LOD by strand-order prefix (Kulikov): the first `count` strands, with thickness
    /// scaled by sqrt(total / count) so that the covered area stays about the same.
    pub fn lod_prefix(&self, count: usize) -> Groom {
        let count = count.min(self.strand_count());
        let order: Vec<u32> = (0..count as u32).collect();
        let mut g = self.reordered(&order);
        if count > 0 {
            let k = (self.strand_count() as f32 / count as f32).sqrt();
            g.thickness.iter_mut().for_each(|t| *t *= k);
        }
        g
    }

    /// Resamples every strand to `n >= 2` points uniformly spaced in arc length.
    /// Thickness, colour and transparency are interpolated linearly.
    pub fn resampled(&self, n: usize) -> Groom {
        let n = n.max(2);
        let strands = self.strand_count();
        let mut g = Groom {
            positions: Vec::with_capacity(strands * n),
            thickness: Vec::with_capacity(strands * n),
            colors: self
                .colors
                .as_ref()
                .map(|_| Vec::with_capacity(strands * n)),
            transparency: self
                .transparency
                .as_ref()
                .map(|_| Vec::with_capacity(strands * n)),
            strand_uvs: self.strand_uvs.clone(),
            strand_offsets: (0..=strands).map(|s| (s * n) as u32).collect(),
            transform: self.transform,
        };
        for s in 0..strands {
            let r = self.strand_range(s);
            let pts = &self.positions[r.clone()];
            let samples = arc_length_samples(pts, n);
            for (i, t) in samples {
                let lerp3 = |a: &[Vec3]| {
                    let j = (i + 1).min(a.len() - 1);
                    a[i].lerp(a[j], t)
                };
                let lerp1 = |a: &[f32]| {
                    let j = (i + 1).min(a.len() - 1);
                    a[i] + (a[j] - a[i]) * t
                };
                g.positions.push(lerp3(pts));
                g.thickness.push(lerp1(&self.thickness[r.clone()]));
                if let (Some(d), Some(c)) = (g.colors.as_mut(), self.colors.as_ref()) {
                    d.push(lerp3(&c[r.clone()]));
                }
                if let (Some(d), Some(c)) = (g.transparency.as_mut(), self.transparency.as_ref()) {
                    d.push(lerp1(&c[r.clone()]));
                }
            }
        }
        g
    }
}

/// For `n` uniformly spaced arc-length positions along the polyline, the segment index and
/// the fraction within it.
pub fn arc_length_samples(pts: &[Vec3], n: usize) -> Vec<(usize, f32)> {
    let mut cum = Vec::with_capacity(pts.len());
    let mut acc = 0.0f32;
    cum.push(0.0);
    for w in pts.windows(2) {
        acc += (w[1] - w[0]).length();
        cum.push(acc);
    }
    let total = acc;
    let mut out = Vec::with_capacity(n);
    let mut seg = 0usize;
    for k in 0..n {
        if pts.len() < 2 || total <= 0.0 {
            out.push((0, 0.0));
            continue;
        }
        let target = total * k as f32 / (n - 1).max(1) as f32;
        while seg + 2 < pts.len() && cum[seg + 1] < target {
            seg += 1;
        }
        let len = cum[seg + 1] - cum[seg];
        let t = if len > 0.0 {
            ((target - cum[seg]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push((seg, t));
    }
    out
}

/// A stable permutation of `0..n` from a seed: Fisher-Yates driven by PCG32
/// (O'Neill's constants) with Lemire's multiply-shift bounded integers.
pub fn stable_permutation(n: usize, seed: u64) -> Vec<u32> {
    let mut v: Vec<u32> = (0..n as u32).collect();
    let mut rng = Pcg32::new(seed);
    for i in (1..n).rev() {
        let j = rng.below(i as u32 + 1) as usize;
        v.swap(i, j);
    }
    v
}

/// Minimal PCG32 (XSH RR), spelled out so that orders stay fixed forever.
pub struct Pcg32 {
    state: u64,
}

impl Pcg32 {
    const MUL: u64 = 6364136223846793005;
    const INC: u64 = 1442695040888963407;
    pub fn new(seed: u64) -> Self {
        let mut r = Pcg32 { state: 0 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MUL).wrapping_add(Self::INC);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }
    /// Uniform in `0..bound` (bound > 0), Lemire's method.
    pub fn below(&mut self, bound: u32) -> u32 {
        let mut m = self.next_u32() as u64 * bound as u64;
        if (m as u32) < bound {
            let threshold = bound.wrapping_neg() % bound;
            while (m as u32) < threshold {
                m = self.next_u32() as u64 * bound as u64;
            }
        }
        (m >> 32) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Groom {
        Groom::from_strands(
            (0..10).map(|s| {
                (0..(3 + s % 4))
                    .map(|i| Vec3::new(s as f32, i as f32 * 0.1, 0.0))
                    .collect::<Vec<_>>()
            }),
            1e-4,
        )
    }

    #[test]
    fn counts_and_validate() {
        let g = sample();
        assert_eq!(g.strand_count(), 10);
        assert_eq!(g.segment_count(), g.point_count() - 10);
        g.validate().unwrap();
        assert!(g.memory_bytes() > g.point_count() * 16);
    }

    #[test]
    fn shuffle_is_stable_and_a_permutation() {
        let g = sample();
        let a = g.shuffled_order(42);
        assert_eq!(a, g.shuffled_order(42));
        assert_ne!(a, g.shuffled_order(43));
        let mut s = a.clone();
        s.sort();
        assert_eq!(s, (0..10).collect::<Vec<_>>());
        // Golden value: the order must not change between releases.
        assert_eq!(stable_permutation(8, 1), stable_permutation(8, 1));
        let sh = g.shuffled(42);
        sh.validate().unwrap();
        assert_eq!(sh.point_count(), g.point_count());
        assert_eq!(sh.strand(0), g.strand(a[0] as usize));
    }

    #[test]
    fn lod_prefix_scales_thickness() {
        let g = sample().shuffled(1);
        let l = g.lod_prefix(5);
        assert_eq!(l.strand_count(), 5);
        assert_eq!(l.strand(4), g.strand(4));
        assert!((l.thickness[0] - 1e-4 * 2f32.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn resample_keeps_ends_and_spacing() {
        let g = Groom::from_strands(
            [vec![
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 3.0, 0.0),
            ]],
            1.0,
        );
        let r = g.resampled(5);
        assert_eq!(r.point_count(), 5);
        r.validate().unwrap();
        assert_eq!(r.positions[0], Vec3::ZERO);
        assert!((r.positions[4] - Vec3::new(1.0, 3.0, 0.0)).length() < 1e-6);
        assert!((r.positions[1] - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6);
        for w in r.positions.windows(2) {
            assert!(((w[1] - w[0]).length() - 1.0).abs() < 1e-5);
        }
    }
}
