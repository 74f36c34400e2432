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
//!
//! `word_per_lane` (ours): a lane takes a 32-bit word of visibility bits,
//! not one bit, and appends its set bits in order after the subgroup's
//! earlier lanes' (`subgroupExclusiveAdd` of the bit counts). The order is
//! the same natural order; the dispatch is 32 times smaller. Most words are
//! empty beyond the LOD's kept strands, so most lanes do one load. Off, a
//! workgroup covers the same 8,192 segments in 32 rounds of a bit per lane.

use crate::contract::{Binding, CpuKernel, Dispatch, Shader, count, flag};
use crate::describe::PassKind;
use crate::kernel::{CounterValues, Ctx, subgroup};
use crate::params::PassParams;
use strandgraph_graph::schema::Quantity;

pub const GROUP: u32 = 256;
/// Segments per workgroup: a word of 32 visibility bits per lane.
pub const SEGMENTS_PER_GROUP: u32 = GROUP * 32;
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
    /// Ours: a lane appends a word's set bits; off, a bit per lane.
    pub word_per_lane: bool,
}

impl Default for ShadeSortParams {
    fn default() -> Self {
        Self {
            wave_aggregated_atomics: true,
            word_per_lane: true,
        }
    }
}

impl PassParams for ShadeSortParams {}

crate::gpu_block! {
    /// The WGSL `ShadeSortParams` block (binding 0): switches, segments.
    pub struct ShadeSortGpu {
        wave_aggregated_atomics: u32,
        word_per_lane: u32,
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
        per_group: SEGMENTS_PER_GROUP,
    },
    shader: Shader::compute("kulikov/shade_sort.wgsl", "shade_sort"),
    kernel: |p| {
        Box::new(ShadeSortKernel {
            aggregated: p.wave_aggregated_atomics,
            word_per_lane: p.word_per_lane,
        })
    },
    gpu: |p, q| ShadeSortGpu {
        wave_aggregated_atomics: flag(p.wave_aggregated_atomics),
        word_per_lane: flag(p.word_per_lane),
        segments: count(q.segments),
    },
    raster: None,
};

struct ShadeSortKernel {
    aggregated: bool,
    word_per_lane: bool,
}

impl CpuKernel for ShadeSortKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let bits = ctx.words("segment_visibility");
        let segments = ctx.quantities.segments;
        // Lane l's visibility bits and the segment of its bit 0.
        let lane_bits = |first: u32, one_bit: bool| -> u32 {
            let word = if u64::from(first) < segments {
                bits.load((first / 32) as usize)
            } else {
                0
            };
            if one_bit {
                return (word >> (first % 32)) & 1;
            }
            // A whole word (`first` is a multiple of 32): off with the bits
            // of segments past the end, which no pass sets.
            let valid = (segments - u64::from(first)).min(32) as u32;
            word & if valid == 32 { !0 } else { (1 << valid) - 1 }
        };
        let base = group * SEGMENTS_PER_GROUP;
        let mut tally = CounterValues::default();
        if self.word_per_lane {
            let lanes: Vec<(u32, u32)> = (0..GROUP)
                .map(|l| base + 32 * l)
                .map(|first| (lane_bits(first, false), first))
                .collect();
            self.append(&lanes, ctx, &mut tally);
        } else {
            for round in 0..32 {
                let lanes: Vec<(u32, u32)> = (0..GROUP)
                    .map(|l| base + round * GROUP + l)
                    .map(|id| (lane_bits(id, true), id))
                    .collect();
                self.append(&lanes, ctx, &mut tally);
            }
        }
        if ctx.instrument {
            ctx.counters.add(&tally);
        }
    }
}

