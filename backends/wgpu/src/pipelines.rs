//! Pipelines, bind groups and parameter blocks, built once per session:
//! a frame only records them ([`crate::record`]).

use super::*;
use strandgraph_passes::raster_state::{Blend, ColorLoad, Compare, DepthLoad, Draw, RasterState};
use wgpu::util::DeviceExt;

/// One pass, ready to record every frame.
pub(crate) enum Built {
    Compute {
        pipeline: wgpu::ComputePipeline,
        /// One dispatch per bind group: a pass without fixed bindings
        /// (`common.clear`) dispatches once per resource it writes.
        dispatches: Vec<(wgpu::BindGroup, Launch)>,
    },
    Raster {
        /// One pipeline and bind group per [`Draw`] (automatic layouts are per pipeline).
        draws: Vec<(wgpu::RenderPipeline, wgpu::BindGroup)>,
        color: Vec<wgpu::TextureView>,
        depth: Option<wgpu::TextureView>,
        state: RasterState,
        vertices: u32,
    },
}

fn compare(c: Compare) -> wgpu::CompareFunction {
    match c {
        Compare::Always => wgpu::CompareFunction::Always,
        Compare::Less => wgpu::CompareFunction::Less,
        Compare::Equal => wgpu::CompareFunction::Equal,
    }
}

fn blend(b: Blend) -> Option<wgpu::BlendState> {
    match b {
        Blend::Replace => None,
        Blend::PremultipliedOverKeepAlpha => Some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        }),
    }
}

pub(crate) fn color_op(c: ColorLoad) -> wgpu::LoadOp<wgpu::Color> {
    match c {
        ColorLoad::Load => wgpu::LoadOp::Load,
        ColorLoad::Clear([r, g, b, a]) => wgpu::LoadOp::Clear(wgpu::Color {
            r: r.into(),
            g: g.into(),
            b: b.into(),
            a: a.into(),
        }),
    }
}

pub(crate) fn depth_op(d: DepthLoad) -> wgpu::LoadOp<f32> {
    match d {
        DepthLoad::Load => wgpu::LoadOp::Load,
        DepthLoad::Clear(v) => wgpu::LoadOp::Clear(v),
    }
}

