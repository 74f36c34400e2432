//! `kulikov.depth_downsample`: the farthest scene depth of each 16×16 block.
//!
//! Kulikov, "Culling": "Occlusion cull against downscaled depth (1/16 on each
//! axis) ... just using 16x downscaled depth buffer was enough." A segment is
//! occluded when it is behind the farthest depth of every block it touches.

use crate::contract::{Binding, CpuKernel, Dispatch, ParamError, PassDef, Shader};
use crate::sim::Ctx;
use strandgraph_graph::schema::Quantity;

pub struct DepthDownsample;

/// Block edge in pixels.
pub const FACTOR: u32 = 16;
const GROUP: u32 = 64;

impl PassDef for DepthDownsample {
    fn kind(&self) -> &'static str {
        "kulikov.depth_downsample"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        const BINDINGS: &[Binding] = &[Binding::read("scene.depth"), Binding::write("hiz")];
        Some(BINDINGS)
    }
    fn workgroup_size(&self) -> u32 {
        GROUP
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::PerElement {
            quantity: Quantity::Tiles(FACTOR),
            per_group: GROUP,
        }
    }
    fn shader(&self) -> Shader {
        Shader::compute("kulikov/hiz.wgsl", "downsample")
    }
    fn cpu_kernel(&self, _: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        Ok(Box::new(DownsampleKernel))
    }
    /// `HizParams`: the full-resolution screen size.
    fn gpu_params(
        &self,
        _: &ron::Value,
        q: &strandgraph_graph::Quantities,
    ) -> Result<Vec<u32>, ParamError> {
        Ok(vec![q.width, q.height])
    }
}

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
