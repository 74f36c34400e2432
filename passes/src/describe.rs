//! One declaration per pass kind: [`PassKind`] holds everything a kind
//! defines (name, citation, interface, dispatch, shader, parameters, CPU
//! kernel, GPU parameter block) and implements [`PassDef`] for every backend.
//!
//! A pass file declares its `Params` ([`PassParams`]), its GPU block
//! ([`gpu_block!`](crate::gpu_block)) and a `pub static` `PassKind`; the
//! registry (`crate::PASSES`) lists the statics.

use crate::contract::{Binding, CpuKernel, Dispatch, GpuLayout, ParamError, PassDef, Shader};
use crate::params::{self, Invalid, PassParams};
use crate::raster_state::RasterState;
use strandgraph_graph::Quantities;

/// A pass's GPU parameter block (binding 0): a `#[repr(C)]` `Pod` struct
/// whose fields are the WGSL struct's members, in order, at the same
/// offsets (`passes/tests/wgsl_params.rs` checks them with naga). Declare it with
/// [`gpu_block!`](crate::gpu_block).
pub trait GpuBlock: bytemuck::Pod {
    /// Field names and byte offsets, in declaration order. Fields named
    /// `_pad…` may be padding the WGSL struct leaves implicit.
    const FIELDS: &'static [(&'static str, usize)];
}

/// Declares a [`GpuBlock`]: the struct (`#[repr(C)]`, `Pod`, all fields
/// public) and its [`GpuBlock::FIELDS`].
#[macro_export]
macro_rules! gpu_block {
    ($(#[$m:meta])* $vis:vis struct $name:ident {
        $($(#[$fm:meta])* $field:ident : $ty:ty),+ $(,)?
    }) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name { $($(#[$fm])* pub $field: $ty),+ }

        impl $crate::describe::GpuBlock for $name {
            const FIELDS: &'static [(&'static str, usize)] =
                &[$((stringify!($field), std::mem::offset_of!($name, $field))),+];
        }
    };
}

/// Everything one pass kind defines. `P` is its parameters, `G` its GPU
/// parameter block.
pub struct PassKind<P: PassParams, G: GpuBlock> {
    /// Registry key, `pipeline.pass`.
    pub kind: &'static str,
    pub summary: &'static str,
    /// Where the algorithm comes from (paper and section).
    pub source: &'static str,
    /// The bindings, or `None` when the pass binds whatever the graph gives
    /// it (`common.clear`).
    pub bindings: Option<&'static [Binding]>,
    pub workgroup_size: u32,
    pub dispatch: Dispatch,
    pub shader: Shader,
    /// The CPU kernel, configured by checked parameters.
    pub kernel: fn(&P) -> Box<dyn CpuKernel>,
    /// The GPU parameter block from the parameters and the scene's counts.
    pub gpu: fn(&P, &Quantities) -> G,
    /// The draw state of a raster pass (`shader.fragment` is `Some`).
    pub raster: Option<fn(&P, &Quantities) -> RasterState>,
}

impl<P: PassParams, G: GpuBlock> PassKind<P, G> {
    /// The typed parameters of a compiled pass (see [`params::parse`]).
    pub fn params(&self, value: &ron::Value) -> Result<P, ParamError> {
        params::parse(value).map_err(|e| self.error(e))
    }

    /// The GPU block itself, for tests and tools that want fields, not words.
    pub fn gpu_block(&self, value: &ron::Value, q: &Quantities) -> Result<G, ParamError> {
        Ok((self.gpu)(&self.params(value)?, q))
    }

    fn error(&self, e: Invalid) -> ParamError {
        ParamError {
            kind: self.kind,
            param: e.key,
            message: e.message,
        }
    }
}

impl<P: PassParams, G: GpuBlock> PassDef for PassKind<P, G> {
    fn kind(&self) -> &'static str {
        self.kind
    }
    fn summary(&self) -> &'static str {
        self.summary
    }
    fn source(&self) -> &'static str {
        self.source
    }
    fn bindings(&self) -> Option<&'static [Binding]> {
        self.bindings
    }
    fn workgroup_size(&self) -> u32 {
        self.workgroup_size
    }
    fn dispatch(&self) -> Dispatch {
        self.dispatch
    }
    fn shader(&self) -> Shader {
        self.shader
    }
    fn entry(&self, value: &ron::Value) -> Result<&'static str, ParamError> {
        Ok(self.params(value)?.entry(self.shader.entry))
    }
    fn entries(&self) -> Vec<&'static str> {
        std::iter::once(self.shader.entry)
            .chain(P::VARIANT_ENTRIES.iter().copied())
            .collect()
    }
    fn check_params(&self, value: &ron::Value) -> Result<(), ParamError> {
        params::check::<P>(value)
            .map(drop)
            .map_err(|e| self.error(e))
    }
    fn param_defaults(&self) -> ron::Value {
        params::defaults::<P>()
    }
    fn cpu_kernel(&self, value: &ron::Value) -> Result<Box<dyn CpuKernel>, ParamError> {
        Ok((self.kernel)(&self.params(value)?))
    }
    fn gpu_params(&self, value: &ron::Value, q: &Quantities) -> Result<Vec<u32>, ParamError> {
        let block = self.gpu_block(value, q)?;
        Ok(bytemuck::pod_collect_to_vec(bytemuck::bytes_of(&block)))
    }
    fn gpu_layout(&self) -> Option<GpuLayout> {
        Some(GpuLayout {
            fields: G::FIELDS,
            size: std::mem::size_of::<G>(),
        })
    }
    fn raster(
        &self,
        value: &ron::Value,
        q: &Quantities,
    ) -> Result<Option<RasterState>, ParamError> {
        match self.raster {
            None => Ok(None),
            Some(draw) => Ok(Some(draw(&self.params(value)?, q))),
        }
    }
}
