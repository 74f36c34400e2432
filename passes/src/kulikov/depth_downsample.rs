//! `kulikov.depth_downsample`: the farthest scene depth of each 16×16 block.
//!
//! Kulikov, "Culling": "Occlusion cull against downscaled depth (1/16 on each
//! axis) ... just using 16x downscaled depth buffer was enough." A segment is
//! occluded when it is behind the farthest depth of every block it touches.
//!
//! One workgroup per block, one lane per texel: the farthest depth is an
//! `atomicMax` on the depth bits in workgroup memory (depths are in [0, 1],
//! and non-negative floats order like their bits). A lane per block reading
//! 256 texels in a row took 0.034 ms at 1080p on an H100, latency-bound.

use crate::contract::{Binding, CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::{Ctx, Words};
use crate::params::NoParams;
use strandgraph_graph::schema::Quantity;

/// Block edge in pixels.
pub const FACTOR: u32 = 16;
/// A box over more blocks than this is not tested against the Hi-Z
/// ([`farthest`]): long segments are not worth the reads.
pub const MAX_BLOCKS: u32 = 16;
/// One lane per texel of a block.
const GROUP: u32 = FACTOR * FACTOR;

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
        per_group: 1,
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
        let Some(pixels) = block_pixels(group, w, h) else {
            return;
        };
        let (depth, hiz) = (ctx.words("scene.depth"), ctx.words("hiz"));
        // The lanes' atomicMax on the bits.
        let far = pixels
            .map(|(x, y)| depth_bits(depth.load_f32((y * w + x) as usize)))
            .max()
            .unwrap_or(0);
        hiz.store(group as usize, far);
    }
}

/// The pixels of Hi-Z block `block` of a `w`×`h` screen, the blocks
/// numbered row by row; `None` past the last block (shaders/common/hiz.wgsl,
/// `hiz_block_pixel`).
pub fn block_pixels(block: u32, w: u32, h: u32) -> Option<impl Iterator<Item = (u32, u32)>> {
    let blocks_x = w.div_ceil(FACTOR);
    if block >= blocks_x * h.div_ceil(FACTOR) {
        return None;
    }
    let (bx, by) = (block % blocks_x * FACTOR, block / blocks_x * FACTOR);
    Some(
        (by..(by + FACTOR).min(h))
            .flat_map(move |y| (bx..(bx + FACTOR).min(w)).map(move |x| (x, y))),
    )
}

/// A depth's bits, ordered as the depths (`hiz_bits`): depths are in
/// [0, 1], and clearing the sign keeps a -0.0 from ordering above them all.
pub fn depth_bits(z: f32) -> u32 {
    z.to_bits() & 0x7FFF_FFFF
}

/// The farthest depth in `hiz` (a screen `width` pixels wide) over the
/// blocks that pixel box `bounds` (x0, y0, x1, y1, inclusive, on screen)
/// touches; `None` when it touches more than [`MAX_BLOCKS`]. The test
/// `kulikov.cull` and `lipp.raster` share (shaders/common/hiz.wgsl).
pub fn farthest(hiz: &Words<'_>, width: u32, bounds: [u32; 4]) -> Option<f32> {
    let [tx0, ty0, tx1, ty1] = bounds.map(|b| b / FACTOR);
    if (tx1 - tx0 + 1) * (ty1 - ty0 + 1) > MAX_BLOCKS {
        return None;
    }
    let hw = width.div_ceil(FACTOR);
    let far = (ty0..=ty1)
        .flat_map(|ty| (tx0..=tx1).map(move |tx| (ty * hw + tx) as usize))
        .map(|i| hiz.load_f32(i))
        .fold(0.0f32, f32::max);
    Some(far)
}
