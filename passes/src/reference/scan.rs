//! `reference.scan`: the tiles' list offsets, an exclusive prefix sum of
//! the counts `reference.count` left, and after them the total the frame
//! needs (which [`super::check_lists`] compares with the lists' size).
//!
//! One workgroup: each lane sums a run of consecutive tiles, the lanes'
//! sums are scanned in workgroup memory, then each lane writes its run (the
//! shape of `kulikov.sort_scan`).

use super::TILE;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::NoParams;
use strandgraph_graph::schema::Quantity;

pub const LANES: u32 = 256;

crate::gpu_block! {
    /// `ScanParams` in shaders/reference/scan.wgsl.
    pub struct ScanGpu {
        tiles: u32,
    }
}

pub static SCAN: PassKind<NoParams, ScanGpu> = PassKind {
    kind: "reference.scan",
    summary: "prefix sum of the reference's per-tile segment counts, and their total",
    source: "ours: the ground-truth reference (docs/reference.md)",
    bindings: Some(&[
        Binding::read("reference_counts"),
        Binding::write("reference_offsets"),
    ]),
    workgroup_size: LANES,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("reference/scan.wgsl", "scan"),
    kernel: |_| Box::new(ScanKernel),
    gpu: |_, q| ScanGpu {
        tiles: count(q.count(Quantity::Tiles(TILE))),
    },
    raster: None,
};

struct ScanKernel;

impl CpuKernel for ScanKernel {
    fn run_workgroup(&self, _: u32, ctx: &Ctx<'_>) {
        let tiles = ctx.quantities.count(Quantity::Tiles(TILE)) as usize;
        let (counts, offsets) = (
            ctx.words("reference_counts"),
            ctx.words("reference_offsets"),
        );
        let mut sum = 0u32;
        for t in 0..tiles {
            offsets.store(t, sum);
            sum = sum.wrapping_add(counts.load(t));
        }
        offsets.store(tiles, sum);
    }
}
