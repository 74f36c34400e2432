//! # strandgraph-wgpu
//!
//! Runs a compiled `Plan` on wgpu 30, a thin runner like the CPU backend
//! (`backends/cpu/src/execute.rs`), with what wgpu cannot do declared in
//! every frame's [`Frame::notes`]:
//! - **no memory aliasing**: every transient gets its own buffer or texture;
//! - **one queue**: AsyncCompute passes run on the one queue in plan order,
//!   and the plan's sync points hold trivially; wgpu tracks the plan's
//!   barriers itself.
//!
//! Shaders are the WGSL under `shaders/` (built into the binary), composed with naga_oil
//! (`strandgraph_passes::wgsl`) and handed to wgpu as naga modules. Binding 0 is the pass's
//! parameter block ([`PassDef::gpu_params`]), then the pass's `bindings()`
//! in order; raster passes (`Shader.fragment`) are render pipelines whose
//! colour and depth attachments are not bound. Each pass is one compute or
//! render pass with begin/end `TIMESTAMP_QUERY` writes.

mod depth_upload;
mod gpu;
mod interface;
mod memory;
mod pipelines;
mod prepare;
mod readback;
mod record;
mod session;
mod shaders;

pub use gpu::Gpu;
use readback::read_buffer;
pub use session::{Frame, Session};

use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};
use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl, Usage};
use strandgraph_graph::{Instance, LifetimeClass, Plan, Queue};
use strandgraph_passes::LoopCounters;
use strandgraph_passes::upload::Upload;
use strandgraph_passes::wgsl::{Composed, Shaders};
use strandgraph_passes::{Definitions, Dispatch, PassDef, Registry};

#[derive(Debug, thiserror::Error)]
pub enum WgpuError {
    #[error("wgpu: no adapter ({0}); install a Vulkan driver (lavapipe: mesa-vulkan-drivers)")]
    NoAdapter(String),
    #[error("adapter `{adapter}` lacks wgpu feature {feature}, which pass `{pass}` needs ({why})")]
    MissingFeature {
        adapter: String,
        feature: &'static str,
        pass: String,
        why: String,
    },
    #[error("wgpu: request_device: {0}")]
    Device(String),
    #[error("pass `{pass}`: kind `{kind}` has no definition")]
    NoDefinition { pass: String, kind: String },
    #[error(transparent)]
    MissingBinding(#[from] strandgraph_passes::bind::MissingBinding),
    #[error(transparent)]
    Param(#[from] strandgraph_passes::ParamError),
    #[error("shader: {0}")]
    Shader(String),
    #[error("input `{resource}`: {message}")]
    Input { resource: String, message: String },
    #[error("pass `{pass}`: {message}")]
    Pass { pass: String, message: String },
    #[error("wgpu validation: {0}")]
    Validation(String),
    /// One submission holds every pass, so wgpu cannot say which one hung
    /// (the ash backend names it).
    #[error(
        "wgpu: the GPU did not finish the frame and its readback within {millis} ms (a shader that does not end, or a lost device; run on ash to see the pass)"
    )]
    Timeout { millis: u128 },
    #[error("no resource `{0}`")]
    NoResource(String),
}

/// How the wgpu backend runs.
#[derive(Debug, Clone)]
pub struct WgpuBackend {
    /// Read the WGSL from this directory instead of the shaders built into
    /// the binary ([`strandgraph_passes::wgsl::EMBEDDED`]); by default
    /// `$STRANDGRAPH_SHADERS` ([`strandgraph_passes::wgsl::override_dir`]).
    pub shader_dir: Option<PathBuf>,
    /// Which wgpu backends to look for an adapter on (Vulkan by default).
    pub backends: wgpu::Backends,
    /// Which passes get naga's loop counters, which wgpu adds to every
    /// shader it does not create trusted
    /// (`ShaderRuntimeChecks::force_loop_bounding`; [`LoopCounters`] says
    /// why). By default those whose graph keeps them.
    pub loop_counters: LoopCounters,
}

impl Default for WgpuBackend {
    fn default() -> Self {
        Self {
            shader_dir: strandgraph_passes::wgsl::override_dir(),
            backends: wgpu::Backends::VULKAN,
            loop_counters: LoopCounters::Graph,
        }
    }
}

/// One pass's GPU time, from its begin and end timestamps.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassTiming {
    pub pass: PassId,
    pub name: String,
    /// The queue the plan gave it; it ran on wgpu's one queue.
    pub queue: Queue,
    pub workgroups: u32,
    pub millis: f64,
}

enum Memory {
    /// The buffer and the plan's size in words.
    Buffer(wgpu::Buffer, usize),
    Texture {
        texture: wgpu::Texture,
        format: wgpu::TextureFormat,
        extent: [u32; 3],
        texel_bytes: u32,
    },
}

fn texture_format(f: ImageFormat) -> wgpu::TextureFormat {
    use wgpu::TextureFormat as T;
    match f {
        ImageFormat::R8Unorm => T::R8Unorm,
        ImageFormat::Rgba8Unorm => T::Rgba8Unorm,
        ImageFormat::Rgba8Srgb => T::Rgba8UnormSrgb,
        ImageFormat::R16Float => T::R16Float,
        ImageFormat::Rg16Float => T::Rg16Float,
        ImageFormat::Rgba16Float => T::Rgba16Float,
        ImageFormat::R32Float => T::R32Float,
        ImageFormat::R32Uint => T::R32Uint,
        ImageFormat::Rg32Uint => T::Rg32Uint,
        ImageFormat::Rgba32Float => T::Rgba32Float,
        ImageFormat::D32Float => T::Depth32Float,
    }
}

/// How a compute dispatch gets its workgroup count.
#[derive(Clone, Copy)]
enum Launch {
    Direct(u32),
    /// Resource id and byte offset of the `[x, y, z]` arguments.
    Indirect(usize, u64),
}

/// A pass ready to record.
struct Prepared<'d> {
    p: PassId,
    def: &'d dyn PassDef,
    /// Binding name → physical resource id, in `bindings()` order.
    bindings: Vec<(String, usize)>,
    /// Binding index (into `bindings`) → attachment usage, for raster passes.
    attachments: Vec<(usize, Usage)>,
    params: Vec<u32>,
    /// The compute (or vertex) entry point these parameters run (`PassDef::entry`).
    entry: &'static str,
    composed: Composed,
    /// The draw state, for raster passes.
    raster: Option<strandgraph_passes::RasterState>,
    /// Whether this pass's module has naga's loop counters
    /// ([`WgpuBackend::loop_counters`]).
    loop_bounding: bool,
}

fn read_only_storage_texture_needs(module: &naga::Module) -> Option<naga::StorageFormat> {
    // A read-write storage texture of a format other than the r32 ones needs
    // TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES (WebGPU allows read_write only
    // for r32float/r32uint/r32sint; wgpu-types `TextureFormat::guaranteed_format_features`).
    module.global_variables.iter().find_map(|(_, v)| {
        if v.space != AddressSpace::Handle {
            return None;
        }
        match &module.types[v.ty].inner {
            TypeInner::Image {
                class: ImageClass::Storage { format, access },
                ..
            } if access.contains(StorageAccess::LOAD | StorageAccess::STORE)
                && !matches!(
                    format,
                    naga::StorageFormat::R32Float
                        | naga::StorageFormat::R32Uint
                        | naga::StorageFormat::R32Sint
                ) =>
            {
                Some(*format)
            }
            _ => None,
        }
    })
}
