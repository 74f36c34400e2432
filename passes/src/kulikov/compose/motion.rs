//! Per-pixel motion, written by composition (Kulikov, "Composition":
//! "Output lighting, depth and motion"; "Motion vectors": "we need positions
//! per pixel to calculate motion vectors"). Per pixel, as composition
//! decides its depth:
//! - **hair** (a model's front layer wrote the pixel's depth): that
//!   segment's `vertex_motion`, interpolated where composition interpolates
//!   its lighting ([`super::axis_t`]) at the atlas sample composition read.
//!   This is the talk's path: motion from the post-transform cache history,
//!   so skinned and simulated motion shows, and a vertex the previous frame
//!   did not transform has none;
//! - **everything else with depth** (the opaque head; hair too thin to
//!   write depth): the depth reprojected with last frame's camera
//!   (`prev_frame`, a History copy of `frame`), which sees camera motion only;
//! - background, and every pixel of the first frame: zero.
//!
//! `pixel_motion` holds two f32 per pixel: this frame's position minus last
//! frame's, in pixels, y down (as `vertex_motion`).

use crate::kernel::Words;
use crate::layout::FrameData;
use glam::{Mat4, Vec4};

/// The front hair layer that wrote a pixel's depth: its segment's vertices
/// and where along it the pixel's sample projects.
#[derive(Debug, Clone, Copy)]
pub struct Front {
    pub ends: [u32; 2],
    pub t: f32,
}

/// The motion of pixel `(x, y)` whose composed NDC depth is `z`.
pub fn pixel_motion(
    front: Option<Front>,
    vertex_motion: &Words<'_>,
    now: &FrameData,
    prev: &FrameData,
    (x, y): (u32, u32),
    z: f32,
) -> [f32; 2] {
    if let Some(f) = front {
        let (a, b) = (f.ends[0] as usize, f.ends[1] as usize);
        let lerp = |k: usize| {
            let (ma, mb) = (
                vertex_motion.load_f32(2 * a + k),
                vertex_motion.load_f32(2 * b + k),
            );
            ma + f.t * (mb - ma)
        };
        return [lerp(0), lerp(1)];
    }
    if z < 1.0 {
        return reprojected(now, prev, x, y, z).unwrap_or([0.0; 2]);
    }
    [0.0; 2]
}

/// Motion of the surface at pixel `(x, y)` with NDC depth `z` under a pure
/// camera move from `prev` to `now`; `None` without a previous camera or
/// where it had the point behind its near plane.
pub fn reprojected(now: &FrameData, prev: &FrameData, x: u32, y: u32, z: f32) -> Option<[f32; 2]> {
    if prev.screen[0] <= 0.0 {
        return None; // the first frame: History starts zeroed
    }
    let (w, h) = (now.screen[0], now.screen[1]);
    let ndc = [
        (x as f32 + 0.5) / w * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / h * 2.0,
    ];
    let world = Mat4::from_cols_array(&now.inv_view_proj) * Vec4::new(ndc[0], ndc[1], z, 1.0);
    let c = Mat4::from_cols_array(&prev.view_proj) * (world / world.w);
    if !(c.w > prev.near) {
        return None;
    }
    let (px, py) = (c.x / c.w, c.y / c.w);
    Some([(ndc[0] - px) * 0.5 * w, (py - ndc[1]) * 0.5 * h])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::opaque_mesh::testing::frame;
    use glam::Vec3;

    #[test]
    fn reprojection_follows_a_sideways_camera_move() {
        let (w, h) = (64, 36);
        let prev = frame(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0, w, h);
        let now = frame(
            Vec3::new(0.1, 0.0, 3.0),
            Vec3::new(0.1, 0.0, 0.0),
            40.0,
            w,
            h,
        );
        // The origin, seen by both cameras: project it with each.
        let at = |f: &FrameData| {
            let c = Mat4::from_cols_array(&f.view_proj) * Vec4::new(0.0, 0.0, 0.0, 1.0);
            (
                c / c.w,
                (
                    (c.x / c.w + 1.0) * 0.5 * w as f32,
                    (1.0 - c.y / c.w) * 0.5 * h as f32,
                ),
            )
        };
        let ((c_now, (x, y)), (_, (px, _))) = (at(&now), at(&prev));
        let m = reprojected(&now, &prev, x as u32, y as u32, c_now.z).unwrap();
        // Moving right makes the origin move left on screen.
        assert!(px - x > 1.0, "{px} {x}");
        assert!((m[0] - (x - px)).abs() < 0.6, "{m:?} vs {}", x - px);
        assert!(m[1].abs() < 0.6, "{m:?}");
        // No previous frame yet: no motion.
        let zeroed = bytemuck::Zeroable::zeroed();
        assert!(reprojected(&now, &zeroed, 3, 3, 0.5).is_none());
    }
}
