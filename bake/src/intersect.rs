//! Ray tests against the two kinds of occluder of the bake: strand segments
//! as thin cylinders and the head's triangles.
//!
//! Kulikov traces "against the parent mesh as well so hair is always
//! shadowed by the head"; strands are the "nearby strands" of the talk's
//! visibility diagram. A strand segment is a capsule whose radius goes
//! linearly from root-side to tip-side thickness / 2: a ray hits it when it
//! passes within that radius of the segment, the usual thin-hair test (hair
//! is ~70 µm across, far below the segment length, so caps and the exact
//! entry point do not matter; what is counted is the crossing).

use glam::Vec3A;

/// A strand segment, as the bake stores it.
#[derive(Debug, Clone, Copy)]
pub struct Segment {
    pub a: Vec3A,
    pub b: Vec3A,
    /// Radius at `a` and at `b` (half the strand thickness).
    pub ra: f32,
    pub rb: f32,
    /// Packed index of `a`; `b` is `v0 + 1`.
    pub v0: u32,
    /// The strand's last segment (it owns the tip).
    pub last: bool,
}

impl Segment {
    /// Whether the segment touches packed vertex `v` (its own strand at the
    /// ray's origin, which is not a shadow caster for it).
    #[inline]
    pub fn touches(&self, v: u32) -> bool {
        self.v0 == v || self.v0.wrapping_add(1) == v
    }

    pub fn bounds(&self) -> (Vec3A, Vec3A) {
        let r = Vec3A::splat(self.ra.max(self.rb));
        (self.a.min(self.b) - r, self.a.max(self.b) + r)
    }
}

/// Distance along the ray (unit `dir`) at which it passes closest to `seg`,
/// if it passes within the segment's radius there and that distance lies in
/// `(tmin, tmax)`.
///
/// A crossing is counted where the ray passes the segment's axis: the point
/// of the axis nearest to the ray's line must lie inside the segment, with
/// `s` in `[0, 1)` (`[0, 1]` for the strand's last segment, which owns the
/// tip). So a ray crossing a strand counts once however finely the strand is
/// cut, even where pieces are shorter than the strand is thick; clamping to
/// the nearest end instead would count the crossing again on the
/// neighbouring piece.
#[inline]
pub fn ray_segment(origin: Vec3A, dir: Vec3A, seg: &Segment, tmin: f32, tmax: f32) -> Option<f32> {
    let v = seg.b - seg.a;
    let w = origin - seg.a;
    let c = v.dot(v);
    if c <= 0.0 {
        return None;
    }
    let b = dir.dot(v);
    let d = dir.dot(w);
    let e = v.dot(w);
    let denom = c - b * b; // |dir| = 1
    // Parallel to the axis: the ray runs along the strand, never across it.
    if denom <= 1e-12 * c {
        return None;
    }
    let s = (e - b * d) / denom;
    if !(0.0..=1.0).contains(&s) || (s == 1.0 && !seg.last) {
        return None;
    }
    let q = seg.a + v * s;
    let t = (q - origin).dot(dir);
    if t <= tmin || t >= tmax {
        return None;
    }
    let r = seg.ra + (seg.rb - seg.ra) * s;
    let dist2 = (origin + dir * t - q).length_squared();
    (dist2 <= r * r).then_some(t)
}

/// Möller–Trumbore, two-sided: the distance to triangle `[p0, p1, p2]` in
/// `(tmin, tmax)`, if hit.
#[inline]
pub fn ray_triangle(
    origin: Vec3A,
    dir: Vec3A,
    tri: &[Vec3A; 3],
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - tri[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > tmin && t < tmax).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: [f32; 3], b: [f32; 3], r: f32, last: bool) -> Segment {
        Segment {
            a: Vec3A::from(a),
            b: Vec3A::from(b),
            ra: r,
            rb: r,
            v0: 10,
            last,
        }
    }

    #[test]
    fn segment_hit_and_miss_by_radius() {
        let s = seg([-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], 0.01, true);
        let o = Vec3A::new(0.0, 0.005, 0.0);
        let t = ray_segment(o, Vec3A::Z, &s, 0.0, 10.0).expect("passes 5 mm from a 10 mm radius");
        assert!((t - 1.0).abs() < 1e-5, "t = {t}");
        let o = Vec3A::new(0.0, 0.02, 0.0);
        assert!(ray_segment(o, Vec3A::Z, &s, 0.0, 10.0).is_none());
        // Behind the origin or past tmax.
        assert!(ray_segment(Vec3A::ZERO, -Vec3A::Z, &s, 0.0, 10.0).is_none());
        assert!(ray_segment(Vec3A::ZERO, Vec3A::Z, &s, 0.0, 0.5).is_none());
        // Beyond the segment's ends.
        let o = Vec3A::new(1.5, 0.0, 0.0);
        assert!(ray_segment(o, Vec3A::Z, &s, 0.0, 10.0).is_none());
    }

    #[test]
    fn joint_counts_once() {
        let s0 = seg([-1.0, 0.0, 1.0], [0.0, 0.0, 1.0], 0.01, false);
        let mut s1 = seg([0.0, 0.0, 1.0], [1.0, 0.0, 1.0], 0.01, true);
        s1.v0 = 11;
        let o = Vec3A::new(0.005, 0.0, 0.0);
        let hits = [s0, s1]
            .iter()
            .filter(|s| ray_segment(o, Vec3A::Z, s, 0.0, 10.0).is_some())
            .count();
        assert_eq!(hits, 1);
        assert!(s0.touches(10) && s0.touches(11) && !s0.touches(12));
    }

    #[test]
    fn triangle_two_sided() {
        let tri = [
            Vec3A::new(-1.0, -1.0, 2.0),
            Vec3A::new(1.0, -1.0, 2.0),
            Vec3A::new(0.0, 1.0, 2.0),
        ];
        let t = ray_triangle(Vec3A::ZERO, Vec3A::Z, &tri, 0.0, 10.0).unwrap();
        assert!((t - 2.0).abs() < 1e-6);
        let back = Vec3A::new(0.0, 0.0, 4.0);
        assert!(ray_triangle(back, -Vec3A::Z, &tri, 0.0, 10.0).is_some());
        assert!(ray_triangle(Vec3A::new(2.0, 0.0, 0.0), Vec3A::Z, &tri, 0.0, 10.0).is_none());
    }
}
