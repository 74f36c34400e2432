//! Recording and submitting one frame: every built pass in plan order,
//! each inside begin/end timestamp writes.

use super::*;
use crate::pipelines::{Built, DrawCall, color_op, depth_op};

/// The query set and its resolve buffer, two timestamps per pass.
pub(crate) struct Timestamps {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    count: u32,
}

impl Timestamps {
    pub(crate) fn new(device: &wgpu::Device, passes: usize) -> Self {
        let count = (passes * 2).max(2) as u32;
        Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolved: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: u64::from(count) * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            count,
        }
    }
}

/// Records every pass, submits, and reads the timestamps back.
pub(crate) fn record_and_run(s: &Session) -> Result<Vec<PassTiming>, WgpuError> {
    let g = &s.plan.graph;
    let ts = &s.timestamps;
    let buffer_of = |r: usize| match &s.memory[r] {
        Some(Memory::Buffer(b, _)) => Some(b),
        _ => None,
    };
    let mut encoder = s.gpu.device.create_command_encoder(&Default::default());
    let mut workgroups = Vec::with_capacity(s.built.len());
    for (i, (prep, built)) in s.prepared.iter().zip(&s.built).enumerate() {
        let pass = &g.passes[prep.p];
        let (begin, end) = (i as u32 * 2, i as u32 * 2 + 1);
        match built {
            Built::Raster {
                draws,
                color,
                depth,
                state,
                call,
            } => {
                let color_attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> = color
                    .iter()
                    .map(|view| {
                        Some(wgpu::RenderPassColorAttachment {
                            view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: color_op(state.color_load),
                                store: wgpu::StoreOp::Store,
                            },
                        })
                    })
                    .collect();
                let depth_stencil_attachment =
                    depth
                        .as_ref()
                        .map(|view| wgpu::RenderPassDepthStencilAttachment {
                            view,
                            depth_ops: Some(wgpu::Operations {
                                load: depth_op(state.depth_load),
                                store: wgpu::StoreOp::Store,
                            }),
                            stencil_ops: None,
                        });
                let mut rp = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&pass.name),
                    color_attachments: &color_attachments,
                    depth_stencil_attachment,
                    timestamp_writes: Some(wgpu::RenderPassTimestampWrites {
                        query_set: &ts.queries,
                        beginning_of_pass_write_index: Some(begin),
                        end_of_pass_write_index: Some(end),
                    }),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                for (pipeline, bind_group) in draws {
                    rp.set_pipeline(pipeline);
                    rp.set_bind_group(0, bind_group, &[]);
                    // No vertex buffers: the vertex shader fetches (shader headers).
                    match *call {
                        DrawCall::Vertices(n) => rp.draw(0..n, 0..1),
                        DrawCall::Indirect(r, offset) => {
                            if let Some(buffer) = buffer_of(r) {
                                rp.draw_indirect(buffer, offset);
                            }
                        }
                        DrawCall::MeshTasks(groups) => rp.draw_mesh_tasks(groups, 1, 1),
                    }
                }
                workgroups.push(match *call {
                    DrawCall::Vertices(n) | DrawCall::MeshTasks(n) => n,
                    DrawCall::Indirect(..) => 0,
                });
            }
            Built::Compute {
                pipeline,
                dispatches,
            } => {
                let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&pass.name),
                    timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                        query_set: &ts.queries,
                        beginning_of_pass_write_index: Some(begin),
                        end_of_pass_write_index: Some(end),
                    }),
                });
                cp.set_pipeline(pipeline);
                let mut total = 0u32;
                for (bg, launch) in dispatches {
                    cp.set_bind_group(0, bg, &[]);
                    match *launch {
                        Launch::Direct(n) => {
                            total = total.saturating_add(n);
                            cp.dispatch_workgroups(n, 1, 1);
                        }
                        Launch::Indirect(r, offset) => {
                            // `build` checked that `r` is a buffer.
                            if let Some(buffer) = buffer_of(r) {
                                cp.dispatch_workgroups_indirect(buffer, offset);
                            }
                        }
                    }
                }
                workgroups.push(total);
            }
        }
    }
    encoder.resolve_query_set(&ts.queries, 0..ts.count, &ts.resolved, 0);
    s.gpu.queue.submit([encoder.finish()]);
    let ticks = read_buffer(
        &s.gpu.device,
        &s.gpu.queue,
        &ts.resolved,
        u64::from(ts.count) * 8,
    )?;
    let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&ticks);
    let period = f64::from(s.gpu.queue.get_timestamp_period());
    let mut timings = Vec::new();
    for (i, prep) in s.prepared.iter().enumerate() {
        let pass = &g.passes[prep.p];
        let (a, b) = (ticks[2 * i], ticks[2 * i + 1]);
        // Indirect dispatch counts live on the GPU: read them back for the report.
        let mut groups = workgroups[i];
        if let Dispatch::Indirect { binding, word } = prep.def.dispatch()
            && let Some((_, r)) = prep.bindings.iter().find(|(n, _)| n == binding)
            && let Some(buf) = buffer_of(*r)
        {
            let bytes = read_buffer(&s.gpu.device, &s.gpu.queue, buf, (word as u64 + 1) * 4)?;
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
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
