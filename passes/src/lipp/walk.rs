//! The DDA column walk (Lipp §3.1.2: "we rasterize them as single-pixel-wide
//! lines") shared by `lipp.raster` (its centre and conservative layers and
//! the MSAA pixel list) and the deep opacity maps (`dom::walk`). A segment in
//! pixel coordinates is walked one column at a time along its major axis;
//! each column gives the segment's parameter range inside it, from which the
//! callers pick their rows.
//!
//! The WGSL ports (`walk_columns` and `walk_column` in
//! `shaders/lipp/dom_maps.wgsl`, and the raster's segment loop) do the same
//! operations in the same order, so the CPU kernels and the shaders visit the
//! same pixels with the same bits.

/// A segment in the walk's (major, minor) axes: x is the major axis when the
/// segment spans at least as far in x as in y.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dda {
    pub x_major: bool,
    /// Major and minor coordinates of the first end.
    pub ma: f32,
    pub na: f32,
    /// Major and minor coordinates of the second end.
    pub mb: f32,
    pub nb: f32,
    /// `mb − ma` and `nb − na`.
    pub dm: f32,
    pub dn: f32,
}

impl Dda {
    /// The segment from `a` to `b`, (x, y) in pixels.
    pub fn new(a: [f32; 2], b: [f32; 2]) -> Self {
        let x_major = (b[0] - a[0]).abs() >= (b[1] - a[1]).abs();
        let (ma, na, mb, nb) = if x_major {
            (a[0], a[1], b[0], b[1])
        } else {
            (a[1], a[0], b[1], b[0])
        };
        Self {
            x_major,
            ma,
            na,
            mb,
            nb,
            dm: mb - ma,
            dn: nb - na,
        }
    }

    /// The major axis's pixel count on a `width` × `height` grid.
    pub fn limit(&self, width: u32, height: u32) -> f32 {
        (if self.x_major { width } else { height }) as f32
    }

    /// (x, y) of the pixel in column `m`, row `n`.
    pub fn pixel<T>(&self, m: T, n: T) -> (T, T) {
        if self.x_major { (m, n) } else { (n, m) }
    }

    /// Calls `visit(col, t0, t1)` for every column in [0, `limit`) that the
    /// segment's major range touches, in increasing order, with t0 ≤ t1 the
    /// segment's parameter range inside the column (all of it when the
    /// segment does not move along the major axis).
    pub fn columns(&self, limit: f32, mut visit: impl FnMut(f32, f32, f32)) {
        let lo = self.ma.min(self.mb).max(0.0).floor();
        let hi = self.ma.max(self.mb).min(limit - 1.0).floor();
        let mut col = lo;
        while col <= hi {
            let (t0, t1) = if self.dm != 0.0 {
                let ta = ((col - self.ma) / self.dm).clamp(0.0, 1.0);
                let tb = ((col + 1.0 - self.ma) / self.dm).clamp(0.0, 1.0);
                (ta.min(tb), ta.max(tb))
            } else {
                (0.0, 1.0)
            };
            visit(col, t0, t1);
            col += 1.0;
        }
    }

    /// The first and last row (floored minor coordinate, unclipped) the
    /// segment touches between parameters t0 and t1.
    pub fn rows(&self, t0: f32, t1: f32) -> (f32, f32) {
        let (n0, n1) = (self.na + self.dn * t0, self.na + self.dn * t1);
        (n0.min(n1).floor(), n0.max(n1).floor())
    }

    /// The conservative walk within one column: `visit(x, y)` for every row
    /// the segment touches between t0 and t1, unclipped (the caller's write
    /// tests the screen).
    pub fn column_pixels(&self, col: f32, t0: f32, t1: f32, mut visit: impl FnMut(i32, i32)) {
        let (r0, r1) = self.rows(t0, t1);
        for row in r0 as i32..=r1 as i32 {
            let (x, y) = self.pixel(col as i32, row);
            visit(x, y);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steep_segment_walks_rows_as_columns() {
        let dda = Dda::new([1.5, 0.5], [2.5, 3.5]);
        assert!(!dda.x_major);
        let mut pixels = Vec::new();
        dda.columns(dda.limit(8, 8), |col, t0, t1| {
            dda.column_pixels(col, t0, t1, |x, y| pixels.push((x, y)));
        });
        assert_eq!(pixels, vec![(1, 0), (1, 1), (2, 1), (2, 2), (2, 3)]);
    }

    #[test]
    fn a_point_covers_its_column_once() {
        let dda = Dda::new([2.25, 3.75], [2.25, 3.75]);
        let mut seen = Vec::new();
        dda.columns(4.0, |col, t0, t1| seen.push((col, t0, t1)));
        assert_eq!(seen, vec![(2.0, 0.0, 1.0)]);
    }
}
