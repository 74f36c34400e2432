//! `kulikov.shade_sort`: visible segments back to their natural order for
//! strand-space shading.
//!
//! Kulikov, "Strand-space shading needs different segment order": "Sort again
//! with 'natural' segment order. No need for buckets, let GPU scheduler do
//! your work for you": each subgroup counts its visible lanes
//! (`subgroupAdd`), one lane appends them with one `atomicAdd`, every lane
//! writes at the returned base plus its `subgroupExclusiveAdd`. Waves launch
//! roughly in order, so the list comes out nearly in segment order.
//!
//! `shade_args` (cleared to 0 before) ends as the shade pass's indirect
//! dispatch: `[groups, 1, 1, count]`; word 3 is the append counter and word
//! 0 is raised with `atomicMax` by every subgroup, so no scan pass is needed.
//! `wave_aggregated_atomics: false` appends one lane at a time (the ablation).

use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, subgroup};
use crate::params::PassParams;
use strandgraph_graph::schema::Quantity;

pub const GROUP: u32 = 256;
/// Segments per workgroup of `kulikov.shade` (the indirect count's divisor).
pub const SHADE_GROUP: u32 = 64;
/// The most workgroups `shade_args` asks for: every Vulkan device launches
/// 65,535 in x (wgpu's limit per dimension), and past it (more than 4.19M
/// visible segments: the reference graph's crowd, with no LOD) the shading
/// lanes stride over the rest.
pub const MAX_SHADE_GROUPS: u32 = 65_535;

#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadeSortParams {
    /// One `atomicAdd` per subgroup; off, one per lane (the ablation).
    pub wave_aggregated_atomics: bool,
}

impl Default for ShadeSortParams {
    fn default() -> Self {
        Self {
            wave_aggregated_atomics: true,
        }
    }
}

impl PassParams for ShadeSortParams {}

crate::gpu_block! {
    /// The WGSL `ShadeSortParams` block (binding 0): switch, segments.
    pub struct ShadeSortGpu {
        wave_aggregated_atomics: u32,
        /// Scene quantity: segments in the full numbering.
        segments: u32,
    }
}

pub static SHADE_SORT: PassKind<ShadeSortParams, ShadeSortGpu> = PassKind {
    kind: "kulikov.shade_sort",
    summary: "re-sort visible segments to natural order for strand-space shading",
    source: "Kulikov 2025, 'Strand-space shading needs different segment order'",
    bindings: Some(&[
        Binding::read("segment_visibility"),
        Binding::atomic("shade_args"),
        Binding::write("shading_segments"),
    ]),
    workgroup_size: GROUP,
    dispatch: Dispatch::PerElement {
        quantity: Quantity::Segments,
        per_group: GROUP,
    },
    shader: Shader::compute("kulikov/shade_sort.wgsl", "shade_sort"),
    kernel: |p| {
        Box::new(ShadeSortKernel {
            aggregated: p.wave_aggregated_atomics,
        })
    },
    gpu: |p, q| ShadeSortGpu {
        wave_aggregated_atomics: flag(p.wave_aggregated_atomics),
        segments: count(q.segments),
    },
    raster: None,
};

struct ShadeSortKernel {
    aggregated: bool,
}

impl CpuKernel for ShadeSortKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let (bits, args, out) = (
            ctx.words("segment_visibility"),
            ctx.words("shade_args"),
            ctx.words("shading_segments"),
        );
        let width = ctx.subgroup_width.max(1);
        let mut tally = CounterValues::default();
        for sub in (0..GROUP).step_by(width as usize) {
            let ids: Vec<u32> = (sub..(sub + width).min(GROUP))
                .map(|l| group * GROUP + l)
                .collect();
            let active: Vec<bool> = ids
                .iter()
                .map(|&id| {
                    u64::from(id) < ctx.quantities.segments
                        && bits.load((id / 32) as usize) & (1 << (id % 32)) != 0
                })
                .collect();
            let n = subgroup::count(&active);
            if n == 0 {
                continue;
            }
            let (slots, end) = if self.aggregated {
                let ones = vec![1; ids.len()];
                let base = args.fetch_add(3, n);
                tally.atomics += 1;
                let offs = subgroup::exclusive_add(&ones, &active);
                (offs.iter().map(|o| base + o).collect::<Vec<_>>(), base + n)
            } else {
                let slots: Vec<u32> = active
                    .iter()
                    .map(|&a| if a { args.fetch_add(3, 1) } else { 0 })
                    .collect();
                tally.atomics += u64::from(n);
                let end = slots
                    .iter()
                    .zip(&active)
                    .filter(|(_, a)| **a)
                    .map(|(s, _)| s + 1);
                (slots.clone(), end.max().unwrap_or(0))
            };
            for ((id, slot), a) in ids.iter().zip(&slots).zip(&active) {
                if *a {
                    out.store(*slot as usize, *id);
                }
            }
            args.fetch_max(0, end.div_ceil(SHADE_GROUP).min(MAX_SHADE_GROUPS));
            args.store(1, 1);
            args.store(2, 1);
            tally.atomics += 1;
            tally.active_lanes += u64::from(n);
            tally.total_lanes += u64::from(width);
        }
        if ctx.instrument {
            ctx.counters.add(&tally);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use strandgraph_graph::Quantities;

    fn run(aggregated: bool, width: u32) -> (Vec<u32>, Vec<u32>, u64) {
        run_on(1000, aggregated, width, |i| (i * 7919) % 3 != 0)
    }

    fn run_on(
        segments: u32,
        aggregated: bool,
        width: u32,
        shown: impl Fn(u32) -> bool,
    ) -> (Vec<u32>, Vec<u32>, u64) {
        let visible: Vec<u32> = (0..segments).filter(|&i| shown(i)).collect();
        let mut bits = vec![0u32; segments.div_ceil(32) as usize];
        for &v in &visible {
            bits[(v / 32) as usize] |= 1 << (v % 32);
        }
        let mut hs = Harness::new(Quantities {
            segments: u64::from(segments),
            ..Default::default()
        });
        hs.subgroup_width = width;
        hs.buffer("segment_visibility", bits)
            .buffer("shade_args", vec![0; 4])
            .buffer("shading_segments", vec![u32::MAX; segments as usize + 4]);
        let params: ron::Value =
            ron::from_str(&format!("{{\"wave_aggregated_atomics\": {aggregated}}}")).unwrap();
        let k = crate::PassDef::cpu_kernel(&SHADE_SORT, &params).unwrap();
        let c = hs.run(k.as_ref(), segments.div_ceil(GROUP), GROUP);
        let args = hs.read("shade_args");
        let mut list = hs.read("shading_segments")[..args[3] as usize].to_vec();
        list.sort_unstable();
        assert_eq!(list, visible);
        (args, visible, c.atomics)
    }

    #[test]
    fn appends_every_visible_segment_once() {
        let (args, visible, aggregated) = run(true, 32);
        let n = visible.len() as u32;
        assert_eq!(args, vec![n.div_ceil(SHADE_GROUP), 1, 1, n]);
        let (args8, _, per_lane) = run(false, 8);
        assert_eq!(args8, args);
        // One append per subgroup instead of one per visible lane.
        assert!(aggregated * 8 < per_lane, "{aggregated} vs {per_lane}");
    }

    #[test]
    fn more_segments_than_one_dispatch_holds_cap_the_groups() {
        let n = MAX_SHADE_GROUPS * SHADE_GROUP + 100;
        let (args, ..) = run_on(n, true, 32, |_| true);
        assert_eq!(args, vec![MAX_SHADE_GROUPS, 1, 1, n]);
    }
}