impl ShadeSortKernel {
    /// One workgroup step: each lane's `(bits, first segment)`; a lane's
    /// set bits are appended as segments `first + bit`, in bit order, after
    /// those of the subgroup's earlier lanes.
    fn append(&self, lanes: &[(u32, u32)], ctx: &Ctx<'_>, tally: &mut CounterValues) {
        let (args, out) = (ctx.words("shade_args"), ctx.words("shading_segments"));
        let width = ctx.subgroup_width.max(1) as usize;
        for sub in lanes.chunks(width) {
            let counts: Vec<u32> = sub.iter().map(|(b, _)| b.count_ones()).collect();
            let n: u32 = counts.iter().sum();
            if n == 0 {
                continue;
            }
            let mut end = 0;
            if self.aggregated {
                let base = args.fetch_add(3, n);
                tally.atomics += 1;
                let offsets = subgroup::exclusive_add(&counts, &vec![true; sub.len()]);
                for (&(b, first), offset) in sub.iter().zip(offsets) {
                    for (k, bit) in set_bits(b).enumerate() {
                        out.store((base + offset) as usize + k, first + bit);
                    }
                }
                end = base + n;
            } else {
                // One append per segment.
                tally.atomics += u64::from(n);
                for &(b, first) in sub {
                    for bit in set_bits(b) {
                        let slot = args.fetch_add(3, 1);
                        out.store(slot as usize, first + bit);
                        end = end.max(slot + 1);
                    }
                }
            }
            args.fetch_max(0, end.div_ceil(SHADE_GROUP).min(MAX_SHADE_GROUPS));
            args.store(1, 1);
            args.store(2, 1);
            tally.atomics += 1;
            tally.active_lanes += counts.iter().filter(|&&c| c > 0).count() as u64;
            tally.total_lanes += width as u64;
        }
    }
}

/// The set bits of `b`, lowest first.
fn set_bits(mut b: u32) -> impl Iterator<Item = u32> {
    std::iter::from_fn(move || {
        (b != 0).then(|| {
            let bit = b.trailing_zeros();
            b &= b - 1;
            bit
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::harness::Harness;
    use strandgraph_graph::Quantities;

    fn run(aggregated: bool, width: u32) -> (Vec<u32>, Vec<u32>, u64) {
        let (args, visible, atomics, _) =
            run_on(1000, (aggregated, true), width, |i| (i * 7919) % 3 != 0);
        (args, visible, atomics)
    }

    /// `switches`: (wave_aggregated_atomics, word_per_lane).
    fn run_on(
        segments: u32,
        switches: (bool, bool),
        width: u32,
        shown: impl Fn(u32) -> bool,
    ) -> (Vec<u32>, Vec<u32>, u64, Vec<u32>) {
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
        let (aggregated, words) = switches;
        let params: ron::Value = ron::from_str(&format!(
            "{{\"wave_aggregated_atomics\": {aggregated}, \"word_per_lane\": {words}}}"
        ))
        .unwrap();
        let k = crate::PassDef::cpu_kernel(&SHADE_SORT, &params).unwrap();
        let c = hs.run(k.as_ref(), segments.div_ceil(SEGMENTS_PER_GROUP), GROUP);
        let args = hs.read("shade_args");
        let appended = hs.read("shading_segments")[..args[3] as usize].to_vec();
        let mut list = appended.clone();
        list.sort_unstable();
        assert_eq!(list, visible);
        (args, visible, c.atomics, appended)
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
        let (args, ..) = run_on(n, (true, true), 32, |_| true);
        assert_eq!(args, vec![MAX_SHADE_GROUPS, 1, 1, n]);
    }

    #[test]
    fn a_word_per_lane_keeps_natural_order_with_fewer_appends() {
        // One workgroup (its subgroups run in order), a count that is not a
        // multiple of 32, visibility in runs as the LOD's kept strands give.
        let shown = |i: u32| ((i / 40) % 3 != 1 && !i.is_multiple_of(7)) || i >= 4990;
        let (args, visible, words, in_words) = run_on(5000, (true, true), 32, shown);
        let (bit_args, _, bits, in_bits) = run_on(5000, (true, false), 32, shown);
        assert_eq!(in_words, visible);
        assert_eq!(in_bits, visible);
        assert_eq!(args, bit_args);
        assert!(words * 8 < bits, "{words} vs {bits}");
        // Per-segment appends of either layout give the same set.
        run_on(5000, (false, true), 8, shown);
        run_on(5000, (false, false), 8, shown);
    }
}
