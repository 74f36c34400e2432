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
//! ([`shaders`]) and handed to wgpu as naga modules. Binding 0 is the pass's
//! parameter block ([`PassDef::gpu_params`]), then the pass's `bindings()`
//! in order; raster passes (`Shader.fragment`) are render pipelines whose
//! colour and depth attachments are not bound. Each pass is one compute or
//! render pass with begin/end `TIMESTAMP_QUERY` writes.

pub mod shaders;

use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};
use shaders::{CAPABILITY_FEATURES, Composed, Shaders};
use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::{ImageFormat, ResourceDecl, Usage};
use strandgraph_graph::{Instance, LifetimeClass, Plan, Queue};
use strandgraph_passes::upload::Upload;
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
    /// The WGSL directory ([`shaders::default_dir`]).
    pub shader_dir: PathBuf,
    /// Which wgpu backends to look for an adapter on (Vulkan by default).
    pub backends: wgpu::Backends,
}

impl Default for WgpuBackend {
    fn default() -> Self {
        Self {
            shader_dir: shaders::default_dir(),
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

/// Looks up every live pass's definition, binds it, fills its parameter block
/// and composes its shader.
fn prepare<'d>(
    defs: &'d dyn Definitions,
    plan: &Plan,
    instance: &Instance,
    shaders: &mut Shaders,
) -> Result<Vec<Prepared<'d>>, WgpuError> {
    let g = &plan.graph;
    let mut out = Vec::new();
    for &p in &plan.order {
        let pass = &g.passes[p];
        let def = defs
            .definition(&pass.kind)
            .ok_or_else(|| WgpuError::NoDefinition {
                pass: pass.name.clone(),
                kind: pass.kind.clone(),
            })?;
        let chosen: Vec<(String, usize, Usage)> = strandgraph_passes::bind::bind(def, g, p)?
            .into_iter()
            .map(|b| (b.name, b.access.resource, b.access.usage))
            .collect();
        let attachments = chosen
            .iter()
            .enumerate()
            .filter(|(_, (_, _, u))| matches!(u, Usage::Color | Usage::Depth))
            .map(|(i, (_, _, u))| (i, *u))
            .collect();
        let bindings = chosen
            .into_iter()
            .map(|(n, r, _)| (n, g.physical(r)))
            .collect();
        if def.shader().fragment.is_some() && !RASTER_KINDS.contains(&def.kind()) {
            return Err(WgpuError::Pass {
                pass: pass.name.clone(),
                message: format!(
                    "`{}` is a raster pass whose pipeline state (blending, draw count, \
                     extra pipelines) the wgpu backend does not know yet; it runs \
                     {RASTER_KINDS:?}",
                    def.kind()
                ),
            });
        }
        let params = def.gpu_params(&pass.params, &instance.quantities)?;
        let file = def.shader().file;
        let composed = shaders
            .compose(file)
            .map_err(|e| WgpuError::Shader(format!("pass `{}`: {e}", pass.name)))?;
        out.push(Prepared {
            p,
            def,
            bindings,
            attachments,
            params,
            composed,
        });
    }
    Ok(out)
}

fn create_memory(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    plan: &Plan,
    instance: &Instance,
    inputs: &Upload,
    prepared: &[Prepared<'_>],
) -> Result<Vec<Option<Memory>>, WgpuError> {
    let g = &plan.graph;
    // Texture usages from how live passes access each image.
    let mut usages: Vec<wgpu::TextureUsages> =
        vec![wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST; g.resources.len()];
    let mut used = vec![false; g.resources.len()];
    for prep in prepared {
        for a in &g.passes[prep.p].accesses {
            let r = g.physical(a.resource);
            used[r] = true;
            usages[r] |= match a.usage {
                Usage::Sampled => wgpu::TextureUsages::TEXTURE_BINDING,
                Usage::Color | Usage::Depth => wgpu::TextureUsages::RENDER_ATTACHMENT,
                _ => wgpu::TextureUsages::STORAGE_BINDING,
            };
        }
    }
    let mut memory = Vec::with_capacity(g.resources.len());
    for (r, res) in g.resources.iter().enumerate() {
        let imported = res.decl.lifetime() != LifetimeClass::Transient;
        if res.version_of.is_some() || !(used[r] || imported) {
            memory.push(None);
            continue;
        }
        let size = instance.sizes[r];
        let init = inputs.resources.get(&res.name);
        if let Some(w) = init
            && w.len() as u64 * 4 > size.bytes
        {
            return Err(WgpuError::Input {
                resource: res.name.clone(),
                message: format!(
                    "{} words given, the plan sizes it at {} bytes",
                    w.len(),
                    size.bytes
                ),
            });
        }
        let made = match &res.decl {
            ResourceDecl::Buffer { .. } => {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&res.name),
                    size: size.bytes.max(4).next_multiple_of(4),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::INDIRECT
                        | wgpu::BufferUsages::COPY_SRC
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                if let Some(w) = init {
                    queue.write_buffer(&buffer, 0, bytemuck::cast_slice(w));
                }
                Memory::Buffer(buffer, size.bytes.div_ceil(4) as usize)
            }
            ResourceDecl::Image { format, .. } => {
                let extent = size.extent.unwrap_or([1, 1, 1]);
                let wformat = texture_format(*format);
                let mut usage = usages[r];
                if format.is_depth() {
                    usage -= wgpu::TextureUsages::STORAGE_BINDING;
                }
                let texture = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&res.name),
                    size: wgpu::Extent3d {
                        width: extent[0].max(1),
                        height: extent[1].max(1),
                        depth_or_array_layers: extent[2].max(1),
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wformat,
                    usage,
                    view_formats: &[],
                });
                let texel_bytes = format.texel_bytes() as u32;
                if let Some(w) = init {
                    let bytes: &[u8] = bytemuck::cast_slice(w);
                    let row = extent[0] * texel_bytes;
                    let rows = extent[1] * extent[2].max(1);
                    let mut full = bytes.to_vec();
                    full.resize((row * rows) as usize, 0);
                    queue.write_texture(
                        texture.as_image_copy(),
                        &full,
                        wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(row),
                            rows_per_image: Some(extent[1]),
                        },
                        texture.size(),
                    );
                }
                Memory::Texture {
                    texture,
                    format: wformat,
                    extent,
                    texel_bytes,
                }
            }
        };
        memory.push(Some(made));
    }
    Ok(memory)
}

