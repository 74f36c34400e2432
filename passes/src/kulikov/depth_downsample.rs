//! `kulikov.depth_downsample`: the farthest scene depth of each 16×16 block.
//!
//! Kulikov, "Culling": "Occlusion cull against downscaled depth (1/16 on each
//! axis) ... just using 16x downscaled depth buffer was enough." A segment is
//! occluded when it is behind the farthest depth of every block it touches.

use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::NoParams;
use strandgraph_graph::schema::Quantity;

/// Block edge in pixels.
pub const FACTOR: u32 = 16;
const GROUP: u32 = 64;

crate::gpu_block! {
    /// `DepthDownsampleParams`: the full-resolution screen size.
    pub struct DepthDownsampleGpu {
        width: u32,
        height: u32,
    }
}

pub static DEPTH_DOWNSAMPLE: PassKind<NoParams, DepthDownsampleGpu> = PassKind {
    kind: "kulikov.depth_downsample",
    summary: "1/16 downscaled max depth for segment occlusion culling",
    source: "Kulikov 2025, 'Culling'",
    bindings: Some(&[Binding::read("scene.depth"), Binding::write("hiz")]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Tiles(FACTOR),
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/depth_downsample.wgsl", "downsample"),
    kernel: |_| Box::new(DownsampleKernel),
    gpu: |_, q| DepthDownsampleGpu {
        width: q.width,
        height: q.height,
    },
    raster: None,
};

struct DownsampleKernel;

impl CpuKernel for DownsampleKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let hw = w.div_ceil(FACTOR);
        let (depth, hiz) = (ctx.words("scene.depth"), ctx.words("hiz"));
        for lane in 0..GROUP {
            let i = group * GROUP + lane;
            if i >= hw * h.div_ceil(FACTOR) {
                break;
            }
            let (bx, by) = (i % hw * FACTOR, i / hw * FACTOR);
            let mut far = 0.0f32;
            for y in by..(by + FACTOR).min(h) {
                for x in bx..(bx + FACTOR).min(w) {
                    far = far.max(depth.load_f32((y * w + x) as usize));
                }
            }
            hiz.store_f32(i as usize, far);
        }
    }
}
