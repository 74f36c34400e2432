//! `scene.depth_attachment`: `scene.depth` into a `D32Float` depth
//! attachment, for the hair passes that draw through the hardware
//! rasterizer (Scheuermann's patches) and must be hidden by the head.
//!
//! `scene.depth` is written in compute (`scene.depth_resolve`), and no API
//! lets a compute shader write a depth attachment, so on the GPU backends
//! this is a raster pass (`shaders/opaque_mesh/depth_attachment.wgsl`): one
//! triangle over the screen writes each texel's depth with `frag_depth`,
//! compare `Always`, so the copy is exact. The CPU kernel copies the words.

use super::{PIXEL_GROUP, pixel_dispatch};
use crate::contract::{Binding, CpuKernel, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::NoParams;
use crate::raster_state::{
    Blend, ColorLoad, Compare, Cull, DepthLoad, Draw, Geometry, RasterState,
};
use strandgraph_graph::Quantities;

crate::gpu_block! {
    /// `DepthAttachmentParams`: one unused word.
    pub struct DepthAttachmentGpu {
        unused: u32,
    }
}

pub static DEPTH_ATTACHMENT: PassKind<NoParams, DepthAttachmentGpu> = PassKind {
    kind: "scene.depth_attachment",
    summary: "scene depth copied into the depth attachment of the hardware-raster hair passes",
    source: "strandgraph",
    bindings: Some(&[Binding::read("scene.depth"), Binding::write("depth_buffer")]),
    workgroup_size: PIXEL_GROUP,
    dispatch: pixel_dispatch(),
    shader: Shader {
        file: "opaque_mesh/depth_attachment.wgsl",
        entry: "vs_main",
        fragment: Some("fs_main"),
    },
    kernel: |_| Box::new(CopyKernel),
    gpu: |_, _| DepthAttachmentGpu::default(),
    raster: Some(draw),
};

/// One full-screen triangle writing `frag_depth` wherever it lands.
fn draw(_: &NoParams, _: &Quantities) -> RasterState {
    RasterState {
        geometry: Geometry::Vertices(3),
        cull: Cull::None,
        color_load: ColorLoad::Load,
        depth_load: DepthLoad::Clear(1.0),
        draws: vec![Draw {
            fragment: "fs_main",
            blend: Blend::Replace,
            color_writes: false,
            depth_compare: Compare::Always,
            depth_write: true,
        }],
    }
}

struct CopyKernel;

impl CpuKernel for CopyKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let q = ctx.quantities;
        let pixels = q.width as usize * q.height as usize;
        let (from, to) = (ctx.words("scene.depth"), ctx.words("depth_buffer"));
        // A multisampled attachment: `samples` words per pixel, each the
        // texel's depth (frag_depth is written to every covered sample).
        let samples = (to.len() / pixels.max(1)).max(1);
        let first = group as usize * PIXEL_GROUP as usize;
        for i in first..(first + PIXEL_GROUP as usize).min(pixels) {
            let d = from.load(i);
            for s in 0..samples {
                to.store(i * samples + s, d);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{frame, harness, head, render, run};
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_attachment_holds_scene_depth_bit_for_bit() {
        let f = frame(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 35.0, 48, 32);
        let mut hs = harness(f, &head(), &[]);
        hs.buffer("depth_buffer", vec![0; 48 * 32]);
        render(&hs);
        run(&hs, &DEPTH_ATTACHMENT);
        assert_eq!(hs.out_of_bounds(), 0);
        let depth = hs.read("scene.depth");
        assert!(depth.iter().any(|&d| d != 1.0f32.to_bits()));
        assert_eq!(hs.read("depth_buffer"), depth);
    }
}