/// The raster passes whose pipeline state [`color_load`] and
/// `record_and_run` know. Any other pass with a fragment entry is refused
/// rather than drawn with the wrong state.
const RASTER_KINDS: [&str; 3] = ["scene.depth_prepass", "scene.opaque", COMPOSE];

/// shaders/kulikov/compose.wgsl (header): six vertices per model, drawn back
/// to front with premultiplied blending (src One, dst OneMinusSrcAlpha) over
/// the loaded colour; then `fs_depth` with the same quads writes hair depth
/// into the loaded `scene.depth` where nearer (the CPU kernel's `z < depth`).
const COMPOSE: &str = "kulikov.compose";
const COMPOSE_DEPTH_ENTRY: &str = "fs_depth";

/// The raster state a render-pipeline pass needs, from its shader's header
/// (shaders/scene/depth_prepass.wgsl, shaders/scene/opaque.wgsl): triangle
/// list, counter-clockwise front faces, back faces culled; a written depth
/// attachment is cleared to 1.0 and tested Less, a read one is loaded and
/// tested Equal; scene.opaque clears its colour attachment to `background`.
fn color_load(
    def: &dyn PassDef,
    params: &ron::Value,
) -> Result<wgpu::LoadOp<wgpu::Color>, WgpuError> {
    if def.kind() == "scene.opaque" {
        let p = strandgraph_passes::scene::opaque::OpaqueParams::from_ron(params)?;
        let [r, g, b] = p.background.map(f64::from);
        Ok(wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }))
    } else {
        Ok(wgpu::LoadOp::Load)
    }
}

