//! `common.clear`: fill every resource the pass writes with one 32-bit value.
//!
//! Atomic targets need it: `atomicMin` visibility buffers start at all-ones,
//! `atomicAdd` counters at zero. (wgpu's `clear_buffer` only writes zeros,
//! so the GPU backends run this as a compute pass; ash may use `vkCmdFillBuffer`.)

use crate::contract::{CpuKernel, Dispatch, Shader};
use crate::describe::PassKind;
use crate::kernel::Ctx;
use crate::params::PassParams;

const GROUP: u32 = 256;
/// Words each lane clears per round, `GROUP` apart (coalesced): a
/// workgroup clears 4,096 consecutive words a round, and the dispatch's
/// workgroups stride over larger buffers (the reference's records reach
/// 2.7 GB on the crowd; `Dispatch::CoverWrites` launches at most 65,535).
pub const WORDS_PER_LANE: u32 = 16;

#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClearParams {
    /// The word every written resource is filled with.
    pub value: u32,
}

impl PassParams for ClearParams {}

crate::gpu_block! {
    /// `ClearParams`: value, words (the backend fills `words` per resource).
    pub struct ClearGpu {
        value: u32,
        words: u32,
    }
}

pub static CLEAR: PassKind<ClearParams, ClearGpu> = PassKind {
    kind: "common.clear",
    summary: "fill buffers or images with a constant (all-ones for atomicMin targets)",
    source: "strandgraph",
    bindings: None,
    workgroup_size: GROUP,
    dispatch: Dispatch::CoverWrites {
        words_per_group: GROUP * WORDS_PER_LANE,
    },
    shader: Shader::compute("common/clear.wgsl", "clear"),
    kernel: |p| Box::new(ClearKernel { value: p.value }),
    gpu: |p, _| ClearGpu {
        value: p.value,
        words: 0,
    },
    raster: None,
};

struct ClearKernel {
    value: u32,
}

impl CpuKernel for ClearKernel {
    fn run_workgroup(&self, group: u32, ctx: &Ctx<'_>) {
        let span = (GROUP * WORDS_PER_LANE) as usize;
        let stride = span * ctx.workgroups.max(1) as usize;
        for words in ctx.bindings.values() {
            for start in (group as usize * span..words.len()).step_by(stride) {
                for i in start..(start + span).min(words.len()) {
                    words.store(i, self.value);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::PassDef;
    use crate::kernel::harness::Harness;
    use strandgraph_graph::Quantities;

    /// Fewer workgroups than the buffer's spans (as past the dispatch cap):
    /// the groups stride, and every word is written.
    #[test]
    fn workgroups_stride_over_buffers_larger_than_the_dispatch() {
        let mut h = Harness::new(Quantities::default());
        h.buffer("big", vec![0; 3 * 4096 + 17]);
        let k = CLEAR
            .cpu_kernel(&ron::from_str("{\"value\": 7}").unwrap())
            .unwrap();
        h.run(k.as_ref(), 2, GROUP);
        assert!(h.read("big").iter().all(|&w| w == 7));
    }
}
