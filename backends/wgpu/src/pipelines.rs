//! Pipelines, bind groups and parameter blocks, built once per session:
//! a frame only records them ([`crate::record`]).
//!
//! Every pass starts from a [`PassContext`] (its shader module and texture
//! views); raster passes then build one render pipeline per draw
//! ([`raster`]), compute passes one compute pipeline and its dispatches.

mod raster;

use super::*;
use strandgraph_passes::raster_state::RasterState;
use wgpu::util::DeviceExt;

// `crate::record` turns a pass's load operations into wgpu's when it records.
pub(crate) use raster::{color_op, depth_op};

/// One pass, ready to record every frame.
pub(crate) enum Built {
    Compute {
        pipeline: wgpu::ComputePipeline,
        /// One dispatch per bind group: a pass without fixed bindings
        /// (`common.clear`) dispatches once per resource it writes.
        dispatches: Vec<(wgpu::BindGroup, Launch)>,
    },
    Raster {
        /// One pipeline and bind group per [`Draw`](strandgraph_passes::raster_state::Draw)
        /// (automatic layouts are per pipeline).
        draws: Vec<(wgpu::RenderPipeline, wgpu::BindGroup)>,
        color: Vec<wgpu::TextureView>,
        depth: Option<wgpu::TextureView>,
        state: Box<RasterState>,
        call: DrawCall,
    },
}

/// How a raster pass's draws are issued ([`Geometry`](strandgraph_passes::raster_state::Geometry)).
#[derive(Debug, Clone, Copy)]
pub(crate) enum DrawCall {
    Vertices(u32),
    /// The arguments' physical resource and byte offset.
    Indirect(usize, u64),
    /// Task workgroups of a mesh pipeline.
    MeshTasks(u32),
}

/// Everything one pass needs to record, from its prepared form.
pub(crate) fn build(
    device: &wgpu::Device,
    plan: &Plan,
    instance: &Instance,
    prep: &Prepared<'_>,
    memory: &[Option<Memory>],
) -> Result<Built, WgpuError> {
    let cx = PassContext::new(device, plan, instance, prep, memory);
    if let Some(state) = &prep.raster {
        return raster::build_raster(&cx, state);
    }
    let pipeline = cx.compute_pipeline();
    let layout = pipeline.get_bind_group_layout(0);
    let dispatches = if prep.def.bindings().is_none() {
        build_clear(&cx, &layout)?
    } else {
        vec![build_compute(&cx, &layout)?]
    };
    Ok(Built::Compute {
        pipeline,
        dispatches,
    })
}

/// One pass's shader module and texture views, and the helpers every kind
/// of pipeline binds its resources with.
struct PassContext<'a> {
    device: &'a wgpu::Device,
    plan: &'a Plan,
    instance: &'a Instance,
    prep: &'a Prepared<'a>,
    memory: &'a [Option<Memory>],
    name: &'a str,
    module: wgpu::ShaderModule,
    /// One view per binding that is a texture (depth formats show depth only).
    views: Vec<Option<wgpu::TextureView>>,
}

impl<'a> PassContext<'a> {
    fn new(
        device: &'a wgpu::Device,
        plan: &'a Plan,
        instance: &'a Instance,
        prep: &'a Prepared<'a>,
        memory: &'a [Option<Memory>],
    ) -> Self {
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(prep.def.shader().file),
            source: wgpu::ShaderSource::Naga(Cow::Owned(prep.composed.module.clone())),
        };
        let checks = wgpu::ShaderRuntimeChecks {
            force_loop_bounding: prep.loop_bounding,
            ..wgpu::ShaderRuntimeChecks::checked()
        };
        // SAFETY: every check but loop bounding stays on, and without it
        // the caller must ensure no loop is endless: our shaders' loops end
        // by construction (WgpuBackend::loop_counters).
        let module = unsafe { device.create_shader_module_trusted(desc, checks) };
        let views = prep
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
        Self {
            device,
            plan,
            instance,
            prep,
            memory,
            name: &plan.graph.passes[prep.p].name,
            module,
            views,
        }
    }

    fn error(&self, message: String) -> WgpuError {
        WgpuError::Pass {
            pass: self.name.to_owned(),
            message,
        }
    }

    /// A parameter block, padded to whole 16-byte rows (at least one).
    fn uniform(&self, words: &[u32]) -> wgpu::Buffer {
        let mut padded = words.to_vec();
        padded.resize(words.len().next_multiple_of(4).max(4), 0);
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::cast_slice(&padded),
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    /// The parameter block at binding 0, then the bindings `bound` (indices
    /// into `prep.bindings`) at 1, 2, ….
    fn entries<'b>(
        &'b self,
        params: &'b wgpu::Buffer,
        bound: &[usize],
    ) -> Result<Vec<wgpu::BindGroupEntry<'b>>, WgpuError> {
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        }];
        for (n, &b) in bound.iter().enumerate() {
            entries.push(self.entry(n as u32 + 1, b)?);
        }
        Ok(entries)
    }

    fn entry(&self, binding: u32, b: usize) -> Result<wgpu::BindGroupEntry<'_>, WgpuError> {
        let resource = match (&self.memory[self.prep.bindings[b].1], &self.views[b]) {
            (Some(Memory::Buffer(buf, _)), _) => {
                let limit = self.device.limits().max_storage_buffer_binding_size;
                if buf.size() > limit {
                    return Err(WgpuError::MissingFeature {
                        adapter: self.device.adapter_info().name,
                        feature: "max_storage_buffer_binding_size",
                        pass: self.name.to_string(),
                        why: format!(
                            "it binds `{}` whole, {} MiB, over the limit of {} MiB",
                            self.prep.bindings[b].0,
                            buf.size() >> 20,
                            limit >> 20
                        ),
                    });
                }
                buf.as_entire_binding()
            }
            (Some(Memory::Texture { .. }), Some(view)) => wgpu::BindingResource::TextureView(view),
            _ => {
                return Err(self.error(format!("`{}` has no memory", self.prep.bindings[b].0)));
            }
        };
        Ok(wgpu::BindGroupEntry { binding, resource })
    }

    fn bind_group(
        &self,
        layout: &wgpu::BindGroupLayout,
        entries: &[wgpu::BindGroupEntry<'_>],
    ) -> wgpu::BindGroup {
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.name),
            layout,
            entries,
        })
    }

    fn compute_pipeline(&self) -> wgpu::ComputePipeline {
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(self.name),
                layout: None,
                module: &self.module,
                entry_point: Some(self.prep.entry),
                compilation_options: Default::default(),
                cache: None,
            })
    }

    /// A direct dispatch's workgroup count, if the adapter can launch it.
    fn workgroups(&self, groups: u64) -> Result<u32, WgpuError> {
        let max_groups = self.device.limits().max_compute_workgroups_per_dimension;
        u32::try_from(groups)
            .ok()
            .filter(|&n| n <= max_groups)
            .ok_or_else(|| {
                self.error(format!(
                    "{groups} workgroups exceed the adapter's {max_groups} per dimension"
                ))
            })
    }

    /// Resource `r`'s size in whole words.
    fn words_of(&self, r: usize) -> u64 {
        self.instance.sizes[r].bytes.div_ceil(4)
    }

    fn is_buffer(&self, r: usize) -> bool {
        matches!(self.memory[r], Some(Memory::Buffer(..)))
    }
}

