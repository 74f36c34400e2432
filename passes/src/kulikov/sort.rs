//! `kulikov.sort_scan` and `kulikov.sort`: a global counting sort of visible
//! segments into tile-sized screen buckets.
//!
//! Kulikov, "L2 cache is your friend": "Global counting sort. Populate sorting
//! bins in visibility culling pass. Do a prefix sum on buckets. Write
//! partially sorted segment indices." The scan also writes the raster's
//! indirect dispatch. With sorting off, segments keep arrival order (random,
//! since strands are shuffled for LOD): the talk's "unsorted" baseline.

use super::cull::{GROUP as CULL_GROUP, drawn_segment, screen_bin};
use super::{Scene, clip_to_screen};
use crate::contract::{Binding, CpuKernel, Dispatch, ParamError, Params, PassDef, Shader};
use crate::sim::Ctx;
use strandgraph_graph::schema::Quantity;

pub struct SortScan;
pub struct Sort;

impl PassDef for SortScan {
    fn kind(&self) -> &'static str {
        "kulikov.sort_scan"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        const BINDINGS: &[Binding] = &[
            Binding::read("sort_bins"),
            Binding::write("sort_offsets"),
            Binding::write("raster_args"),
        ];
        Some(BINDINGS)
    }
    fn workgroup_size(&self) -> u32 {
        1
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::Fixed(1)
    }
    fn shader(&self) -> Shader {
        Shader::compute("kulikov/sort.wgsl", "scan")
    }
    fn cpu_kernel(&self, _: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        Ok(Box::new(ScanKernel))
    }
    /// `SortParams` (shared with `kulikov.sort`; `enabled` unused by the scan).
    fn gpu_params(
        &self,
        _: &ron::Value,
        q: &strandgraph_graph::Quantities,
    ) -> Result<Vec<u32>, ParamError> {
        Ok(sort_params(true, q))
    }
}

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

impl PassDef for Sort {
    fn kind(&self) -> &'static str {
        "kulikov.sort"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        const BINDINGS: &[Binding] = &[
            Binding::read("frame"),
            Binding::read("models"),
            Binding::read("lod_models"),
            Binding::read("clip_positions"),
            Binding::read("segment_visibility"),
            Binding::atomic("sort_offsets"),
            Binding::write("sorted_segments"),
        ];
        Some(BINDINGS)
    }
    fn workgroup_size(&self) -> u32 {
        CULL_GROUP
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::PerElement {
            quantity: Quantity::Segments,
            per_group: CULL_GROUP,
        }
    }
    fn shader(&self) -> Shader {
        Shader::compute("kulikov/sort.wgsl", "scatter")
    }
    fn cpu_kernel(&self, params: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        let p = Params::new(self.kind(), params)?;
        Ok(Box::new(ScatterKernel {
            enabled: p.bool("enabled", true)?,
        }))
    }
    /// `SortParams`: enabled, segments, bins.
    fn gpu_params(
        &self,
        params: &ron::Value,
        q: &strandgraph_graph::Quantities,
    ) -> Result<Vec<u32>, ParamError> {
        let p = Params::new(self.kind(), params)?;
        Ok(sort_params(p.bool("enabled", true)?, q))
    }
}

/// The WGSL `SortParams` block of both entry points in shaders/kulikov/sort.wgsl.
fn sort_params(enabled: bool, q: &strandgraph_graph::Quantities) -> Vec<u32> {
    vec![
        crate::contract::flag(enabled),
        crate::contract::count(q.segments),
        crate::contract::count(q.count(Quantity::Tiles(super::TILE))),
    ]
}

struct ScatterKernel {
    enabled: bool,
}

impl CpuKernel for ScatterKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let scene = Scene::load(ctx);
        let lods = scene.lods(ctx);
        let (clip, bits, offsets, out) = (
            ctx.words("clip_positions"),
            ctx.words("segment_visibility"),
            ctx.words("sort_offsets"),
            ctx.words("sorted_segments"),
        );
        let counter = ctx.quantities.count(Quantity::Tiles(super::TILE)) as usize;
        let (w, h) = (scene.frame.screen[0], scene.frame.screen[1]);
        for lane in 0..CULL_GROUP {
            let id = group * CULL_GROUP + lane;
            if u64::from(id) >= ctx.quantities.segments
                || bits.load((id / 32) as usize) & (1 << (id % 32)) == 0
            {
                continue;
            }
            let slot = if self.enabled {
                let Some(seg) = drawn_segment(&scene, &lods, id) else {
                    continue;
                };
                let s0 = clip_to_screen(clip.load_vec4(seg.v0 as usize), w, h);
                let s1 = clip_to_screen(clip.load_vec4(seg.v1 as usize), w, h);
                offsets.fetch_add(screen_bin(w, h, s0, s1) as usize, 1)
            } else {
                offsets.fetch_add(counter, 1)
            };
            out.store(slot as usize, id);
        }
    }
}
