//! Triangle rasterization as hardware does it, for the CPU kernels of the
//! raster passes (`bench.raster`, the graphics roofline; Scheuermann's hair
//! patches), which must make the same coverage decisions as the GPU
//! backends' hardware rasterizers. The rules are the
//! ones D3D11 and Vulkan specify for hardware:
//!
//! - corners snap to a fixed-point grid of 1/256 pixel (8 sub-pixel bits, the
//!   usual `VkPhysicalDeviceLimits::subPixelPrecisionBits`; D3D11 functional
//!   spec §15.5 "Fixed point rasterization" also uses 8 bits), and the edge
//!   functions are evaluated exactly in integers;
//! - coverage is sampled at pixel centres (+0.5, +0.5);
//! - a centre exactly on an edge belongs to the triangle only when that edge
//!   is a *top* or *left* edge (D3D11 §3.4.1 "Triangle Rasterization Rules
//!   (Without Multisampling)"; Vulkan spec §28.7 "Polygons" / "Basic Polygon
//!   Rasterization", the same rule). Adjacent triangles therefore cover each
//!   pixel of their union exactly once;
//! - depth (NDC z/w) is interpolated linearly in screen space, attributes
//!   perspective-correctly (Vulkan §28.7.1 "Polygon Interpolation").
//!
//! Front faces are counter-clockwise in NDC (y up), the convention of glam's
//! `perspective_rh` and wgpu's default `FrontFace::Ccw`; [`Cull`] says which
//! faces a pass drops.

pub use crate::raster_state::Cull;
use glam::Vec4;

/// Sub-pixel precision: corners snap to 1/2^8 pixel.
pub const SUBPIXEL_BITS: u32 = 8;
const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;

/// Corners farther than this (pixels) from the screen origin are outside the
/// guard band: the triangle is dropped rather than risk overflow. With
/// |coordinate| ≤ 2^28 sub-pixel units, edge functions stay below 2^60 in i64.
/// Hardware clips such triangles instead; heads and bodies never reach it.
pub const GUARD_BAND: f32 = 1_048_576.0;

/// One covered pixel centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragment {
    pub x: u32,
    pub y: u32,
    /// NDC depth z/w, interpolated linearly in screen space.
    pub depth: f32,
    /// Screen-space barycentrics of the source corners a, b, c (sum to 1).
    pub screen: [f32; 3],
}

/// A triangle that survived culling, ready to rasterize.
#[derive(Debug, Clone, Copy)]
pub struct Setup {
    /// Snapped corners, reordered so that the signed area is positive.
    x: [i64; 3],
    y: [i64; 3],
    /// Twice the signed area, in sub-pixel units squared (> 0).
    area: i64,
    /// 0 for a top or left edge, 1 otherwise: ties on other edges fail `E >= bias`.
    /// Edge `i` is the one opposite vertex `i`.
    bias: [i64; 3],
    /// Which source corner (0 = a, 1 = b, 2 = c) each setup vertex is.
    order: [usize; 3],
    /// Per source corner: NDC depth and 1/w.
    z: [f32; 3],
    inv_w: [f32; 3],
    /// Inclusive pixel bounds clipped to the screen: x0, y0, x1, y1.
    bounds: [u32; 4],
    /// Made by [`Setup::from_clip_multisampled`].
    multisampled: bool,
}

/// A rounding from sub-pixel units to a pixel index.
type Round = fn(i64) -> i64;

/// Which pixels a setup visits.
#[derive(Clone, Copy)]
enum Bounds {
    /// Those whose centre lies in the bounding box.
    Centres,
    /// Every pixel the bounding box touches (multisampling).
    Touched,
}

/// One pixel with at least one covered sample (multisampled rasterization).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledFragment {
    pub x: u32,
    pub y: u32,
    /// Bit s: sample s is covered.
    pub mask: u32,
    /// At each covered sample: NDC depth (what the depth test compares)
    /// and screen-space barycentrics of the source corners (what
    /// `@interpolate(linear, sample)` gives a sample-rate fragment shader).
    pub depth: [f32; 8],
    pub screen: [[f32; 3]; 8],
}

