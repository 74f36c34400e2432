//! Segment geometry for the conservative rasterizer: a segment with a width
//! at each end is a trapezoid (Kulikov: "Rasterize each segment as
//! trapezoid"); a pixel's coverage is the exact area of trapezoid ∩ pixel.
//!
//! Positions are snapped to 1/256 pixel first, so every backend makes the
//! same coverage and depth decisions from the same inputs (see
//! docs/architecture.md, "Agreement across backends").

/// Sub-pixel grid of the snap.
pub const SNAP: f32 = 256.0;

pub fn snap(x: f32) -> f32 {
    (x * SNAP).round() / SNAP
}

/// A convex polygon of at most 8 vertices (a quad clipped by two strips).
#[derive(Debug, Clone, Copy)]
pub struct Poly {
    pts: [[f32; 2]; 8],
    n: usize,
}

impl Poly {
    pub fn new(pts: &[[f32; 2]]) -> Self {
        let mut p = Poly {
            pts: [[0.0; 2]; 8],
            n: pts.len().min(8),
        };
        p.pts[..p.n].copy_from_slice(&pts[..p.n]);
        p
    }
    pub fn points(&self) -> &[[f32; 2]] {
        &self.pts[..self.n]
    }
    pub fn is_empty(&self) -> bool {
        self.n < 3
    }

    /// Keeps the part with `sign * (p[axis] - at) >= 0` (Sutherland–Hodgman, one plane).
    pub fn clip(&self, axis: usize, at: f32, sign: f32) -> Poly {
        let mut out = Poly {
            pts: [[0.0; 2]; 8],
            n: 0,
        };
        let inside = |p: [f32; 2]| sign * (p[axis] - at) >= 0.0;
        for i in 0..self.n {
            let (a, b) = (self.pts[i], self.pts[(i + 1) % self.n]);
            let (ia, ib) = (inside(a), inside(b));
            if ia && out.n < 8 {
                out.pts[out.n] = a;
                out.n += 1;
            }
            if ia != ib && out.n < 8 {
                let t = (at - a[axis]) / (b[axis] - a[axis]);
                out.pts[out.n] = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                out.n += 1;
            }
        }
        out
    }

    /// The part within `lo <= p[axis] <= hi`.
    pub fn strip(&self, axis: usize, lo: f32, hi: f32) -> Poly {
        self.clip(axis, lo, 1.0).clip(axis, hi, -1.0)
    }

    pub fn area(&self) -> f32 {
        let p = self.points();
        let twice: f32 = (0..p.len())
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        0.5 * twice.abs()
    }

    pub fn range(&self, axis: usize) -> (f32, f32) {
        self.points()
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                (lo.min(p[axis]), hi.max(p[axis]))
            })
    }
}

/// A projected segment in raster space (pixels of the model's atlas grid).
#[derive(Debug, Clone, Copy)]
pub struct Trapezoid {
    pub a: [f32; 2],
    pub b: [f32; 2],
    /// View depth (clip w) at each end.
    pub wa: f32,
    pub wb: f32,
    pub quad: Poly,
}

impl Trapezoid {
    /// `half_a`, `half_b`: half the strand width at each end, in pixels.
    pub fn new(
        a: [f32; 2],
        b: [f32; 2],
        half_a: f32,
        half_b: f32,
        wa: f32,
        wb: f32,
    ) -> Option<Trapezoid> {
        let (a, b) = ([snap(a[0]), snap(a[1])], [snap(b[0]), snap(b[1])]);
        let (ha, hb) = (snap(half_a).max(1.0 / SNAP), snap(half_b).max(1.0 / SNAP));
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        // Written so that NaN lengths are rejected too.
        if len.is_nan() || len <= 1.0 / SNAP || !len.is_finite() {
            return None;
        }
        let n = [-d[1] / len, d[0] / len];
        let quad = Poly::new(&[
            [a[0] + n[0] * ha, a[1] + n[1] * ha],
            [b[0] + n[0] * hb, b[1] + n[1] * hb],
            [b[0] - n[0] * hb, b[1] - n[1] * hb],
            [a[0] - n[0] * ha, a[1] - n[1] * ha],
        ]);
        Some(Trapezoid { a, b, wa, wb, quad })
    }

    /// The part of the trapezoid over pixel column `x` (Kulikov's `TrapezoidSlice`).
    pub fn column(&self, x: i32) -> Poly {
        self.quad.strip(0, x as f32, x as f32 + 1.0)
    }

