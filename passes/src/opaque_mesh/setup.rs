//! Triangle setup and coverage of the compute rasterizer behind
//! `scene.visibility` and `scene.opaque`, mirrored operation for operation by
//! `shaders/opaque_mesh/setup.wgsl`.
//!
//! The rules are those of hardware rasterization (D3D11 functional spec
//! §3.4.1 and Vulkan §28.7 "Basic Polygon Rasterization"): corners snap to a
//! fixed-point grid, edge functions are evaluated exactly in integers at pixel
//! centres, and a centre exactly on an edge belongs to the triangle only when
//! the edge is a top or left edge, so adjacent triangles cover each pixel of
//! their union exactly once. What differs from the hardware path this
//! replaced is the integer width, chosen so every step fits WGSL's `i32`:
//!
//! - corners snap to 1/16 pixel (4 sub-pixel bits, Vulkan's minimum
//!   `subPixelPrecisionBits`);
//! - edge functions are evaluated relative to the triangle's own snapped
//!   minimum corner. Translation does not change an edge function, so two
//!   triangles sharing an edge still make identical decisions on it;
//! - a triangle whose snapped extent reaches [`MAX_EXTENT`] sub-pixels (about
//!   2044 pixels) in x or y is not drawn: each product of an edge function then
//!   stays below 2^30 and their difference below 2^31. No head or body of a
//!   shipped scene comes near it; hardware would clip such a triangle instead.
//!
//! Depth (NDC z/w) is interpolated linearly in screen space from the exact
//! edge functions, attributes perspective-correctly (Vulkan §28.7.1). Front
//! faces are counter-clockwise in NDC (y up), as glam's `perspective_rh` and
//! wgpu's default `FrontFace::Ccw`.

use glam::Vec4;

/// Sub-pixel precision: corners snap to 1/2^4 pixel.
pub const SUBPIXEL_BITS: u32 = 4;
const ONE: i32 = 1 << SUBPIXEL_BITS;
const HALF: i32 = ONE / 2;

/// Largest snapped extent (sub-pixels, exclusive) of a drawn triangle. The
/// 64 sub-pixels of slack keep the edge functions one pixel step outside the
/// bounding box (where the row loop ends) inside `i32` too.
pub const MAX_EXTENT: i32 = (1 << 15) - 64;

/// Corners farther than this many pixels from the screen origin are dropped
/// before snapping, so `x · 16` stays an exact integer in both `f32` and `i32`.
pub const GUARD_BAND: f32 = 524_288.0;

/// Source corner (0 = a, 1 = b, 2 = c) of each setup vertex. A front face has
/// negative signed area with y down; swapping b and c makes it positive.
pub const ORDER: [usize; 3] = [0, 2, 1];

/// A front-facing triangle ready to rasterize; vertices in [`ORDER`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Snapped corners relative to `origin`, in sub-pixels.
    x: [i32; 3],
    y: [i32; 3],
    /// The snapped minimum corner, in sub-pixels.
    origin: [i32; 2],
    /// Twice the area, in sub-pixels squared (> 0).
    area: i32,
    /// 0 for a top or left edge, 1 otherwise (edge `i` is opposite vertex `i`).
    bias: [i32; 3],
    /// Per setup vertex: NDC depth and 1/w.
    z: [f32; 3],
    inv_w: [f32; 3],
    /// Depth steps per unit of edge functions 1 and 2: (z_i − z_0) / area.
    dz: [f32; 2],
    /// Inclusive pixel bounds clipped to the screen: x0, y0, x1, y1.
    bounds: [u32; 4],
}

