//! `kulikov.pixel_motion`: per-pixel motion vectors for the composed frame.
//!
//! Kulikov, "Composition": "Output lighting, depth and motion", and "Motion
//! vectors": "we need positions per pixel to calculate motion vectors". Per
//! pixel, after composition has written hair depth:
//! - **hair** (a model's front layer is where composition wrote the depth):
//!   the front segment's `vertex_motion`, interpolated at the pixel centre's
//!   projection on the segment as composition interpolates lighting. This is
//!   the talk's path: motion from the post-transform cache history, so
//!   skinned and simulated motion shows, and a vertex the previous frame did
//!   not transform has none;
//! - **everything else with depth** (the opaque head; hair too thin to write
//!   depth): the depth reprojected with last frame's camera (`prev_frame`,
//!   a History copy of `frame`), which sees camera motion only;
//! - background, and every pixel of the first frame: zero.
//!
//! `pixel_motion` holds two f32 per pixel: this frame's position minus last
//! frame's, in pixels, y down (as `vertex_motion`). It reads the final hair
//! depth (`hair_depth`, written by `kulikov.compose`), so it runs after
//! composition; folding it into the composition pass, as the talk does, is
//! still to do.
//!
//! Deviation: composition samples downscaled tiles with a Poisson jitter;
//! motion takes the pixel's own texel (a jittered sample's segment would
//! rarely be the one whose depth composition wrote).

use super::compose::{axis_t, ndc_depth};
use super::cull::drawn_segment;
use super::payload::{EMPTY, segment_of};
use super::raster::{LAYERS, segment_trapezoid};
use super::{Scene, TILE};
use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::layout::{FrameData, read};
use crate::params::NoParams;
use glam::{Mat4, Vec4};
use strandgraph_graph::schema::Quantity;

const GROUP: u32 = 64;
/// How close (NDC depth) a front layer must be to the pixel's depth to be
/// the hair composition wrote there: composition computed the same value,
/// up to the rounding of another shader stage.
pub const DEPTH_MATCH: f32 = 1e-6;

crate::gpu_block! {
    /// `PixelMotionParams`: width, height, two pad words.
    pub struct PixelMotionGpu {
        width: u32,
        height: u32,
        _pad0: u32,
        _pad1: u32,
    }
}

pub static PIXEL_MOTION: PassKind<NoParams, PixelMotionGpu> = PassKind {
    kind: "kulikov.pixel_motion",
    summary: "per-pixel motion: the front hair segment's interpolated vertex motion where composition wrote its depth, else the depth reprojected with last frame's camera",
    source: "Kulikov 2025, 'Composition', 'Motion vectors'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("prev_frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("atlas_tiles"),
        Binding::read("vis_atlas"),
        Binding::read("clip_positions"),
        Binding::read("groom.vertices"),
        Binding::read("vertex_motion"),
        Binding::read("hair_depth"),
        Binding::write("pixel_motion"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Pixels,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/pixel_motion.wgsl", "resolve_motion"),
    kernel: |_| Box::new(PixelMotionKernel),
    gpu: |_, q| PixelMotionGpu {
        width: q.width,
        height: q.height,
        ..PixelMotionGpu::default()
    },
    raster: None,
};

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

struct PixelMotionKernel;

impl CpuKernel for PixelMotionKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let prev: FrameData = read(&ctx.words("prev_frame"), 0);
        let (lods, tiles) = (scene.lods(ctx), scene.tiles(ctx));
        let (vis, motion, depth, out) = (
            ctx.words("vis_atlas"),
            ctx.words("vertex_motion"),
            ctx.words("hair_depth"),
            ctx.words("pixel_motion"),
        );
        let stride = vis.len() / LAYERS;
        let (width, pixels) = (ctx.quantities.width, ctx.quantities.count(Quantity::Pixels));
        let (near, far) = (scene.frame.near, scene.frame.far);
        for i in group * GROUP..((group + 1) * GROUP).min(pixels as u32) {
            let (x, y) = (i % width, i / width);
            let z = depth.load_f32(i as usize);
            let mut m = [0.0f32; 2];
            if z < 1.0 {
                // The model whose front layer composition wrote here, if any.
                let mut best: Option<(f32, [f32; 2])> = None;
                for (mi, t) in tiles.iter().enumerate() {
                    let Some(texel) = t.texel(x, y) else { continue };
                    let p = vis.load(texel as usize);
                    if stride == 0 || p == EMPTY {
                        continue;
                    }
                    let id = scene.models[mi].segment_first + segment_of(p);
                    let Some(seg) = drawn_segment(&scene, &lods, id) else {
                        continue;
                    };
                    let Some((trap, _)) =
                        segment_trapezoid(&scene, ctx, t, &lods[mi], seg.v0, seg.v1)
                    else {
                        continue;
                    };
                    let u = (x / t.downscale - t.origin_x * TILE) as i32;
                    let v = (y / t.downscale - t.origin_y * TILE) as i32;
                    let dz = (ndc_depth(trap.depth_at(u, v), near, far) - z).abs();
                    if dz <= DEPTH_MATCH && best.is_none_or(|(b, _)| dz < b) {
                        let s = axis_t(&trap, u, v);
                        let (a, b) = (seg.v0 as usize, seg.v1 as usize);
                        let lerp = |k: usize| {
                            let (ma, mb) = (motion.load_f32(2 * a + k), motion.load_f32(2 * b + k));
                            ma + s * (mb - ma)
                        };
                        best = Some((dz, [lerp(0), lerp(1)]));
                    }
                }
                m = match best {
                    Some((_, hair)) => hair,
                    None => reprojected(&scene.frame, &prev, x, y, z).unwrap_or([0.0; 2]),
                };
            }
            out.store_f32(2 * i as usize, m[0]);
            out.store_f32(2 * i as usize + 1, m[1]);
        }
    }
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