    /// Exact area of the trapezoid inside pixel (x, y), given its column slice.
    pub fn coverage(column: &Poly, y: i32) -> f32 {
        column.strip(1, y as f32, y as f32 + 1.0).area().min(1.0)
    }

    /// Exact area of the trapezoid inside pixel (x, y), without clipping:
    /// the signed integral over the quad's edges of their height inside the
    /// pixel ([`edge_area`]). The same area as [`Trapezoid::coverage`] up
    /// to rounding, in registers only: composition evaluates it for three
    /// layers per pixel, where the clipper's vertex arrays spill to memory on
    /// the GPU (measured on an H100, 1080p close view: composition 21.1 ms
    /// with the clipper, 3.8 ms with this).
    pub fn pixel_coverage(&self, x: i32, y: i32) -> f32 {
        let p = self.quad.points();
        let (x0, y0) = (x as f32, y as f32);
        let sum: f32 = (0..p.len())
            .map(|i| edge_area(p[i], p[(i + 1) % p.len()], x0, y0))
            .sum();
        sum.abs().min(1.0)
    }

    /// View depth at a pixel centre: the nearest point on the segment's axis.
    pub fn depth_at(&self, x: i32, y: i32) -> f32 {
        let p = [x as f32 + 0.5, y as f32 + 0.5];
        let d = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let t =
            ((p[0] - self.a[0]) * d[0] + (p[1] - self.a[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1]);
        let t = t.clamp(0.0, 1.0);
        self.wa + t * (self.wb - self.wa)
    }

    /// The trapezoid's extent in y over pixel column `x`, from its four
    /// edges each cut to the column (`None` where no edge reaches it).
    /// The clipped slice's [`Poly::range`] in registers: the slice's
    /// vertices are exactly these cut edges' ends. The GPU raster keeps its
    /// lane state in registers with it, where the slice's vertex array lives
    /// in local memory (measured on an H100, 1080p close view: raster
    /// 1.57 → 0.89 ms; benches/results/kulikov-raster-registers-h100.txt).
    pub fn column_span(&self, x: i32) -> Option<(f32, f32)> {
        let p = self.quad.points();
        let x0 = x as f32;
        (0..p.len())
            .filter_map(|i| edge_span(p[i], p[(i + 1) % p.len()], x0))
            .reduce(|(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
    }

    /// Pixel columns the trapezoid touches.
    pub fn columns(&self) -> (i32, i32) {
        let (lo, hi) = self.quad.range(0);
        (lo.floor() as i32, hi.floor() as i32)
    }
}

/// The y extent of edge `a`–`b` cut to pixel column [x0, x0 + 1], or `None`
/// where it misses the column.
fn edge_span(a: [f32; 2], b: [f32; 2], x0: f32) -> Option<(f32, f32)> {
    let (p, q) = if a[0] < b[0] { (a, b) } else { (b, a) };
    let (lo, hi) = (p[0].max(x0), q[0].min(x0 + 1.0));
    if hi < lo {
        return None;
    }
    let (ya, yb) = if q[0] > p[0] {
        let slope = (q[1] - p[1]) / (q[0] - p[0]);
        (p[1] + slope * (lo - p[0]), p[1] + slope * (hi - p[0]))
    } else {
        (p[1], q[1]) // vertical, on the column
    };
    Some((ya.min(yb), ya.max(yb)))
}

/// ∫ over edge `a`→`b`, within pixel columns [x0, x0 + 1], of the edge's
/// height above y0 clamped to the pixel ([y0, y0 + 1]), signed by the
/// direction of travel in x. Summed over a closed polygon's edges this is
/// ± the polygon's area inside the pixel: the upper chain adds the area
/// under it, the lower chain takes away the area under it.
pub fn edge_area(a: [f32; 2], b: [f32; 2], x0: f32, y0: f32) -> f32 {
    let (p, q, sign) = if a[0] < b[0] {
        (a, b, 1.0)
    } else {
        (b, a, -1.0)
    };
    let (lo, hi) = (p[0].max(x0), q[0].min(x0 + 1.0));
    if !(hi > lo) {
        return 0.0; // vertical, or outside the column
    }
    let slope = (q[1] - p[1]) / (q[0] - p[0]);
    let (ya, yb) = (
        p[1] + slope * (lo - p[0]) - y0,
        p[1] + slope * (hi - p[0]) - y0,
    );
    sign * (hi - lo) * clamped_mean(ya, yb)
}

/// The mean over t ∈ [0, 1] of clamp(ya + t (yb − ya), 0, 1): the line
/// split where it crosses 0 and 1, each piece linear, so its midpoint value
/// is its mean.
fn clamped_mean(ya: f32, yb: f32) -> f32 {
    let g = |t: f32| (ya + t * (yb - ya)).clamp(0.0, 1.0);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    if yb != ya {
        let c0 = (-ya / (yb - ya)).clamp(0.0, 1.0);
        let c1 = ((1.0 - ya) / (yb - ya)).clamp(0.0, 1.0);
        (t0, t1) = (c0.min(c1), c0.max(c1));
    }
    t0 * g(0.5 * t0) + (t1 - t0) * g(0.5 * (t0 + t1)) + (1.0 - t1) * g(0.5 * (t1 + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Xorshift uniform numbers in [0, 1] from `seed`.
    fn uniform(mut s: u32) -> impl FnMut() -> f32 {
        move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        }
    }

    #[test]
    fn edge_integration_matches_the_clipper() {
        // Pseudo-random trapezoids of every orientation and width.
        let mut rnd = uniform(12345);
        let mut worst = 0.0f32;
        for _ in 0..400 {
            let a = [1.0 + 6.0 * rnd(), 1.0 + 6.0 * rnd()];
            let b = [1.0 + 6.0 * rnd(), 1.0 + 6.0 * rnd()];
            let Some(t) = Trapezoid::new(a, b, 0.05 + rnd(), 0.05 + rnd(), 1.0, 1.0) else {
                continue;
            };
            for x in -1..10 {
                let col = t.column(x);
                for y in -1..10 {
                    let clipped = if col.is_empty() {
                        0.0
                    } else {
                        Trapezoid::coverage(&col, y)
                    };
                    worst = worst.max((t.pixel_coverage(x, y) - clipped).abs());
                }
            }
        }
        assert!(worst < 2e-5, "largest difference {worst}");
    }

    #[test]
    fn column_span_matches_the_clipped_slice() {
        let mut rnd = uniform(777);
        let mut checked = 0;
        for _ in 0..400 {
            // Axis-aligned ends too: vertical and horizontal edges.
            let mut a = [1.0 + 6.0 * rnd(), 1.0 + 6.0 * rnd()];
            let b = [1.0 + 6.0 * rnd(), 1.0 + 6.0 * rnd()];
            if rnd() < 0.2 {
                a[0] = b[0];
            } else if rnd() < 0.2 {
                a[1] = b[1];
            }
            let Some(t) = Trapezoid::new(a, b, 0.05 + rnd(), 0.05 + rnd(), 1.0, 1.0) else {
                continue;
            };
            let (x0, x1) = t.columns();
            for x in x0 - 1..=x1 + 1 {
                let col = t.column(x);
                match t.column_span(x) {
                    None => assert!(col.is_empty(), "column {x} of {t:?}: no span, a slice"),
                    Some((lo, hi)) if !col.is_empty() => {
                        let (clo, chi) = col.range(1);
                        assert!((lo - clo).abs() < 1e-4 && (hi - chi).abs() < 1e-4);
                        checked += 1;
                    }
                    // Touching the column's edge: a degenerate slice, no area.
                    Some(_) => assert!(col.area() == 0.0),
                }
            }
        }
        assert!(checked > 1000, "{checked} columns compared");
    }

    #[test]
    fn coverage_sums_to_the_trapezoid_area() {
        let t = Trapezoid::new([1.3, 2.1], [9.7, 5.4], 0.7, 0.3, 1.0, 2.0).unwrap();
        let (x0, x1) = t.columns();
        let mut sum = 0.0;
        for x in x0..=x1 {
            let col = t.column(x);
            if col.is_empty() {
                continue;
            }
            let (lo, hi) = col.range(1);
            for y in lo.floor() as i32..=hi.floor() as i32 {
                sum += Trapezoid::coverage(&col, y);
            }
        }
        assert!(
            (sum - t.quad.area()).abs() < 1e-3,
            "{sum} vs {}",
            t.quad.area()
        );
        let len = ((9.7f32 - 1.3).powi(2) + (5.4f32 - 2.1).powi(2)).sqrt();
        assert!((t.quad.area() - len * (0.7 + 0.3)).abs() < 0.01);
    }

    #[test]
    fn depth_is_interpolated_along_the_axis() {
        let t = Trapezoid::new([0.5, 0.5], [10.5, 0.5], 0.5, 0.5, 1.0, 2.0).unwrap();
        assert!((t.depth_at(5, 0) - 1.5).abs() < 1e-6);
        assert_eq!(t.depth_at(-3, 0), 1.0);
        assert!(Trapezoid::new([1.0, 1.0], [1.0, 1.0], 1.0, 1.0, 1.0, 1.0).is_none());
    }
}