impl Setup {
    /// Sets up the triangle with clip-space corners `clip` (a, b, c), or
    /// `None` when it is culled: a back face, degenerate after snapping, off
    /// screen, too large, or with a corner at or behind the near plane
    /// (w ≤ `near`). Near-plane crossers are dropped, not clipped: heads never
    /// cross the near plane in our scenes.
    pub fn from_clip(clip: [Vec4; 3], near: f32, width: u32, height: u32) -> Option<Self> {
        let near = near.max(0.0);
        let mut sx = [0i32; 3];
        let mut sy = [0i32; 3];
        let mut z = [0.0f32; 3];
        let mut inv_w = [0.0f32; 3];
        for (i, &k) in ORDER.iter().enumerate() {
            let c = clip[k];
            if c.w.is_nan() || c.w <= near {
                return None;
            }
            let iw = 1.0 / c.w;
            // Viewport transform, y down (D3D/Vulkan/WebGPU framebuffer coordinates).
            let px = (c.x * iw * 0.5 + 0.5) * width as f32;
            let py = (0.5 - c.y * iw * 0.5) * height as f32;
            if !(px.abs() <= GUARD_BAND && py.abs() <= GUARD_BAND) {
                return None;
            }
            // Round to the nearest 1/16 pixel, ties to even as WGSL's
            // `round` does (scaling by 16 is exact).
            sx[i] = (px * ONE as f32).round_ties_even() as i32;
            sy[i] = (py * ONE as f32).round_ties_even() as i32;
            z[i] = c.z * iw;
            inv_w[i] = iw;
        }
        let origin = [min3(sx), min3(sy)];
        if max3(sx) - origin[0] >= MAX_EXTENT || max3(sy) - origin[1] >= MAX_EXTENT {
            return None;
        }
        let x = sx.map(|v| v - origin[0]);
        let y = sy.map(|v| v - origin[1]);
        // Twice the signed area, y down, decided on the snapped corners so
        // that every backend agrees on the winding.
        let area = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        if area <= 0 {
            return None; // back face (after the swap) or degenerate
        }
        let bias = [0, 1, 2].map(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (x[k] - x[j], y[k] - y[j]);
            // With positive area and y down, the triangle lies to the right
            // of each directed edge: a left edge goes up (dy < 0), a top edge
            // is horizontal going right (dy == 0, dx > 0).
            i32::from(!(dy < 0 || (dy == 0 && dx > 0)))
        });
        // Pixels whose centre (p + 0.5) lies within the snapped bounding box;
        // `>>` is floor division by 16 on negative values too.
        let lo = |v: i32| (v - HALF + ONE - 1) >> SUBPIXEL_BITS;
        let hi = |v: i32| (v - HALF) >> SUBPIXEL_BITS;
        let (x0, x1) = (lo(origin[0]).max(0), hi(max3(sx)).min(width as i32 - 1));
        let (y0, y1) = (lo(origin[1]).max(0), hi(max3(sy)).min(height as i32 - 1));
        if x1 < x0 || y1 < y0 {
            return None;
        }
        let inv_area = 1.0 / area as f32;
        Some(Self {
            x,
            y,
            origin,
            area,
            bias,
            z,
            inv_w,
            dz: [(z[1] - z[0]) * inv_area, (z[2] - z[0]) * inv_area],
            bounds: [x0 as u32, y0 as u32, x1 as u32, y1 as u32],
        })
    }

    /// Inclusive pixel bounds clipped to the screen: x0, y0, x1, y1.
    pub fn bounds(&self) -> [u32; 4] {
        self.bounds
    }

    /// Pixels in the clipped bounding box.
    pub fn box_pixels(&self) -> u32 {
        let [x0, y0, x1, y1] = self.bounds;
        (x1 - x0 + 1) * (y1 - y0 + 1)
    }

    /// Edge functions at the centre of pixel (px, py), relative to the origin.
    pub fn edges(&self, px: u32, py: u32) -> [i32; 3] {
        let cx = px as i32 * ONE + HALF - self.origin[0];
        let cy = py as i32 * ONE + HALF - self.origin[1];
        [0, 1, 2].map(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            (self.x[k] - self.x[j]) * (cy - self.y[j]) - (self.y[k] - self.y[j]) * (cx - self.x[j])
        })
    }

    /// Whether edge function values `e` cover the pixel (the top-left rule).
    pub fn covers(&self, e: [i32; 3]) -> bool {
        e[0] >= self.bias[0] && e[1] >= self.bias[1] && e[2] >= self.bias[2]
    }

    /// NDC depth at a covered pixel, linear in screen space.
    pub fn depth(&self, e: [i32; 3]) -> f32 {
        self.z[0] + e[1] as f32 * self.dz[0] + e[2] as f32 * self.dz[1]
    }

    /// Calls `f(x, y, depth)` for every covered pixel centre, row by row,
    /// stepping the edge functions by exact integer increments.
    pub fn rasterize(&self, mut f: impl FnMut(u32, u32, f32)) {
        let [x0, y0, x1, y1] = self.bounds;
        let step_x = [0, 1, 2].map(|i| -(self.y[(i + 2) % 3] - self.y[(i + 1) % 3]) * ONE);
        for y in y0..=y1 {
            let mut e = self.edges(x0, y);
            for x in x0..=x1 {
                if self.covers(e) {
                    f(x, y, self.depth(e));
                }
                for (ei, s) in e.iter_mut().zip(step_x) {
                    *ei += s;
                }
            }
        }
    }

    /// Perspective-correct barycentrics of the source corners a, b, c at a
    /// covered pixel (what `@interpolate(perspective)` gives a fragment).
    pub fn barycentrics(&self, e: [i32; 3]) -> [f32; 3] {
        let q = [0, 1, 2].map(|i| e[i] as f32 * self.inv_w[i]);
        let sum = q[0] + q[1] + q[2];
        let setup = if sum > 0.0 {
            let inv = 1.0 / sum;
            q.map(|v| v * inv)
        } else {
            [1.0, 0.0, 0.0]
        };
        let mut source = [0.0; 3];
        for (i, &k) in ORDER.iter().enumerate() {
            source[k] = setup[i];
        }
        source
    }
}

fn min3(v: [i32; 3]) -> i32 {
    v[0].min(v[1]).min(v[2])
}

