//! Recording and submitting the passes in plan order, with timestamps.

use super::*;

/// The raster passes whose pipeline state [`color_load`] and
/// `record_and_run` know. Any other pass with a fragment entry is refused
/// rather than drawn with the wrong state.
pub(crate) const RASTER_KINDS: [&str; 3] = ["scene.depth_prepass", "scene.opaque", COMPOSE];

/// shaders/kulikov/compose.wgsl (header): six vertices per model, drawn back
/// to front with premultiplied blending (src One, dst OneMinusSrcAlpha) over
/// the loaded colour; then `fs_depth` with the same quads writes hair depth
/// into the loaded `scene.depth` where nearer (the CPU kernel's `z < depth`).
pub(crate) const COMPOSE: &str = "kulikov.compose";
pub(crate) const COMPOSE_DEPTH_ENTRY: &str = "fs_depth";

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

pub(crate) fn record_and_run(
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
