//! `common.clear`: fill every resource the pass writes with one 32-bit value.
//!
//! Atomic targets need it: `atomicMin` visibility buffers start at all-ones,
//! `atomicAdd` counters at zero. (wgpu's `clear_buffer` only writes zeros,
//! so the GPU backends run this as a compute pass; ash may use `vkCmdFillBuffer`.)

use crate::contract::{Binding, CpuKernel, Dispatch, ParamError, Params, PassDef, Shader};
use crate::sim::Ctx;

pub struct Clear;

const GROUP: u32 = 256;
/// Words each lane clears, `GROUP` apart (coalesced). A 1080p 8-sample
/// G-buffer is 33M words: one word per lane would need 129,600 workgroups,
/// past the 65,535 per dimension Vulkan guarantees; 16 per lane allow
/// buffers up to 1 GiB in one dimension.
pub const WORDS_PER_LANE: u32 = 16;

impl PassDef for Clear {
    fn kind(&self) -> &'static str {
        "common.clear"
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        None
    }
    fn workgroup_size(&self) -> u32 {
        GROUP
    }
    fn dispatch(&self) -> Dispatch {
        Dispatch::CoverWrites {
            words_per_group: GROUP * WORDS_PER_LANE,
        }
    }
    fn shader(&self) -> Shader {
        Shader::compute("common/clear.wgsl", "clear")
    }
    fn cpu_kernel(&self, params: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        let p = Params::new(self.kind(), params)?;
        Ok(Box::new(ClearKernel {
            value: p.u32("value", 0)?,
        }))
    }
    /// `ClearParams`: value, words (the backend fills `words` per resource).
    fn gpu_params(
        &self,
        params: &ron::Value,
        _: &strandgraph_graph::Quantities,
    ) -> Result<Vec<u32>, ParamError> {
        let p = Params::new(self.kind(), params)?;
        Ok(vec![p.u32("value", 0)?, 0])
    }
}

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