/// A standard sample pattern in sub-pixel units (1/256 pixel) from the pixel
/// centre: Vulkan's standard locations (the same as Direct3D's) for 1, 2,
/// 4 and 8 samples, on their 1/16-pixel grid.
pub fn standard_samples(n: u32) -> Vec<[i64; 2]> {
    let grid: &[[i64; 2]] = match n {
        2 => &[[4, 4], [-4, -4]],
        4 => &[[-2, -6], [6, -2], [-6, 2], [2, 6]],
        8 => &[
            [1, -3],
            [-1, 3],
            [5, 1],
            [-3, -5],
            [-5, 5],
            [-7, -1],
            [3, 7],
            [7, -7],
        ],
        _ => &[[0, 0]],
    };
    grid.iter()
        .map(|g| [g[0] * ONE / 16, g[1] * ONE / 16])
        .collect()
}

impl Setup {
    /// Sets up the triangle with clip-space corners `clip`, or `None` when it
    /// is culled: a back face, degenerate after snapping, off screen, or with
    /// a corner behind the near plane (w < `near`; a strand quad's corner cut
    /// at the plane has w = `near` exactly, see `common::clip`). Dropping
    /// near-plane crossers instead of clipping them is deliberate: heads never
    /// cross the near plane in our scenes, and the WGSL vertex shaders drop
    /// them the same way so every backend agrees.
    pub fn from_clip(clip: [Vec4; 3], near: f32, width: u32, height: u32) -> Option<Self> {
        Self::from_clip_culled(clip, near, width, height, Cull::Back)
    }

    /// [`Setup::from_clip`] dropping the faces `cull` names.
    pub fn from_clip_culled(
        clip: [Vec4; 3],
        near: f32,
        width: u32,
        height: u32,
        cull: Cull,
    ) -> Option<Self> {
        Self::from_clip_culled_bounds(clip, near, width, height, cull, Bounds::Centres)
    }

    /// Sets up a triangle from screen positions (pixels, y down), per-corner
    /// depth and 1/w. Culls back faces and degenerate triangles.
    pub fn from_screen(
        xy: [[f32; 2]; 3],
        z: [f32; 3],
        inv_w: [f32; 3],
        width: u32,
        height: u32,
    ) -> Option<Self> {
        Self::from_screen_culled(xy, z, inv_w, width, height, Cull::Back)
    }

    /// [`Setup::from_clip_culled`] for a multisampled attachment: the
    /// bounds are every pixel the snapped bounding box touches, since a
    /// triangle may cover samples of pixels whose centre it misses (a thin
    /// strand quad often does). Rasterize it with [`Setup::rasterize_samples`].
    pub fn from_clip_multisampled(
        clip: [Vec4; 3],
        near: f32,
        width: u32,
        height: u32,
        cull: Cull,
    ) -> Option<Self> {
        let mut s =
            Self::from_clip_culled_bounds(clip, near, width, height, cull, Bounds::Touched)?;
        s.multisampled = true;
        Some(s)
    }

    fn from_clip_culled_bounds(
        clip: [Vec4; 3],
        near: f32,
        width: u32,
        height: u32,
        cull: Cull,
        bounds: Bounds,
    ) -> Option<Self> {
        let near = near.max(0.0);
        let mut xy = [[0.0f32; 2]; 3];
        let mut z = [0.0f32; 3];
        let mut inv_w = [0.0f32; 3];
        for (k, c) in clip.iter().enumerate() {
            if !(c.w >= near && c.w > 0.0) {
                return None;
            }
            let iw = 1.0 / c.w;
            let ndc = [c.x * iw, c.y * iw];
            // Viewport transform, y down (D3D/Vulkan/WebGPU framebuffer coordinates).
            xy[k] = [
                (ndc[0] * 0.5 + 0.5) * width as f32,
                (0.5 - ndc[1] * 0.5) * height as f32,
            ];
            z[k] = c.z * iw;
            inv_w[k] = iw;
        }
        Self::build(xy, z, inv_w, width, height, cull, bounds)
    }

    /// [`Setup::from_screen`] dropping the faces `cull` names (and
    /// degenerate triangles, always).
    pub fn from_screen_culled(
        xy: [[f32; 2]; 3],
        z: [f32; 3],
        inv_w: [f32; 3],
        width: u32,
        height: u32,
        cull: Cull,
    ) -> Option<Self> {
        Self::build(xy, z, inv_w, width, height, cull, Bounds::Centres)
    }

