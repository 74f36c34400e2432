//! `lipp.lod_scan`: the exclusive prefix sum of `lipp.lod`'s strand counts,
//! and the rasterizer's indirect dispatch.
//!
//! Deviation: the paper feeds each bundle's N_LOD to a per-bundle indirect
//! dispatch (Lipp §3.2). Here the rasterizer is one flat indirect dispatch
//! over all drawn strands (a workgroup per strand), so each bundle needs its
//! first strand: this pass copies `lod_choices` into `bundle_lod` with word 2
//! the running sum, and writes `raster_args` = (min(drawn, 65535), 1, 1,
//! drawn, Σ N, Σ N_LOD, and the drawn bundles' screen rectangle,
//! [`super::super::rect`], the dispatch over its runs of pixels, and the
//! bundles of the groom scanned, [`ARGS_BUNDLES_LO`]). With `groom_rect`
//! off (ours, on by default) the rectangle is the whole screen.
//! A frustum-culled bundle draws nothing (its
//! `bundle_lod` count is 0) but its N_LOD counts in β = Σ N_LOD / Σ N of
//! Eq. 8, over the bundles the decision was for (not another groom's): β is
//! the fraction of strands the LOD removed, which culling must not change.
//! One workgroup of 256 threads, each owning a contiguous run of bundles,
//! scans their sums in workgroup memory (shaders/lipp/lod_scan.wgsl); the
//! CPU kernel computes the same values sequentially.

use super::super::rect::{ARGS_CLEAR, ARGS_RECT_HI, ARGS_RECT_LO, ARGS_RUNS, Rect};
use super::super::{
    ARGS_ALL, ARGS_BUNDLES_HI, ARGS_BUNDLES_LO, ARGS_DRAWN, ARGS_KEPT, BUNDLE_WORDS, BundleLod,
    BundleRecord, LOD_CULLED, LOD_OTHER_GROOM, LOD_WORDS, MAX_GROUPS_X, bundle_count,
    groom_bundles,
};
use super::ALL_MODELS;
use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::{Invalid, PassParams, in_range};

/// Threads of the single scan workgroup (WGSL).
pub const SCAN_GROUP: u32 = 256;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScanParams {
    /// Ours: the drawn bundles' screen rectangle ([`super::super::rect`]);
    /// off, the whole screen, so `lipp.shade` and `lipp.clear_gbuffer`
    /// cover every pixel.
    pub groom_rect: bool,
    /// Only this groom's bundles (the per-model block sets `model_index`);
    /// `None`: all. The scan walks that groom's bundles only (ours: the
    /// crowd's 28 grooms each scanned all 28,000 bundles) and tells the
    /// rasterizer where they are (`raster_args` words
    /// [`ARGS_BUNDLES_LO`], [`ARGS_BUNDLES_HI`]), which then looks no
    /// further; other bundles' `bundle_lod` records are left as they were.
    /// A `raster_args` with no room for the range gets every bundle's.
    #[serde(rename = "model_index", deserialize_with = "crate::params::some")]
    pub model: Option<u32>,
    /// Ours: runs of the rectangle each `lipp.clear_gbuffer` workgroup
    /// clears (`raster_args` words [`ARGS_CLEAR`]..); 1: a workgroup a run,
    /// as `lipp.shade` is dispatched (passes/src/lipp/clear.rs says why).
    pub clear_runs: u32,
}

impl Default for ScanParams {
    fn default() -> Self {
        Self {
            groom_rect: true,
            model: None,
            clear_runs: 8,
        }
    }
}

impl PassParams for ScanParams {
    const READS_MODEL_INDEX: bool = true;

    fn validate(&self) -> Result<(), Invalid> {
        in_range("clear_runs", self.clear_runs, 1..=MAX_CLEAR_RUNS)
    }
}

/// The most runs one `lipp.clear_gbuffer` workgroup is given.
pub const MAX_CLEAR_RUNS: u32 = 64;

