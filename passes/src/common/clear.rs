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
/// Words each lane clears, `GROUP` apart (coalesced). A 1080p 8-sample
/// G-buffer is 33M words: one word per lane would need 129,600 workgroups,
/// past the 65,535 per dimension Vulkan guarantees; 16 per lane allow
/// buffers up to 1 GiB in one dimension.
pub const WORDS_PER_LANE: u32 = 16;

#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Deserialize)]
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
        let start = group as usize * span;
        for words in ctx.bindings.values() {
            for i in start..(start + span).min(words.len()) {
                words.store(i, self.value);
            }
        }
    }
}