fn max3(v: [i32; 3]) -> i32 {
    v[0].max(v[1]).max(v[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clip-space corners for screen positions (pixels, y down) on a w × h
    /// screen, at depth `z` and w = 1.
    fn clip(tri: [[f32; 2]; 3], z: [f32; 3], w: u32, h: u32) -> [Vec4; 3] {
        [0, 1, 2].map(|k| {
            let [x, y] = tri[k];
            Vec4::new(
                x / w as f32 * 2.0 - 1.0,
                1.0 - y / h as f32 * 2.0,
                z[k],
                1.0,
            )
        })
    }

    /// Covered pixel centres of a screen-space triangle (either winding).
    fn cover(tri: [[f32; 2]; 3], w: u32, h: u32) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for t in [tri, [tri[0], tri[2], tri[1]]] {
            if let Some(s) = Setup::from_clip(clip(t, [0.5; 3], w, h), 0.0, w, h) {
                s.rasterize(|x, y, _| out.push((x, y)));
            }
        }
        out
    }

    fn next(seed: &mut u32) -> f32 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 17;
        *seed ^= *seed << 5;
        (*seed >> 8) as f32 / (1 << 24) as f32
    }

    #[test]
    fn covered_pixels_match_the_analytic_area() {
        crate::fill_rule_checks::covered_pixels_match_the_analytic_area(&cover);
    }

    #[test]
    fn triangles_sharing_edges_cover_every_pixel_once() {
        crate::fill_rule_checks::shared_edges_cover_every_pixel_once(&cover);
    }

    #[test]
    fn shared_edges_stay_watertight_far_from_the_origin() {
        // A strip of thin triangles across a 1920-pixel screen at random
        // sub-pixel offsets: relative coordinates must not open cracks.
        let (w, h) = (1920u32, 64u32);
        let mut seed = 0x1234_5678_u32;
        let xs: Vec<f32> = (0..40)
            .map(|i| i as f32 * 48.0 + next(&mut seed) * 30.0)
            .collect();
        let mut count = vec![0u8; (w * h) as usize];
        for pair in xs.windows(2) {
            let q = [
                [pair[0], 3.3],
                [pair[1], 3.7],
                [pair[1], 60.2],
                [pair[0], 59.9],
            ];
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                for (x, y) in cover(t, w, h) {
                    count[(y * w + x) as usize] += 1;
                }
            }
        }
        assert!(count.iter().all(|&c| c <= 1), "a pixel was covered twice");
        for y in 5..58 {
            for x in (xs[0] as u32 + 2)..(xs[39] as u32 - 2) {
                assert_eq!(count[(y * w + x) as usize], 1, "crack at ({x}, {y})");
            }
        }
    }

    #[test]
    fn back_faces_degenerates_and_giants_are_culled() {
        let s = |t: [[f32; 2]; 3], w: u32| Setup::from_clip(clip(t, [0.5; 3], w, w), 0.0, w, w);
        // Rows grow downwards: (1,1) → (9,1) → (1,9) is clockwise on screen.
        let back = [[1.0f32, 1.0], [9.0, 1.0], [1.0, 9.0]];
        assert!(s(back, 16).is_none());
        assert!(s([back[0], back[2], back[1]], 16).is_some());
        assert!(s([[1.0, 1.0], [5.0, 5.0], [9.0, 9.0]], 16).is_none());
        assert!(s([[f32::NAN, 1.0], [1.0, 9.0], [9.0, 1.0]], 16).is_none());
        assert!(s([[-9.0, -9.0], [-9.0, -1.0], [-1.0, -9.0]], 16).is_none());
        // 2100 pixels wide: past MAX_EXTENT, not drawn (rather than overflow).
        assert!(s([[1.0, 1.0], [1.0, 9.0], [2101.0, 1.0]], 4096).is_none());
        assert!(s([[1.0, 1.0], [1.0, 9.0], [2001.0, 1.0]], 4096).is_some());
    }

    #[test]
    fn depth_is_linear_and_attributes_perspective() {
        let (w, h) = (32, 32);
        let tri = [[0.5f32, 0.5], [0.5, 16.5], [16.5, 0.5]];
        let mut c = clip(tri, [0.0, 1.0, 0.5], w, h);
        // Corner b four times as far: scale its clip position by w = 4.
        c[1] *= 4.0;
        let s = Setup::from_clip(c, 0.0, w, h).unwrap();
        let mut seen = 0;
        s.rasterize(|x, y, depth| {
            seen += 1;
            let e = s.edges(x, y);
            // Screen-space weights of b and c (setup vertices 2 and 1).
            let (wb, wc) = (e[2] as f32 / s.area as f32, e[1] as f32 / s.area as f32);
            assert!((depth - (wb + 0.5 * wc)).abs() < 1e-6);
            let p = s.barycentrics(e);
            assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            // The far corner b gets less weight than on screen.
            assert!(p[1] <= wb + 1e-6, "{p:?} vs {wb}");
        });
        assert!(seen > 100);
    }
}
