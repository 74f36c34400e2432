//! `kulikov.sort_scan` and `kulikov.sort`: a global counting sort of visible
//! segments into tile-sized screen buckets.
//!
//! Kulikov, "L2 cache is your friend": "Global counting sort. Populate sorting
//! bins in visibility culling pass. Do a prefix sum on buckets. Write
//! partially sorted segment indices." The scan also writes the raster's
//! indirect dispatch. With sorting off, segments keep arrival order (random,
//! since strands are shuffled for LOD): the talk's "unsorted" baseline.

use super::cull::{DrawnSegment, GROUP as CULL_GROUP, drawn_blocks, nth_drawn, screen_bin};
use super::{Scene, clip_to_screen};
use crate::common::clip::near_clip;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::{NoParams, PassParams};
use strandgraph_graph::Quantities;
use strandgraph_graph::schema::Quantity;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SortParams {
    /// Off: segments keep arrival order (the talk's "unsorted" baseline).
    pub enabled: bool,
    /// Ours: one atomicAdd per subgroup and bucket instead of one per
    /// segment; the subgroup's segments of a bucket take consecutive slots.
    pub wave_aggregated_atomics: bool,
}

impl Default for SortParams {
    fn default() -> Self {
        Self {
            enabled: true,
            wave_aggregated_atomics: true,
        }
    }
}

impl PassParams for SortParams {}

crate::gpu_block! {
    /// The WGSL `SortParams` block of both entry points in shaders/kulikov/sort.wgsl.
    pub struct SortGpu {
        /// kulikov.sort `enabled` (scatter only).
        enabled: u32,
        /// Scene quantity: segments in the full numbering.
        segments: u32,
        /// Sort bins (64x64 screen tiles).
        bins: u32,
        /// kulikov.sort `wave_aggregated_atomics` (scatter only).
        aggregate: u32,
    }
}

fn sort_gpu(p: SortParams, q: &Quantities) -> SortGpu {
    SortGpu {
        enabled: flag(p.enabled),
        segments: count(q.segments),
        bins: count(q.count(Quantity::Tiles(super::TILE))),
        aggregate: flag(p.wave_aggregated_atomics),
    }
}

pub static SORT_SCAN: PassKind<NoParams, SortGpu> = PassKind {
    kind: "kulikov.sort_scan",
    summary: "prefix sum over sort buckets; writes the raster's indirect dispatch",
    source: "Kulikov 2025, 'Sort everything!'",
    bindings: Some(&[
        Binding::read("sort_bins"),
        Binding::write("sort_offsets"),
        Binding::write("raster_args"),
    ]),
    // One workgroup: lanes scan runs of bins in parallel (shaders/kulikov/sort.wgsl).
    workgroup_size: 256,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("kulikov/sort.wgsl", "scan"),
    kernel: |_| Box::new(ScanKernel),
    // The switches are the scatter's.
    gpu: |_, q| sort_gpu(SortParams::default(), q),
    raster: None,
};

pub static SORT: PassKind<SortParams, SortGpu> = PassKind {
    kind: "kulikov.sort",
    summary: "global counting sort of visible segments by screen bucket",
    source: "Kulikov 2025, 'Sort everything!'",
    bindings: Some(&[
        Binding::read("frame"),
        Binding::read("models"),
        Binding::read("lod_models"),
        Binding::read("clip_positions"),
        Binding::read("segment_visibility"),
        Binding::atomic("sort_offsets"),
        Binding::write("sorted_segments"),
        Binding::read("lod_args"),
    ]),
    workgroup_size: CULL_GROUP,
    // Over the drawn segments only (cull::nth_drawn).
    dispatch: Dispatch::Indirect {
        binding: "lod_args",
        word: 4,
    },
    shader: Shader::compute("kulikov/sort.wgsl", "scatter"),
    kernel: |p| Box::new(ScatterKernel(*p)),
    gpu: |p, q| sort_gpu(*p, q),
    raster: None,
};

struct ScanKernel;

impl CpuKernel for ScanKernel {
    fn run_workgroup(&self, _: u32, ctx: &Ctx<'_>) {
        let bins = ctx.quantities.count(Quantity::Tiles(super::TILE)) as usize;
        let (counts, offsets, args) = (
            ctx.words("sort_bins"),
            ctx.words("sort_offsets"),
            ctx.words("raster_args"),
        );
        let mut sum = 0u32;
        for b in 0..bins {
            offsets.store(b, sum);
            sum += counts.load(b);
        }
        // Header after the bins: the arrival counter the unsorted variant uses.
        offsets.store(bins, 0);
        args.store(0, sum.div_ceil(super::raster::GROUP));
        args.store(1, 1);
        args.store(2, 1);
        args.store(3, sum);
    }
}

struct ScatterKernel(SortParams);

impl ScatterKernel {
    /// The bucket drawn segment `seg` goes to (the WGSL's `bucket`),
    /// `None` when it is not visible.
    fn bucket(&self, scene: &Scene, ctx: &Ctx<'_>, seg: &DrawnSegment) -> Option<u32> {
        let (bits, id) = (ctx.words("segment_visibility"), seg.id);
        if u64::from(id) >= ctx.quantities.segments
            || bits.load((id / 32) as usize) & (1 << (id % 32)) == 0
        {
            return None;
        }
        if !self.0.enabled {
            return Some(ctx.quantities.count(Quantity::Tiles(super::TILE)) as u32);
        }
        let clip = ctx.words("clip_positions");
        let (c0, c1) = (
            clip.load_vec4(seg.v0 as usize),
            clip.load_vec4(seg.v1 as usize),
        );
        // The bin the cull counted: that of the part in front of the near plane.
        let part = near_clip(c0, c1, scene.frame.near)?;
        let (w, h) = (scene.frame.screen[0], scene.frame.screen[1]);
        Some(screen_bin(
            w,
            h,
            clip_to_screen(part.a, w, h),
            clip_to_screen(part.b, w, h),
        ))
    }
}

impl CpuKernel for ScatterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let (offsets, out) = (ctx.words("sort_offsets"), ctx.words("sorted_segments"));
        let width = if self.0.wave_aggregated_atomics {
            ctx.subgroup_width.max(1)
        } else {
            1
        };
        for (first, sub) in drawn_blocks(ctx, group)
            .flat_map(|first| (0..CULL_GROUP.div_ceil(width)).map(move |sub| (first, sub)))
        {
            let lanes = sub * width..((sub + 1) * width).min(CULL_GROUP);
            let keyed: Vec<(u32, u32)> = lanes
                .filter_map(|l| nth_drawn(&scene, &lods, first + l))
                .filter_map(|seg| Some((self.bucket(&scene, ctx, &seg)?, seg.id)))
                .collect();
            // Buckets in ascending order (the subgroupMin loop), one atomic
            // each; the lanes of a bucket in lane order.
            let mut buckets: Vec<u32> = keyed.iter().map(|&(k, _)| k).collect();
            buckets.sort_unstable();
            buckets.dedup();
            for k in buckets {
                let lanes: Vec<u32> = keyed
                    .iter()
                    .filter(|&&(b, _)| b == k)
                    .map(|&(_, id)| id)
                    .collect();
                let base = offsets.fetch_add(k as usize, lanes.len() as u32);
                for (rank, id) in lanes.into_iter().enumerate() {
                    out.store(base as usize + rank, id);
                }
            }
        }
    }
}