fn record_and_run(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    plan: &Plan,
    instance: &Instance,
    prepared: &[Prepared<'_>],
    memory: &[Option<Memory>],
) -> Result<Vec<PassTiming>, WgpuError> {
    let g = &plan.graph;
    let q = &instance.quantities;
    let limits = device.limits();
    let query_count = (prepared.len() * 2).max(2) as u32;
    let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("pass timestamps"),
        ty: wgpu::QueryType::Timestamp,
        count: query_count,
    });
    let resolved = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("timestamps"),
        size: u64::from(query_count) * 8,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let uniform = |words: &[u32]| {
        let mut padded = words.to_vec();
        padded.resize(words.len().next_multiple_of(4).max(4), 0);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: padded.len() as u64 * 4,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&padded));
        buffer
    };
    let buffer_of = |r: usize| match &memory[r] {
        Some(Memory::Buffer(b, _)) => Some(b),
        _ => None,
    };
    let words_of = |r: usize| instance.sizes[r].bytes.div_ceil(4);

    let mut encoder = device.create_command_encoder(&Default::default());
    let mut workgroups = Vec::new();
    for (i, prep) in prepared.iter().enumerate() {
        let pass = &g.passes[prep.p];
        let shader = prep.def.shader();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(shader.file),
            source: wgpu::ShaderSource::Naga(Cow::Owned(prep.composed.module.clone())),
        });
        let pass_error = |message: String| WgpuError::Pass {
            pass: pass.name.clone(),
            message,
        };
        let views: Vec<Option<wgpu::TextureView>> = prep
            .bindings
            .iter()
            .map(|(_, r)| match &memory[*r] {
                Some(Memory::Texture {
                    texture, format, ..
                }) => Some(texture.create_view(&wgpu::TextureViewDescriptor {
                    aspect: if format.is_depth_stencil_format() {
                        wgpu::TextureAspect::DepthOnly
                    } else {
                        wgpu::TextureAspect::All
                    },
                    ..Default::default()
                })),
                _ => None,
            })
            .collect();
        let entry = |binding: u32, b: usize| -> Result<wgpu::BindGroupEntry<'_>, WgpuError> {
            let r = prep.bindings[b].1;
            let resource = match (&memory[r], &views[b]) {
                (Some(Memory::Buffer(buf, _)), _) => buf.as_entire_binding(),
                (Some(Memory::Texture { .. }), Some(view)) => {
                    wgpu::BindingResource::TextureView(view)
                }
                _ => {
                    return Err(pass_error(format!(
                        "`{}` has no memory",
                        prep.bindings[b].0
                    )));
                }
            };
            Ok(wgpu::BindGroupEntry { binding, resource })
        };
        let (begin, end) = (i as u32 * 2, i as u32 * 2 + 1);

        if let Some(fragment) = shader.fragment {
            // A render pipeline: bound resources are the bindings before the attachments.
            let bound: Vec<usize> = (0..prep.bindings.len())
                .filter(|b| !prep.attachments.iter().any(|(a, _)| a == b))
                .collect();
            let depth = prep
                .attachments
                .iter()
                .find(|(_, u)| *u == Usage::Depth)
                .map(|(b, _)| *b);
            let color: Vec<usize> = prep
                .attachments
                .iter()
                .filter(|(_, u)| *u == Usage::Color)
                .map(|(b, _)| *b)
                .collect();
            let compose = prep.def.kind() == COMPOSE;
            let depth_writes = depth.is_some_and(|b| {
                pass.accesses
                    .iter()
                    .any(|a| g.physical(a.resource) == prep.bindings[b].1 && a.mode.writes())
            });
            let format_of = |b: usize| match &memory[prep.bindings[b].1] {
                Some(Memory::Texture { format, .. }) => Ok(*format),
                _ => Err(pass_error(format!(
                    "attachment `{}` is not an image",
                    prep.bindings[b].0
                ))),
            };
            let targets: Vec<Option<wgpu::ColorTargetState>> = color
                .iter()
                .map(|&b| {
                    format_of(b).map(|format| {
                        Some(wgpu::ColorTargetState {
                            format,
                            blend: compose.then_some(wgpu::BlendState {
                                color: wgpu::BlendComponent {
                                    src_factor: wgpu::BlendFactor::One,
                                    dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                                    operation: wgpu::BlendOperation::Add,
                                },
                                // The opaque image's alpha stays.
                                alpha: wgpu::BlendComponent {
                                    src_factor: wgpu::BlendFactor::Zero,
                                    dst_factor: wgpu::BlendFactor::One,
                                    operation: wgpu::BlendOperation::Add,
                                },
                            }),
                            write_mask: wgpu::ColorWrites::ALL,
                        })
                    })
                })
                .collect::<Result<_, _>>()?;
            let depth_stencil = match depth {
                Some(b) => Some(wgpu::DepthStencilState {
                    format: format_of(b)?,
                    depth_write_enabled: Some(depth_writes && !compose),
                    depth_compare: Some(if compose {
                        wgpu::CompareFunction::Always
                    } else if depth_writes {
                        wgpu::CompareFunction::Less
                    } else {
                        wgpu::CompareFunction::Equal
                    }),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                None => None,
            };
            let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(&pass.name),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(shader.entry),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode: (!compose).then_some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil: depth_stencil.clone(),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            });
            let params = uniform(&prep.params);
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            }];
            for (n, &b) in bound.iter().enumerate() {
                entries.push(entry(n as u32 + 1, b)?);
            }
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&pass.name),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            let load = color_load(prep.def, &pass.params)?;
            let color_attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> = color
                .iter()
                .map(|&b| {
                    views[b]
                        .as_ref()
                        .map(|view| wgpu::RenderPassColorAttachment {
                            view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load,
                                store: wgpu::StoreOp::Store,
                            },
                        })
                })
                .collect();
            let depth_stencil_attachment = match depth {
                Some(b) => Some(wgpu::RenderPassDepthStencilAttachment {
                    view: views[b]
                        .as_ref()
                        .ok_or_else(|| pass_error("depth attachment has no view".into()))?,
                    depth_ops: Some(wgpu::Operations {
                        load: if depth_writes && !compose {
                            wgpu::LoadOp::Clear(1.0)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                None => None,
            };
            let drawn = if compose {
                q.models * 6
            } else {
                q.triangles * 3
            };
            let vertices = u32::try_from(drawn)
                .map_err(|_| pass_error(format!("{drawn} vertices are too many")))?;
            // compose's second pipeline: hair depth, no colour writes.
            let depth_pass = if compose {
                let targets: Vec<Option<wgpu::ColorTargetState>> = targets
                    .iter()
                    .map(|t| {
                        t.as_ref().map(|t| wgpu::ColorTargetState {
                            format: t.format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::empty(),
                        })
                    })
                    .collect();
                let depth_stencil = depth_stencil.map(|d| wgpu::DepthStencilState {
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    ..d
                });
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(&pass.name),
                    layout: None,
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(shader.entry),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        ..Default::default()
                    },
                    depth_stencil,
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(COMPOSE_DEPTH_ENTRY),
                        compilation_options: Default::default(),
                        targets: &targets,
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                // Automatic layouts are per pipeline: its own bind group.
                let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(&pass.name),
                    layout: &pipeline.get_bind_group_layout(0),
                    entries: &entries,
                });
                Some((pipeline, bind_group))
            } else {
                None
            };
            let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&pass.name),
                color_attachments: &color_attachments,
                depth_stencil_attachment,
                timestamp_writes: Some(wgpu::RenderPassTimestampWrites {
                    query_set: &queries,
                    beginning_of_pass_write_index: Some(begin),
                    end_of_pass_write_index: Some(end),
                }),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&pipeline);
            rp.set_bind_group(0, &bind_group, &[]);
            // Draw 3 × triangles vertices, no vertex buffers (the shader headers).
            rp.draw(0..vertices, 0..1);
            if let Some((pipeline, bind_group)) = &depth_pass {
                rp.set_pipeline(pipeline);
                rp.set_bind_group(0, bind_group, &[]);
                rp.draw(0..vertices, 0..1);
            }
            workgroups.push(vertices);
            continue;
        }

        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&pass.name),
            layout: None,
            module: &module,
            entry_point: Some(shader.entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let layout = pipeline.get_bind_group_layout(0);
        let max_groups = limits.max_compute_workgroups_per_dimension;
        let check_groups = |groups: u64| {
            u32::try_from(groups)
                .ok()
                .filter(|&n| n <= max_groups)
                .ok_or_else(|| {
                    pass_error(format!(
                        "{groups} workgroups exceed the adapter's {max_groups} per dimension"
                    ))
                })
        };
        // One dispatch per bind group: a pass without fixed bindings
        // (common.clear) dispatches once per resource it writes.
        let mut dispatches: Vec<(wgpu::BindGroup, Launch)> = Vec::new();
        if prep.def.bindings().is_none() {
            for b in 0..prep.bindings.len() {
                let r = prep.bindings[b].1;
                let words = words_of(r);
                let mut params = prep.params.clone();
                if let Some(last) = params.last_mut() {
                    *last = u32::try_from(words)
                        .map_err(|_| pass_error(format!("{words} words to clear")))?;
                }
                let Dispatch::CoverWrites { words_per_group } = prep.def.dispatch() else {
                    return Err(pass_error(
                        "a pass without fixed bindings must dispatch CoverWrites".into(),
                    ));
                };
                let groups = check_groups(words.div_ceil(u64::from(words_per_group.max(1))))?;
                let ubuf = uniform(&params);
                let entries = [
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: ubuf.as_entire_binding(),
                    },
                    entry(1, b)?,
                ];
                let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some(&pass.name),
                    layout: &layout,
                    entries: &entries,
                });
                dispatches.push((bg, Launch::Direct(groups)));
            }
        } else {
            let ubuf = uniform(&prep.params);
            let mut entries = vec![wgpu::BindGroupEntry {
                binding: 0,
                resource: ubuf.as_entire_binding(),
            }];
            for b in 0..prep.bindings.len() {
                entries.push(entry(b as u32 + 1, b)?);
            }
            let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&pass.name),
                layout: &layout,
                entries: &entries,
            });
            let launch = match prep.def.dispatch() {
                Dispatch::Fixed(n) => Launch::Direct(check_groups(u64::from(n))?),
                Dispatch::PerElement {
                    quantity,
                    per_group,
                } => Launch::Direct(check_groups(
                    q.count(quantity).div_ceil(u64::from(per_group.max(1))),
                )?),
                Dispatch::Indirect { binding, word } => {
                    let r = prep
                        .bindings
                        .iter()
                        .find(|(n, _)| n == binding)
                        .map(|(_, r)| *r)
                        .ok_or_else(|| pass_error(format!("indirect `{binding}` is not bound")))?;
                    Launch::Indirect(r, word as u64 * 4)
                }
                Dispatch::CoverWrites { words_per_group } => {
                    let most = prep
                        .bindings
                        .iter()
                        .filter(|(_, r)| buffer_of(*r).is_some())
                        .map(|(_, r)| words_of(*r))
                        .max()
                        .unwrap_or(0);
                    Launch::Direct(check_groups(
                        most.div_ceil(u64::from(words_per_group.max(1))),
                    )?)
                }
            };
            dispatches.push((bg, launch));
        }
        let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(&pass.name),
            timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                query_set: &queries,
                beginning_of_pass_write_index: Some(begin),
                end_of_pass_write_index: Some(end),
            }),
        });
        cp.set_pipeline(&pipeline);
        let mut total = 0u32;
        for (bg, launch) in &dispatches {
            cp.set_bind_group(0, bg, &[]);
            match *launch {
                Launch::Direct(n) => {
                    total = total.saturating_add(n);
                    cp.dispatch_workgroups(n, 1, 1);
                }
                Launch::Indirect(r, offset) => {
                    let buffer = buffer_of(r)
                        .ok_or_else(|| pass_error("indirect arguments are not a buffer".into()))?;
                    cp.dispatch_workgroups_indirect(buffer, offset);
                }
            }
        }
        drop(cp);
        workgroups.push(total);
    }
    encoder.resolve_query_set(&queries, 0..query_count, &resolved, 0);
    queue.submit([encoder.finish()]);
    let ticks: Vec<u64> = bytemuck::cast_slice(&read_buffer(
        device,
        queue,
        &resolved,
        u64::from(query_count) * 8,
    )?)
    .to_vec();
    let period = f64::from(queue.get_timestamp_period());
    let mut timings = Vec::new();
    for (i, prep) in prepared.iter().enumerate() {
        let pass = &g.passes[prep.p];
        let (a, b) = (ticks[2 * i], ticks[2 * i + 1]);
        // Indirect dispatch counts live on the GPU: read them back for the report.
        let mut groups = workgroups[i];
        if let Dispatch::Indirect { binding, word } = prep.def.dispatch()
            && let Some((_, r)) = prep.bindings.iter().find(|(n, _)| n == binding)
            && let Some(buf) = buffer_of(*r)
        {
            let words = read_buffer(device, queue, buf, words_of(*r) * 4)?;
            let words: &[u32] = bytemuck::cast_slice(&words);
            groups = words.get(word).copied().unwrap_or(0);
        }
        timings.push(PassTiming {
            pass: prep.p,
            name: pass.name.clone(),
            queue: pass.queue,
            workgroups: groups,
            millis: b.saturating_sub(a) as f64 * period / 1e6,
        });
    }
    Ok(timings)
}