    fn build(
        xy: [[f32; 2]; 3],
        z: [f32; 3],
        inv_w: [f32; 3],
        width: u32,
        height: u32,
        cull: Cull,
        bounds: Bounds,
    ) -> Option<Self> {
        let mut sx = [0i64; 3];
        let mut sy = [0i64; 3];
        for k in 0..3 {
            let [x, y] = xy[k];
            if !(x.abs() <= GUARD_BAND && y.abs() <= GUARD_BAND) {
                return None;
            }
            // Round to the nearest 1/256 pixel (scaling by 2^8 is exact in f32).
            sx[k] = (x * ONE as f32).round() as i64;
            sy[k] = (y * ONE as f32).round() as i64;
        }
        // Twice the signed area in y-down coordinates: a triangle that is
        // counter-clockwise in NDC (y up) comes out negative here. The winding
        // is decided on the *snapped* corners so that every backend agrees.
        let signed = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sy[1] - sy[0]) * (sx[2] - sx[0]);
        let front = signed < 0;
        let culled = match cull {
            Cull::None => false,
            Cull::Back => !front,
            Cull::Front => front,
        };
        if signed == 0 || culled {
            return None;
        }
        // A front face swaps b and c so the area is positive and interior
        // edge functions are > 0; a back face already has that order.
        let order = if front { [0usize, 2, 1] } else { [0, 1, 2] };
        let x = order.map(|k| sx[k]);
        let y = order.map(|k| sy[k]);
        let bias = [0, 1, 2].map(|i| {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (dx, dy) = (x[k] - x[j], y[k] - y[j]);
            // With positive area and y down, the triangle lies to the right of
            // each directed edge: a left edge goes up (dy < 0), a top edge is
            // horizontal going right (dy == 0, dx > 0).
            let top_left = dy < 0 || (dy == 0 && dx > 0);
            i64::from(!top_left)
        });
        // Pixels whose centre (p + 0.5) lies within the snapped bounding box,
        // or for samples anywhere in the pixel, every pixel the box touches.
        let (lo, hi): (Round, Round) = match bounds {
            Bounds::Centres => (
                |v| (v - HALF + ONE - 1).div_euclid(ONE),
                |v| (v - HALF).div_euclid(ONE),
            ),
            Bounds::Touched => (|v| v.div_euclid(ONE), |v| v.div_euclid(ONE)),
        };
        let (x0, x1) = (lo(*x.iter().min()?).max(0), hi(*x.iter().max()?));
        let (y0, y1) = (lo(*y.iter().min()?).max(0), hi(*y.iter().max()?));
        let (x1, y1) = (x1.min(i64::from(width) - 1), y1.min(i64::from(height) - 1));
        if x1 < x0 || y1 < y0 {
            return None;
        }
        Some(Self {
            x,
            y,
            area: signed.abs(),
            bias,
            order,
            z,
            inv_w,
            bounds: [x0 as u32, y0 as u32, x1 as u32, y1 as u32],
            multisampled: false,
        })
    }

    /// Inclusive pixel bounds clipped to the screen: x0, y0, x1, y1.
    pub fn bounds(&self) -> [u32; 4] {
        self.bounds
    }

    /// Edge function of the edge opposite vertex `i` at sub-pixel point (px, py).
    fn edge(&self, i: usize, px: i64, py: i64) -> i64 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        (self.x[k] - self.x[j]) * (py - self.y[j]) - (self.y[k] - self.y[j]) * (px - self.x[j])
    }

    /// Calls `f` for every covered pixel centre, row by row.
    pub fn rasterize(&self, f: impl FnMut(Fragment)) {
        self.rasterize_rows(0, u32::MAX, f);
    }

    /// [`Setup::rasterize`] limited to rows `first..=last` (a CPU workgroup's
    /// band of the screen: bands draw in parallel, triangles in order).
    pub fn rasterize_rows(&self, first: u32, last: u32, mut f: impl FnMut(Fragment)) {
        let [x0, y0, x1, y1] = self.bounds;
        let (y0, y1) = (y0.max(first), y1.min(last));
        if y1 < y0 {
            return;
        }
        let (px, py) = (i64::from(x0) * ONE + HALF, i64::from(y0) * ONE + HALF);
        let mut row = [0, 1, 2].map(|i| self.edge(i, px, py));
        // Exact integer steps, so stepping equals evaluating at every pixel.
        let step_x = [0, 1, 2].map(|i| -(self.y[(i + 2) % 3] - self.y[(i + 1) % 3]) * ONE);
        let step_y = [0, 1, 2].map(|i| (self.x[(i + 2) % 3] - self.x[(i + 1) % 3]) * ONE);
        let area = self.area as f64;
        for y in y0..=y1 {
            let mut e = row;
            for x in x0..=x1 {
                if e.iter().zip(&self.bias).all(|(ei, b)| ei >= b) {
                    let (depth, screen) = self.depth_at(e, area);
                    f(Fragment {
                        x,
                        y,
                        depth,
                        screen,
                    });
                }
                for (ei, s) in e.iter_mut().zip(step_x) {
                    *ei += s;
                }
            }
            for (r, s) in row.iter_mut().zip(step_y) {
                *r += s;
            }
        }
    }

    /// Multisampled rasterization of rows `first..=last`: calls `f` for every
    /// pixel with a covered sample of `samples` ([`standard_samples`]; at
    /// most 8), with the same fill rules per sample as [`Setup::rasterize`]
    /// applies per centre. Needs a setup from [`Setup::from_clip_multisampled`].
    pub fn rasterize_samples(
        &self,
        first: u32,
        last: u32,
        samples: &[[i64; 2]],
        mut f: impl FnMut(SampledFragment),
    ) {
        debug_assert!(self.multisampled && samples.len() <= 8);
        let [x0, y0, x1, y1] = self.bounds;
        let area = self.area as f64;
        let weights = |px: i64, py: i64| [0, 1, 2].map(|i| self.edge(i, px, py));
        for y in y0.max(first)..=y1.min(last) {
            for x in x0..=x1 {
                let (cx, cy) = (i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF);
                let mut frag = SampledFragment {
                    x,
                    y,
                    mask: 0,
                    depth: [0.0; 8],
                    screen: [[0.0; 3]; 8],
                };
                for (s, o) in samples.iter().enumerate() {
                    let e = weights(cx + o[0], cy + o[1]);
                    if e.iter().zip(&self.bias).all(|(ei, b)| ei >= b) {
                        frag.mask |= 1 << s;
                        (frag.depth[s], frag.screen[s]) = self.depth_at(e, area);
                    }
                }
                if frag.mask != 0 {
                    f(frag);
                }
            }
        }
    }

    /// Depth and source-order barycentrics from edge functions.
    fn depth_at(&self, e: [i64; 3], area: f64) -> (f32, [f32; 3]) {
        let mut screen = [0.0f32; 3];
        let mut depth = 0.0f64;
        for (&ei, &src) in e.iter().zip(&self.order) {
            let w = ei as f64 / area;
            screen[src] = w as f32;
            depth += w * f64::from(self.z[src]);
        }
        (depth as f32, screen)
    }

    /// Perspective-correct barycentrics of the source corners from screen-space
    /// ones (what `@interpolate(perspective)` gives a fragment shader).
    pub fn perspective(&self, screen: [f32; 3]) -> [f32; 3] {
        let q = [0, 1, 2].map(|k| screen[k] * self.inv_w[k]);
        let sum = q[0] + q[1] + q[2];
        if sum > 0.0 {
            q.map(|v| v / sum)
        } else {
            screen
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Covered pixel centres of a screen-space triangle (either winding).
    fn cover(tri: [[f32; 2]; 3], w: u32, h: u32) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for t in [tri, [tri[0], tri[2], tri[1]]] {
            if let Some(s) = Setup::from_screen(t, [0.5; 3], [1.0; 3], w, h) {
                s.rasterize(|f| out.push((f.x, f.y)));
            }
        }
        out
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
    fn each_cull_mode_keeps_its_faces_and_coverage_ignores_winding() {
        let front = [[1.0f32, 1.0], [1.0, 9.0], [9.0, 1.0]];
        let back = [front[0], front[2], front[1]];
        let setup = |t, cull| Setup::from_screen_culled(t, [0.5; 3], [1.0; 3], 16, 16, cull);
        let pixels = |s: Option<Setup>| {
            let mut out = Vec::new();
            s.expect("kept")
                .rasterize(|f| out.push((f.x, f.y, f.screen)));
            out
        };
        assert!(setup(back, Cull::Back).is_none() && setup(front, Cull::Front).is_none());
        let a = pixels(setup(front, Cull::None));
        let b = pixels(setup(back, Cull::Front));
        assert!(!a.is_empty());
        assert_eq!(
            a.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(),
            b.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>()
        );
        // Barycentrics stay attached to the source corners whatever the winding.
        for (pa, pb) in a.iter().zip(&b) {
            let (sa, sb) = (pa.2, pb.2);
            assert!((sa[0] - sb[0]).abs() < 1e-6 && (sa[1] - sb[2]).abs() < 1e-6);
        }
        // Rows outside a band are skipped.
        let mut rows = Vec::new();
        setup(front, Cull::None)
            .unwrap()
            .rasterize_rows(3, 4, |f| rows.push(f.y));
        assert!(!rows.is_empty() && rows.iter().all(|&y| (3..=4).contains(&y)));
    }

    /// Samples covered by a screen-space triangle at `n` samples, per pixel.
    fn samples(tri: [[f32; 2]; 3], n: u32, w: u32) -> Vec<(u32, u32, u32)> {
        let clip = tri
            .map(|[x, y]| Vec4::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / w as f32 * 2.0, 0.5, 1.0));
        let mut out = Vec::new();
        if let Some(s) = Setup::from_clip_multisampled(clip, 0.0, w, w, Cull::None) {
            s.rasterize_samples(0, u32::MAX, &standard_samples(n), |f| {
                out.push((f.x, f.y, f.mask))
            });
        }
        out
    }

    #[test]
    fn one_sample_at_the_centre_is_the_single_sampled_rasterizer() {
        let tri = [[1.3f32, 0.7], [13.9, 4.1], [5.2, 14.6]];
        let single = cover(tri, 16, 16);
        let multi = samples(tri, 1, 16);
        assert_eq!(multi.len(), single.len());
        assert!(
            multi
                .iter()
                .all(|&(x, y, m)| m == 1 && single.contains(&(x, y)))
        );
    }

    #[test]
    fn sample_coverage_tracks_area_and_reaches_pixels_whose_centre_is_missed() {
        // A 0.4-pixel-wide horizontal sliver between two rows of centres.
        let sliver = [[0.0f32, 3.55], [16.0, 3.55], [0.0, 3.95]];
        assert!(samples(sliver, 1, 16).is_empty());
        for n in [4, 8] {
            let hits: u32 = samples(sliver, n, 16)
                .iter()
                .map(|&(_, y, m)| {
                    assert_eq!(y, 3);
                    m.count_ones()
                })
                .sum();
            assert!(hits > 0, "{n} samples: the sliver covers none");
        }
        // A large triangle: covered samples / n ≈ its area in pixels.
        let tri = [[0.5f32, 0.5], [30.5, 2.5], [8.5, 29.5]];
        let area = 0.5 * ((30.0f32 * 29.0) - (2.0 * 8.0));
        for n in [2, 4, 8] {
            let covered: u32 = samples(tri, n, 32).iter().map(|s| s.2.count_ones()).sum();
            let est = covered as f32 / n as f32;
            assert!((est - area).abs() < 0.03 * area, "{n}: {est} vs {area}");
        }
    }

    #[test]
    fn back_faces_and_degenerates_are_culled() {
        // Rows grow downwards, so (1,1) → (9,1) → (1,9) turns clockwise as
        // seen on the monitor: clockwise in NDC too, a back face.
        let back = [[1.0f32, 1.0], [9.0, 1.0], [1.0, 9.0]];
        let front = [back[0], back[2], back[1]];
        assert!(Setup::from_screen(back, [0.5; 3], [1.0; 3], 16, 16).is_none());
        assert!(Setup::from_screen(front, [0.5; 3], [1.0; 3], 16, 16).is_some());
        let line = [[1.0f32, 1.0], [5.0, 5.0], [9.0, 9.0]];
        assert!(Setup::from_screen(line, [0.5; 3], [1.0; 3], 16, 16).is_none());
        let nan = [[f32::NAN, 1.0], [9.0, 1.0], [1.0, 9.0]];
        assert!(Setup::from_screen(nan, [0.5; 3], [1.0; 3], 16, 16).is_none());
        let offscreen = [[-9.0f32, -9.0], [-1.0, -9.0], [-9.0, -1.0]];
        assert!(Setup::from_screen(offscreen, [0.5; 3], [1.0; 3], 16, 16).is_none());
    }

    #[test]
    fn depth_interpolates_linearly_and_attributes_perspectively() {
        let tri = [[0.5f32, 0.5], [0.5, 16.5], [16.5, 0.5]];
        let s = Setup::from_screen(tri, [0.0, 1.0, 0.5], [1.0, 0.25, 1.0], 32, 32).unwrap();
        let mut seen = 0;
        s.rasterize(|f| {
            seen += 1;
            let sum: f32 = f.screen.iter().sum();
            assert!((sum - 1.0).abs() < 1e-5);
            let lin = f.screen[1] + 0.5 * f.screen[2];
            assert!((f.depth - lin).abs() < 1e-6);
            let p = s.perspective(f.screen);
            // The far corner b (1/w = 0.25) gets less weight than on screen.
            assert!(p[1] <= f.screen[1] + 1e-6);
        });
        assert!(seen > 100);
    }
}