/// A pass without fixed bindings (`common.clear`) binds whatever it writes;
/// it must dispatch CoverWrites, once per resource, with the resource's
/// size in words as its last parameter.
fn build_clear(
    cx: &PassContext<'_>,
    layout: &wgpu::BindGroupLayout,
) -> Result<Vec<(wgpu::BindGroup, Launch)>, WgpuError> {
    let Dispatch::CoverWrites { words_per_group } = cx.prep.def.dispatch() else {
        return Err(cx.error("a pass without fixed bindings must dispatch CoverWrites".into()));
    };
    let mut dispatches = Vec::new();
    for b in 0..cx.prep.bindings.len() {
        let words = cx.words_of(cx.prep.bindings[b].1);
        let mut params = cx.prep.params.clone();
        if let Some(last) = params.last_mut() {
            *last =
                u32::try_from(words).map_err(|_| cx.error(format!("{words} words to clear")))?;
        }
        let groups = cx.workgroups(Dispatch::cover_groups(words, words_per_group))?;
        let params = cx.uniform(&params);
        let bind_group = cx.bind_group(layout, &cx.entries(&params, &[b])?);
        dispatches.push((bind_group, Launch::Direct(groups)));
    }
    Ok(dispatches)
}

/// A compute pass with fixed bindings: one bind group, launched with a
/// workgroup count from the quantities and its largest buffer, or from
/// arguments a pass wrote into a bound buffer.
fn build_compute(
    cx: &PassContext<'_>,
    layout: &wgpu::BindGroupLayout,
) -> Result<(wgpu::BindGroup, Launch), WgpuError> {
    let params = cx.uniform(&cx.prep.params);
    let all: Vec<usize> = (0..cx.prep.bindings.len()).collect();
    let entries = cx.entries(&params, &all)?;
    let launch = launch(cx)?;
    Ok((cx.bind_group(layout, &entries), launch))
}

fn launch(cx: &PassContext<'_>) -> Result<Launch, WgpuError> {
    let bindings = &cx.prep.bindings;
    let words = |name: &str| {
        let r = bindings.iter().find(|(n, _)| n == name);
        r.map_or(0, |(_, r)| cx.words_of(*r))
    };
    cx.prep
        .def
        .check_binding_sizes(&words)
        .map_err(|e| cx.error(e))?;
    let most = bindings
        .iter()
        .filter(|(_, r)| cx.is_buffer(*r))
        .map(|(_, r)| cx.words_of(*r))
        .max()
        .unwrap_or(0);
    let dispatch = cx.prep.def.dispatch();
    Ok(
        match (
            dispatch.direct_groups(&cx.instance.quantities, most),
            dispatch,
        ) {
            (Some(n), _) => Launch::Direct(cx.workgroups(n)?),
            (None, Dispatch::Indirect { binding, word }) => {
                let r = bindings
                    .iter()
                    .find(|(n, _)| n == binding)
                    .map(|(_, r)| *r)
                    .filter(|&r| cx.is_buffer(r))
                    .ok_or_else(|| {
                        cx.error(format!("indirect `{binding}` is not a bound buffer"))
                    })?;
                Dispatch::check_indirect(binding, word, cx.words_of(r)).map_err(|e| cx.error(e))?;
                Launch::Indirect(r, word as u64 * 4)
            }
            (None, _) => unreachable!("only indirect dispatches have no direct count"),
        },
    )
}