/// Copies `bytes` of `buffer` into a mappable buffer and reads it.
fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<u8>, WgpuError> {
    let size = bytes.max(4).next_multiple_of(4);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size.min(buffer.size()));
    queue.submit([encoder.finish()]);
    map_and_read(device, &staging)
}

fn map_and_read(device: &wgpu::Device, staging: &wgpu::Buffer) -> Result<Vec<u8>, WgpuError> {
    let mapped: Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>> = Arc::default();
    {
        let mapped = mapped.clone();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            *mapped.lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
        });
    }
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| WgpuError::Validation(format!("poll: {e}")))?;
    match mapped.lock().unwrap_or_else(|e| e.into_inner()).take() {
        Some(Ok(())) => {}
        Some(Err(e)) => return Err(WgpuError::Validation(format!("map: {e}"))),
        None => return Err(WgpuError::Validation("map did not complete".into())),
    }
    let data = staging
        .slice(..)
        .get_mapped_range()
        .map_err(|e| WgpuError::Validation(format!("map: {e:?}")))?
        .to_vec();
    staging.unmap();
    Ok(data)
}

impl Frame {
    /// A copy of resource `name`'s words, laid out as the CPU backend lays
    /// them out (images: rows of texels, no padding). `None` when the
    /// resource does not exist or has no memory (used by no live pass).
    pub fn read(&self, plan: &Plan, name: &str) -> Result<Option<Vec<u32>>, WgpuError> {
        let Some(r) = plan.graph.resource_id(name) else {
            return Ok(None);
        };
        let r = plan.graph.physical(r);
        let bytes = match &self.memory[r] {
            None => return Ok(None),
            Some(Memory::Buffer(b, _)) => read_buffer(&self.device, &self.queue, b, b.size())?,
            Some(Memory::Texture {
                texture,
                format,
                extent,
                texel_bytes,
            }) => {
                let row = extent[0] * texel_bytes;
                // wgpu copies rows at 256-byte strides (COPY_BYTES_PER_ROW_ALIGNMENT).
                let stride = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
                let layers = extent[2].max(1);
                let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("readback"),
                    size: u64::from(stride) * u64::from(extent[1] * layers),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut encoder = self.device.create_command_encoder(&Default::default());
                encoder.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture,
                        mip_level: 0,
                        origin: wgpu::Origin3d::ZERO,
                        aspect: if format.is_depth_stencil_format() {
                            wgpu::TextureAspect::DepthOnly
                        } else {
                            wgpu::TextureAspect::All
                        },
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: &staging,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: 0,
                            bytes_per_row: Some(stride),
                            rows_per_image: Some(extent[1]),
                        },
                    },
                    texture.size(),
                );
                self.queue.submit([encoder.finish()]);
                let padded = map_and_read(&self.device, &staging)?;
                padded
                    .chunks(stride as usize)
                    .flat_map(|r| &r[..row as usize])
                    .copied()
                    .collect()
            }
        };
        let mut words: Vec<u32> = bytes
            .chunks(4)
            .map(|c| {
                let mut w = [0u8; 4];
                w[..c.len()].copy_from_slice(c);
                u32::from_le_bytes(w)
            })
            .collect();
        if let Some(Memory::Buffer(_, len)) = &self.memory[r] {
            words.truncate(*len);
        }
        Ok(Some(words))
    }
}