crate::gpu_block! {
    /// `ScanParams` in shaders/lipp/lod_scan.wgsl.
    pub struct ScanGpu {
        /// Scene quantity: bundles packed.
        bundles: u32,
        /// Scene quantities: the screen.
        width: u32,
        height: u32,
        groom_rect: u32,
        /// The groom scanned, or ALL_MODELS.
        model: u32,
        clear_runs: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

pub static LOD_SCAN: PassKind<ScanParams, ScanGpu> = PassKind {
    kind: "lipp.lod_scan",
    summary: "prefix sum of the LOD's strand counts into first strands; the rasterizer's indirect dispatch and β of Eq. 8",
    source: "Lipp §3.2",
    bindings: Some(&[
        Binding::read("hairmesh.bundles"),
        Binding::read("lod_choices"),
        Binding::write("bundle_lod"),
        Binding::write("raster_args"),
    ]),
    workgroup_size: SCAN_GROUP,
    dispatch: Dispatch::Fixed(1),
    shader: Shader::compute("lipp/lod_scan.wgsl", "scan"),
    kernel: |p| Box::new(ScanKernel(*p)),
    gpu: |p, q| ScanGpu {
        bundles: count(q.bundles),
        width: q.width,
        height: q.height,
        groom_rect: flag(p.groom_rect),
        model: p.model.unwrap_or(ALL_MODELS),
        clear_runs: p.clear_runs,
        ..ScanGpu::default()
    },
    raster: None,
};

struct ScanKernel(ScanParams);

impl CpuKernel for ScanKernel {
    fn run_workgroup(&self, _group: u32, ctx: &Ctx<'_>) {
        let (bundles, choices, out) = (
            ctx.words("hairmesh.bundles"),
            ctx.words("lod_choices"),
            ctx.words("bundle_lod"),
        );
        let count = bundle_count(ctx)
            .min(bundles.len() / BUNDLE_WORDS)
            .min(choices.len() / LOD_WORDS)
            .min(out.len() / LOD_WORDS);
        let (mut total, mut full, mut kept) = (0u32, 0u32, 0u32);
        let (w, h) = (ctx.quantities.width, ctx.quantities.height);
        let mut groom = Rect::EMPTY;
        let args = ctx.words("raster_args");
        let room = args.len() > ARGS_BUNDLES_HI;
        let range = if room {
            groom_bundles(&bundles, count, self.0.model)
        } else {
            0..count
        };
        for b in range.clone() {
            let mut lod = BundleLod::load(&choices, b);
            if lod.flags & LOD_OTHER_GROOM == 0 {
                full = full.wrapping_add(BundleRecord::load(&bundles, b).strands);
                kept = kept.wrapping_add(lod.strands);
            }
            if lod.flags & LOD_CULLED != 0 {
                lod.strands = 0;
            }
            if lod.strands > 0 {
                groom = groom.union(Rect::unpack_tiles(lod.first_strand, w, h));
            }
            lod.first_strand = total;
            total = total.wrapping_add(lod.strands);
            lod.store(&out, b);
        }
        args.store(0, total.min(MAX_GROUPS_X));
        args.store(1, 1);
        args.store(2, 1);
        args.store(ARGS_DRAWN, total);
        // β of Lipp Eq. 8 is word 5 / word 4.
        args.store(ARGS_ALL, full);
        args.store(ARGS_KEPT, kept);
        // The screen rectangle of the bundles drawn (rect.rs) and the
        // dispatch over its runs, if there is room.
        if !self.0.groom_rect {
            groom = Rect::full(w, h);
        }
        if args.len() > ARGS_RECT_HI {
            let [lo, hi] = groom.args();
            args.store(ARGS_RECT_LO, lo);
            args.store(ARGS_RECT_HI, hi);
        }
        if args.len() > ARGS_RUNS + 2 {
            for (i, n) in groom.run_dispatch(w, 1).into_iter().enumerate() {
                args.store(ARGS_RUNS + i, n);
            }
        }
        if args.len() > ARGS_CLEAR + 2 {
            let dispatch = groom.run_dispatch(w, self.0.clear_runs);
            for (i, n) in dispatch.into_iter().enumerate() {
                args.store(ARGS_CLEAR + i, n);
            }
        }
        if room {
            args.store(ARGS_BUNDLES_LO, range.start as u32);
            args.store(ARGS_BUNDLES_HI, range.end as u32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use strandgraph_graph::Quantities;

    /// Bundles keeping 10, 7 (frustum-culled), 0 (another groom's), 5 and
    /// 3 (frustum-culled) strands of 20.
    #[test]
    fn first_strands_are_the_running_sum_and_beta_counts_kept_strands_of_this_groom() {
        let counts = [
            (10, 0),
            (7, LOD_CULLED),
            (0, LOD_OTHER_GROOM),
            (5, 0),
            (3, LOD_CULLED),
        ];
        // Screen rectangles in 8-pixel tiles (x0 | y0 << 8 | x1 << 16 | y1 << 24):
        // only the drawn bundles' (the first and the fourth) count.
        let mut rects = [0x0402_0301u32, 0x6464_0000, 0x0101_0000, 0x0906_0505, 1].into_iter();
        let mut bundles = Vec::new();
        let mut choices = Vec::new();
        for (n, flags) in counts {
            let rec = BundleRecord {
                strands: 20,
                ..Default::default()
            };
            bundles.extend(rec.words());
            choices.extend([n, 9, rects.next().unwrap(), flags]);
        }
        let mut h = Harness::new(Quantities {
            bundles: counts.len() as u64,
            width: 640,
            height: 480,
            ..Default::default()
        });
        h.buffer("hairmesh.bundles", bundles)
            .buffer("lod_choices", choices)
            .buffer("bundle_lod", vec![0; 4 * counts.len()])
            .buffer("raster_args", vec![0; ARGS_CLEAR + 3]);
        h.run(&ScanKernel(ScanParams::default()), 1, SCAN_GROUP);
        let lod = h.read("bundle_lod");
        let firsts: Vec<u32> = lod.chunks(4).map(|w| w[2]).collect();
        assert_eq!(firsts, [0, 10, 10, 10, 15]);
        let drawn: Vec<u32> = lod.chunks(4).map(|w| w[0]).collect();
        assert_eq!(drawn, [10, 0, 0, 5, 0], "culled bundles draw nothing");
        assert!(lod.chunks(4).all(|w| w[1] == 9), "C copied");
        // Drawn 15; β = (10 + 7 + 5 + 3) / (4 · 20).
        assert_eq!(&h.read("raster_args")[..6], &[15, 1, 1, 15, 80, 25]);
        // Tiles x 1..6, y 3..9 of 8 pixels.
        let args = h.read("raster_args");
        assert_eq!(
            Rect::from_args(args[ARGS_RECT_LO], args[ARGS_RECT_HI]),
            Rect {
                x0: 8,
                y0: 24,
                x1: 48,
                y1: 72
            }
        );
        // Runs of 64 pixels from (8, 24) to (47, 71) on a 640-wide screen:
        // 24 * 10 + 0 to 71 * 10 + 0.
        assert_eq!(&args[ARGS_RUNS..ARGS_RUNS + 3], &[471, 1, 1]);
        // lipp.clear_gbuffer's: 8 runs a workgroup.
        assert_eq!(&args[ARGS_CLEAR..], &[59, 1, 1]);
        // Off, the whole screen: 640 * 480 / 64 runs.
        h.buffer("raster_args", vec![0; ARGS_CLEAR + 3]);
        let off = ScanParams {
            groom_rect: false,
            ..ScanParams::default()
        };
        h.run(&ScanKernel(off), 1, SCAN_GROUP);
        let args = h.read("raster_args");
        assert_eq!(
            Rect::from_args(args[ARGS_RECT_LO], args[ARGS_RECT_HI]),
            Rect::full(640, 480)
        );
        assert_eq!(&args[ARGS_RUNS..ARGS_RUNS + 3], &[4800, 1, 1]);
        assert_eq!(&args[ARGS_CLEAR..], &[600, 1, 1]);
    }

    /// Three grooms' bundles (models 0, 0, 1, 1, 1, 2), scanned for groom
    /// 1: its bundles get the running sum, the others stay as they were,
    /// and `raster_args` says where the groom's are.
    #[test]
    fn a_grooms_scan_walks_its_own_bundles_only() {
        let models = [0u32, 0, 1, 1, 1, 2];
        let (mut bundles, mut choices) = (Vec::new(), Vec::new());
        for (b, &model) in models.iter().enumerate() {
            let rec = BundleRecord {
                strands: 10,
                model,
                ..Default::default()
            };
            bundles.extend(rec.words());
            let flags = if model == 1 { 0 } else { LOD_OTHER_GROOM };
            choices.extend([if model == 1 { b as u32 } else { 0 }, 9, 0, flags]);
        }
        let mut h = Harness::new(Quantities {
            bundles: models.len() as u64,
            width: 64,
            height: 64,
            ..Default::default()
        });
        h.buffer("hairmesh.bundles", bundles)
            .buffer("lod_choices", choices)
            .buffer("bundle_lod", vec![7; 4 * models.len()])
            .buffer("raster_args", vec![0; 13]);
        let params = ScanParams {
            model: Some(1),
            ..ScanParams::default()
        };
        h.run(&ScanKernel(params), 1, SCAN_GROUP);
        let lod = h.read("bundle_lod");
        let rows: Vec<&[u32]> = lod.chunks(4).collect();
        let other = [7u32; 4];
        assert_eq!(rows[0], other);
        assert_eq!(rows[1], other);
        assert_eq!(rows[2], [2, 9, 0, 0]);
        assert_eq!(rows[3], [3, 9, 2, 0]);
        assert_eq!(rows[4], [4, 9, 5, 0]);
        assert_eq!(rows[5], other);
        // Drawn 9 of the groom's 30 strands, in bundles 2..5.
        let args = h.read("raster_args");
        assert_eq!(&args[..6], &[9, 1, 1, 9, 30, 9]);
        assert_eq!(&args[ARGS_BUNDLES_LO..], &[2, 5]);
    }
}
