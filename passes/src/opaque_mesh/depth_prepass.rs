//! `scene.depth_prepass`: opaque meshes (heads, bodies) into `scene.depth`.
//!
//! `scene.depth` is a `D32Float` screen image: one word per texel, row-major,
//! holding the f32 bits of NDC depth z/w (glam `perspective_rh`: 0 at the
//! near plane, 1 at the far plane). The prologue clears it to 1.0, the render
//! pass's load op; each lane rasterizes one triangle and keeps the nearest
//! depth with `atomicMin` on the bits, which order like the floats because
//! depths are non-negative (IEEE 754 positive floats sort as unsigned ints).
//! The result is therefore independent of triangle and workgroup order.
//!
//! On the GPU backends this is a depth-only raster pipeline
//! (`shaders/opaque_mesh/depth_prepass.wgsl`): depth attachment cleared to 1.0,
//! compare `Less`, writes on, `FrontFace::Ccw`, `CullMode::Back`.

use super::{GROUP, View, clear, dispatch};
use crate::contract::{Binding, CpuKernel, Shader};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx};
use crate::params::NoParams;
use crate::raster_state::{Blend, ColorLoad, Compare, DepthLoad, Draw, RasterState};
use strandgraph_graph::Quantities;

crate::gpu_block! {
    /// `DepthPrepassParams`: one unused word.
    pub struct DepthPrepassGpu {
        unused: u32,
    }
}

pub static DEPTH_PREPASS: PassKind<NoParams, DepthPrepassGpu> = PassKind {
    kind: "scene.depth_prepass",
    summary: "rasterize opaque meshes (heads, bodies) into scene depth",
    source: "strandgraph",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("mesh.triangles"),
        Binding::write("scene.depth"),
    ]),
    workgroup_size: GROUP,
    dispatch: dispatch(),
    shader: Shader {
        file: "opaque_mesh/depth_prepass.wgsl",
        entry: "vs_main",
        fragment: Some("fs_main"),
    },
    kernel: |_| Box::new(PrepassKernel),
    gpu: |_, _| DepthPrepassGpu::default(),
    raster: Some(draw),
};

/// The prologue's clear to 1.0, then `fetch_min` of depth: Less, written.
fn draw(_: &NoParams, q: &Quantities) -> RasterState {
    RasterState {
        vertices: q.triangles * 3,
        cull_back_faces: true,
        color_load: ColorLoad::Load,
        depth_load: DepthLoad::Clear(1.0),
        draws: vec![Draw {
            fragment: "fs_main",
            blend: Blend::Replace,
            color_writes: true,
            depth_compare: Compare::Less,
            depth_write: true,
        }],
    }
}

struct PrepassKernel;

impl CpuKernel for PrepassKernel {
    fn prologue(&self, ctx: &Ctx<'_>) {
        clear(&ctx.words("scene.depth"), 1.0f32.to_bits());
    }

    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let view = View::load(ctx);
        let depth = ctx.words("scene.depth");
        let mut local = CounterValues::default();
        view.for_each_triangle(group, |_, setup| {
            setup.rasterize(|f| {
                // Depth clipping: hardware discards fragments outside [0, 1].
                if (0.0..=1.0).contains(&f.depth) {
                    depth.fetch_min(view.texel(f.x, f.y), f.depth.to_bits());
                    local.atomics += 1;
                }
            });
        });
        if ctx.instrument {
            ctx.counters.add(&local);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{frame, harness, head, run, triangle};
    use super::*;
    use glam::Vec3;

    /// Linear view depth from NDC depth for `perspective_rh(near, far)`.
    fn view_depth(z: f32, near: f32, far: f32) -> f32 {
        near * far / (far - z * (far - near))
    }

    #[test]
    fn nearer_triangle_wins_whatever_the_order() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        // Counter-clockwise seen from +z (the camera): front faces.
        let near = triangle(
            Vec3::new(-0.2, -0.2, 0.1),
            Vec3::new(0.2, -0.2, 0.1),
            Vec3::new(0.0, 0.2, 0.1),
            Vec3::Z,
        );
        let far = triangle(
            Vec3::new(-0.3, -0.3, -0.1),
            Vec3::new(0.3, -0.3, -0.1),
            Vec3::new(0.0, 0.3, -0.1),
            Vec3::Z,
        );
        let mut results = Vec::new();
        for tris in [[near, far], [far, near]] {
            let hs = harness(f, &tris, &[]);
            run(&hs, &DEPTH_PREPASS);
            assert_eq!(hs.out_of_bounds(), 0);
            results.push(hs.read("scene.depth"));
        }
        assert_eq!(results[0], results[1]);
        let centre = f32::from_bits(results[0][16 * 32 + 16]);
        assert!(
            (view_depth(centre, f.near, f.far) - 0.9).abs() < 1e-3,
            "{centre}"
        );
        // The far triangle still shows around the near one; the corners stay clear.
        assert!(results[0].iter().any(|&d| {
            let v = view_depth(f32::from_bits(d), f.near, f.far);
            (v - 1.1).abs() < 1e-3
        }));
        assert_eq!(results[0][0], 1.0f32.to_bits());
    }

    #[test]
    fn back_faces_are_culled() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        let (a, b, c) = (
            Vec3::new(-0.2, -0.2, 0.0),
            Vec3::new(0.2, -0.2, 0.0),
            Vec3::new(0.0, 0.2, 0.0),
        );
        let covered = |t| {
            let hs = harness(f, &[t], &[]);
            run(&hs, &DEPTH_PREPASS);
            hs.read("scene.depth")
                .iter()
                .filter(|&&d| d != 1.0f32.to_bits())
                .count()
        };
        assert!(covered(triangle(a, b, c, Vec3::Z)) > 20);
        assert_eq!(covered(triangle(a, c, b, -Vec3::Z)), 0);
    }

    #[test]
    fn triangles_behind_the_near_plane_are_dropped() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 40.0, 32, 32);
        // One corner behind the camera.
        let t = triangle(
            Vec3::new(-0.2, -0.2, 0.0),
            Vec3::new(0.2, -0.2, 0.0),
            Vec3::new(0.0, 0.2, 2.0),
            Vec3::Z,
        );
        let hs = harness(f, &[t], &[]);
        run(&hs, &DEPTH_PREPASS);
        assert!(
            hs.read("scene.depth")
                .iter()
                .all(|&d| d == 1.0f32.to_bits())
        );
        assert_eq!(hs.out_of_bounds(), 0);
    }

    #[test]
    fn procedural_head_faces_the_camera() {
        // 1 m in front of the face (+z), 128×128.
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 35.0, 128, 128);
        let tris = head();
        let hs = harness(f, &tris, &[]);
        run(&hs, &DEPTH_PREPASS);
        assert_eq!(hs.out_of_bounds(), 0);
        let depth = hs.read("scene.depth");
        let covered = depth.iter().filter(|&&d| d != 1.0f32.to_bits()).count();
        let fraction = covered as f64 / depth.len() as f64;
        assert!(fraction > 0.05 && fraction < 0.8, "{fraction}");
        // With the right winding we see the face (z = +half_depth, 0.902 m
        // away), not the back of the skull (1.098 m) through a culled front.
        let centre = view_depth(f32::from_bits(depth[64 * 128 + 64]), f.near, f.far);
        assert!((centre - 0.902).abs() < 0.01, "centre at {centre} m");
    }
}
