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
//! Shaders are the WGSL under `shaders/`, composed with naga_oil
//! (`strandgraph_passes::wgsl`) and handed to wgpu as naga modules. Binding 0 is the pass's
//! parameter block ([`PassDef::gpu_params`]), then the pass's `bindings()`
//! in order; raster passes (`Shader.fragment`) are render pipelines whose
//! colour and depth attachments are not bound. Each pass is one compute or
//! render pass with begin/end `TIMESTAMP_QUERY` writes.

mod memory;
mod prepare;
mod readback;
mod record;
mod shaders;

use memory::create_memory;
use prepare::prepare;
use readback::read_buffer;
use record::{RASTER_KINDS, record_and_run};

use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};
use shaders::CAPABILITY_FEATURES;
use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl, Usage};
use strandgraph_graph::{Instance, LifetimeClass, Plan, Queue};
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
    #[error("no resource `{0}`")]
    NoResource(String),
}

/// How the wgpu backend runs.
#[derive(Debug, Clone)]
pub struct WgpuBackend {
    /// The WGSL directory ([`strandgraph_passes::wgsl::default_dir`]).
    pub shader_dir: PathBuf,
    /// Which wgpu backends to look for an adapter on (Vulkan by default).
    pub backends: wgpu::Backends,
}

impl Default for WgpuBackend {
    fn default() -> Self {
        Self {
            shader_dir: strandgraph_passes::wgsl::default_dir(),
            backends: wgpu::Backends::VULKAN,
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

/// A finished frame: the device and its resources, to read back, and
/// per-pass GPU times in plan order.
pub struct Frame {
    device: wgpu::Device,
    queue: wgpu::Queue,
    memory: Vec<Option<Memory>>,
    pub timings: Vec<PassTiming>,
    /// What the adapter is, and how the plan degraded on wgpu.
    pub notes: Vec<String>,
    pub adapter: String,
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
    composed: Composed,
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

impl WgpuBackend {
    /// Runs one frame with the built-in pass definitions.
    pub fn execute(
        &self,
        plan: &Plan,
        instance: &Instance,
        inputs: &Upload,
    ) -> Result<Frame, WgpuError> {
        self.execute_with(&Registry, plan, instance, inputs)
    }

    /// Runs one frame, looking pass kinds up in `defs`.
    pub fn execute_with(
        &self,
        defs: &dyn Definitions,
        plan: &Plan,
        instance: &Instance,
        inputs: &Upload,
    ) -> Result<Frame, WgpuError> {
        let mut shaders = Shaders::load(&self.shader_dir).map_err(WgpuError::Shader)?;
        let prepared = prepare(defs, plan, instance, &mut shaders)?;

        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = self.backends;
        let wgpu_instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(wgpu_instance.request_adapter(&Default::default()))
            .map_err(|e| WgpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let adapter_name = format!("{} ({:?}, {})", info.name, info.backend, info.driver);

        // Only the features the plan's passes need, each named with its pass.
        let available = adapter.features();
        let mut features = wgpu::Features::TIMESTAMP_QUERY;
        let mut missing = |feature: wgpu::Features, name: &'static str, pass: &str, why: String| {
            if available.contains(feature) {
                features |= feature;
                Ok(())
            } else {
                Err(WgpuError::MissingFeature {
                    adapter: adapter_name.clone(),
                    feature: name,
                    pass: pass.to_string(),
                    why,
                })
            }
        };
        if let Some(first) = prepared.first() {
            missing(
                wgpu::Features::TIMESTAMP_QUERY,
                "TIMESTAMP_QUERY",
                plan.pass_name(first.p),
                "per-pass GPU times".into(),
            )?;
        }
        for prep in &prepared {
            let name = plan.pass_name(prep.p);
            for (cap, feature, feature_name) in CAPABILITY_FEATURES {
                if prep.composed.needs.contains(cap) {
                    missing(
                        feature,
                        feature_name,
                        name,
                        format!("{} uses {cap:?}", prep.def.shader().file),
                    )?;
                }
            }
            if let Some(format) = read_only_storage_texture_needs(&prep.composed.module) {
                missing(
                    wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
                    "TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES",
                    name,
                    format!("read_write storage texture of {format:?}"),
                )?;
            }
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("strandgraph"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| WgpuError::Device(e.to_string()))?;
        let errors: Arc<Mutex<Vec<String>>> = Arc::default();
        {
            let errors = errors.clone();
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                errors
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(e.to_string());
            }));
        }
        let check = |what: &str| -> Result<(), WgpuError> {
            let mut errs = errors.lock().unwrap_or_else(|e| e.into_inner());
            if errs.is_empty() {
                Ok(())
            } else {
                let all = std::mem::take(&mut *errs).join("\n");
                Err(WgpuError::Validation(format!("{what}: {all}")))
            }
        };

        let mut notes = vec![
            format!("adapter: {adapter_name}; requested features: {features:?}"),
            "wgpu has one queue: AsyncCompute passes run on it in plan order; the plan's sync points hold trivially".into(),
        ];
        let memory = create_memory(&device, &queue, plan, instance, inputs, &prepared)?;
        let transient: u64 = instance.memory.placements.iter().map(|p| p.size).sum();
        notes.push(format!(
            "wgpu cannot alias memory: {} transients take {:.2} MiB in separate allocations (the plan's aliased heaps: {:.2} MiB)",
            instance.memory.placements.len(),
            transient as f64 / (1 << 20) as f64,
            instance.memory.bytes_with_aliasing as f64 / (1 << 20) as f64,
        ));
        check("creating resources")?;

        let timings = record_and_run(&device, &queue, plan, instance, &prepared, &memory)?;
        check("running the frame")?;
        Ok(Frame {
            device,
            queue,
            memory,
            timings,
            notes,
            adapter: adapter_name,
        })
    }
}