/// Everything one pass needs to record, from its prepared form.
pub(crate) fn build(
    device: &wgpu::Device,
    plan: &Plan,
    instance: &Instance,
    prep: &Prepared<'_>,
    memory: &[Option<Memory>],
) -> Result<Built, WgpuError> {
    let pass = &plan.graph.passes[prep.p];
    let pass_error = |message: String| WgpuError::Pass {
        pass: pass.name.clone(),
        message,
    };
    let shader = prep.def.shader();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(shader.file),
        source: wgpu::ShaderSource::Naga(Cow::Owned(prep.composed.module.clone())),
    });
    let uniform = |words: &[u32]| {
        let mut padded = words.to_vec();
        padded.resize(words.len().next_multiple_of(4).max(4), 0);
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::cast_slice(&padded),
            usage: wgpu::BufferUsages::UNIFORM,
        })
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
            (Some(Memory::Texture { .. }), Some(view)) => wgpu::BindingResource::TextureView(view),
            _ => {
                return Err(pass_error(format!(
                    "`{}` has no memory",
                    prep.bindings[b].0
                )));
            }
        };
        Ok(wgpu::BindGroupEntry { binding, resource })
    };

    if let Some(state) = &prep.raster {
        // Bound resources are the bindings before the attachments.
        let bound: Vec<usize> = (0..prep.bindings.len())
            .filter(|b| !prep.attachments.iter().any(|(a, _)| a == b))
            .collect();
        let attachment = |usage: Usage| {
            prep.attachments
                .iter()
                .filter(move |(_, u)| *u == usage)
                .map(|(b, _)| *b)
        };
        let format_of = |b: usize| match &memory[prep.bindings[b].1] {
            Some(Memory::Texture { format, .. }) => Ok(*format),
            _ => Err(pass_error(format!(
                "attachment `{}` is not an image",
                prep.bindings[b].0
            ))),
        };
        let color: Vec<usize> = attachment(Usage::Color).collect();
        let depth = attachment(Usage::Depth).next();
        let params = uniform(&prep.params);
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: params.as_entire_binding(),
        }];
        for (n, &b) in bound.iter().enumerate() {
            entries.push(entry(n as u32 + 1, b)?);
        }
        let mut draws = Vec::new();
        for d in &state.draws {
            let targets: Vec<Option<wgpu::ColorTargetState>> = color
                .iter()
                .map(|&b| {
                    format_of(b).map(|format| {
                        Some(wgpu::ColorTargetState {
                            format,
                            blend: blend(d.blend),
                            write_mask: if d.color_writes {
                                wgpu::ColorWrites::ALL
                            } else {
                                wgpu::ColorWrites::empty()
                            },
                        })
                    })
                })
                .collect::<Result<_, _>>()?;
            let depth_stencil = match depth {
                Some(b) => Some(depth_state(format_of(b)?, d)),
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
                    cull_mode: state.cull_back_faces.then_some(wgpu::Face::Back),
                    ..Default::default()
                },
                depth_stencil,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(d.fragment),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(&pass.name),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            draws.push((pipeline, bind_group));
        }
        let vertices = u32::try_from(state.vertices)
            .map_err(|_| pass_error(format!("{} vertices are too many", state.vertices)))?;
        let view = |b: usize| {
            views[b]
                .clone()
                .ok_or_else(|| pass_error(format!("`{}` has no view", prep.bindings[b].0)))
        };
        return Ok(Built::Raster {
            draws,
            color: color.iter().map(|&b| view(b)).collect::<Result<_, _>>()?,
            depth: depth.map(view).transpose()?,
            state: state.clone(),
            vertices,
        });
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
    let max_groups = device.limits().max_compute_workgroups_per_dimension;
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
    let words_of = |r: usize| instance.sizes[r].bytes.div_ceil(4);
    let is_buffer = |r: usize| matches!(memory[r], Some(Memory::Buffer(..)));
    let bind_group = |entries: &[wgpu::BindGroupEntry<'_>]| {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&pass.name),
            layout: &layout,
            entries,
        })
    };
    let mut dispatches = Vec::new();
    if prep.def.bindings().is_none() {
        let Dispatch::CoverWrites { words_per_group } = prep.def.dispatch() else {
            return Err(pass_error(
                "a pass without fixed bindings must dispatch CoverWrites".into(),
            ));
        };
        for b in 0..prep.bindings.len() {
            let words = words_of(prep.bindings[b].1);
            // The resource's size in words goes into the last parameter word.
            let mut params = prep.params.clone();
            if let Some(last) = params.last_mut() {
                *last = u32::try_from(words)
                    .map_err(|_| pass_error(format!("{words} words to clear")))?;
            }
            let groups = check_groups(words.div_ceil(u64::from(words_per_group.max(1))))?;
            let ubuf = uniform(&params);
            let bg = bind_group(&[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: ubuf.as_entire_binding(),
                },
                entry(1, b)?,
            ]);
            dispatches.push((bg, Launch::Direct(groups)));
        }
        return Ok(Built::Compute {
            pipeline,
            dispatches,
        });
    }
    let ubuf = uniform(&prep.params);
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: ubuf.as_entire_binding(),
    }];
    for b in 0..prep.bindings.len() {
        entries.push(entry(b as u32 + 1, b)?);
    }
    let q = &instance.quantities;
    let most = prep
        .bindings
        .iter()
        .filter(|(_, r)| is_buffer(*r))
        .map(|(_, r)| words_of(*r))
        .max()
        .unwrap_or(0);
    let dispatch = prep.def.dispatch();
    let launch = match (dispatch.direct_groups(q, most), dispatch) {
        (Some(n), _) => Launch::Direct(check_groups(n)?),
        (None, Dispatch::Indirect { binding, word }) => {
            let r = prep
                .bindings
                .iter()
                .find(|(n, _)| n == binding)
                .map(|(_, r)| *r)
                .filter(|&r| is_buffer(r))
                .ok_or_else(|| pass_error(format!("indirect `{binding}` is not a bound buffer")))?;
            Launch::Indirect(r, word as u64 * 4)
        }
        (None, _) => unreachable!("only indirect dispatches have no direct count"),
    };
    dispatches.push((bind_group(&entries), launch));
    Ok(Built::Compute {
        pipeline,
        dispatches,
    })
}

fn depth_state(format: wgpu::TextureFormat, d: &Draw) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(d.depth_write),
        depth_compare: Some(compare(d.depth_compare)),
        stencil: Default::default(),
        bias: Default::default(),
    }
}
