//! Running a frame: the upload prologue, the batches in an order where every
//! signal is submitted before its wait, timeline waits with a timeout, and
//! the timestamps read back.
//!
//! Timeline values: frame `f`'s pass at 1-based lane position `k` signals
//! `f·stride + k` on its lane's semaphore, so the plan's `SyncPoint::value`
//! is the wait value within a frame. The prologue (on the graphics queue)
//! waits for every lane's previous frame, copies the frame's inputs and puts
//! imported images in their first layout, then signals the upload semaphore
//! with `f + 1`, which each lane's first batch waits for.

use crate::barriers::Scope;
use crate::error::{AshError, VkContext};
use crate::memory::{Res, full_range};
use crate::session::{Frame, Session};
use crate::timing::PassTiming;
use ash::vk;
use strandgraph_graph::LifetimeClass;
use strandgraph_passes::upload::Upload;

impl Session {
    /// Uploads `inputs` (imported resources every frame, history resources on
    /// the first) and runs one frame; returns its per-pass GPU times.
    pub fn run(&mut self, inputs: &Upload) -> Result<Frame, AshError> {
        let g = &self.plan.graph;
        for (name, words) in &inputs.resources {
            let Some(r) = g.resource_id(name) else {
                continue;
            };
            let r = g.physical(r);
            let Some(&at) = self.staging_at.get(&r) else {
                continue;
            };
            let bytes = self.instance.sizes[r].bytes;
            if words.len() as u64 * 4 > bytes {
                return Err(AshError::Input {
                    resource: name.clone(),
                    message: format!(
                        "{} words given, the plan sizes it at {bytes} bytes",
                        words.len()
                    ),
                });
            }
            self.staging.write(at, words);
        }
        let f = self.frames;
        let prologue = self.record_prologue(inputs)?;
        let d = &self.gpu.device;
        let gq = self.gpu.queues[0].queue;

        // The prologue waits for the previous frame on every lane.
        let mut waits: Vec<vk::SemaphoreSubmitInfo<'_>> = Vec::new();
        if f > 0 {
            for lane in &self.lanes.lanes {
                waits.push(
                    vk::SemaphoreSubmitInfo::default()
                        .semaphore(lane.semaphore)
                        .value((f - 1) * self.stride + lane.passes.len() as u64)
                        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS),
                );
            }
        }
        let signal = [vk::SemaphoreSubmitInfo::default()
            .semaphore(self.upload_semaphore)
            .value(f + 1)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(prologue)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signal);
        // SAFETY: recorded command buffer; semaphores live.
        unsafe { d.queue_submit2(gq, &[submit], vk::Fence::null()) }
            .ctx("vkQueueSubmit2 (upload)")?;

        // Batches ordered by their first pass in plan order: a signal's
        // batch ends at or before the pass its wait starts with.
        let pos = |p| self.plan.position(p).unwrap_or(usize::MAX);
        let mut order: Vec<(usize, usize)> = Vec::new();
        for (l, lane) in self.lanes.lanes.iter().enumerate() {
            for b in 0..lane.batches.len() {
                order.push((l, b));
            }
        }
        order.sort_by_key(|&(l, b)| {
            pos(self.lanes.lanes[l].passes[self.lanes.lanes[l].batches[b].first])
        });
        for (l, b) in order {
            let lane = &self.lanes.lanes[l];
            let batch = &lane.batches[b];
            let mut waits: Vec<vk::SemaphoreSubmitInfo<'_>> = batch
                .waits
                .iter()
                .map(|&(other, k)| {
                    // ALL_COMMANDS: the plan's happens-before chains run
                    // through lane order after the wait (schedule.rs).
                    vk::SemaphoreSubmitInfo::default()
                        .semaphore(self.lanes.lanes[other].semaphore)
                        .value(f * self.stride + k)
                        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                })
                .collect();
            if b == 0 {
                waits.push(
                    vk::SemaphoreSubmitInfo::default()
                        .semaphore(self.upload_semaphore)
                        .value(f + 1)
                        .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS),
                );
            }
            let signal = [vk::SemaphoreSubmitInfo::default()
                .semaphore(lane.semaphore)
                .value(f * self.stride + batch.last as u64 + 1)
                .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(batch.cmd)];
            let submit = vk::SubmitInfo2::default()
                .wait_semaphore_infos(&waits)
                .command_buffer_infos(&cmds)
                .signal_semaphore_infos(&signal);
            let queue = self.gpu.queues[lane.queue].queue;
            // SAFETY: recorded command buffers; the previous frame completed.
            unsafe { d.queue_submit2(queue, &[submit], vk::Fence::null()) }
                .ctx("vkQueueSubmit2")?;
        }
        self.frames += 1;
        let t0 = std::time::Instant::now();
        self.wait_frame("the frame")?;
        tracing::debug!(ms = t0.elapsed().as_secs_f64() * 1e3, "frame completed");
        for (&r, &l) in &self.sync.last_layout {
            self.layouts.insert(r, l);
        }
        let timings = self.collect_timings()?;
        self.gpu.check("the frame")?;
        self.timings = timings.clone();
        Ok(Frame { timings })
    }

    /// Waits on the host for every lane's last value of the last frame.
    pub(crate) fn wait_frame(&self, what: &str) -> Result<(), AshError> {
        if self.frames == 0 {
            return Ok(());
        }
        let f = self.frames - 1;
        let semaphores: Vec<vk::Semaphore> = self.lanes.lanes.iter().map(|l| l.semaphore).collect();
        let values: Vec<u64> = self
            .lanes
            .lanes
            .iter()
            .map(|l| f * self.stride + l.passes.len() as u64)
            .collect();
        let info = vk::SemaphoreWaitInfo::default()
            .semaphores(&semaphores)
            .values(&values);
        let timeout = u64::try_from(self.timeout.as_nanos()).unwrap_or(u64::MAX);
        // SAFETY: live semaphores.
        match unsafe { self.gpu.device.wait_semaphores(&info, timeout) } {
            Ok(()) => Ok(()),
            Err(vk::Result::TIMEOUT) => Err(AshError::Timeout {
                what: format!("waiting for {what}"),
                millis: self.timeout.as_millis(),
            }),
            Err(e) => Err(AshError::vk(format!("waiting for {what}"), e)),
        }
    }

    fn collect_timings(&self) -> Result<Vec<PassTiming>, AshError> {
        let g = &self.plan.graph;
        let period = f64::from(self.gpu.props.limits.timestamp_period);
        let mut ticks = Vec::new();
        for q in 0..self.gpu.queues.len() {
            ticks.push(self.timestamps.read(&self.gpu, q)?);
        }
        let origin = ticks
            .iter()
            .flatten()
            .flat_map(|t| t.iter().copied())
            .filter(|&t| t != 0)
            .min();
        let mut out = Vec::new();
        for (i, &p) in self.plan.order.iter().enumerate() {
            let lane = &self.lanes.lanes[self.lanes.lane_of[p]];
            let k = lane.position(p).unwrap_or(0);
            let q = lane.queue;
            let (millis, span) = match &ticks[q] {
                Some(t) => {
                    let (a, b) = (t[2 * k], t[2 * k + 1]);
                    let ms = |x: u64| x as f64 * period / 1e6;
                    let dt = b.wrapping_sub(a) & self.timestamps.mask(q);
                    let o = origin.unwrap_or(a);
                    (
                        Some(ms(dt)),
                        Some((ms(a.saturating_sub(o)), ms(b.saturating_sub(o)))),
                    )
                }
                None => (None, None),
            };
            let workgroups = self
                .pipelines
                .built
                .iter()
                .find(|b| b.p == p)
                .map_or(0, |b| match &b.work {
                    crate::pipelines::Work::Compute { dispatches, .. } => dispatches
                        .iter()
                        .map(|(_, l)| match l {
                            crate::pipelines::Launch::Direct(n) => *n,
                            crate::pipelines::Launch::Indirect(..) => 0,
                        })
                        .fold(0u32, u32::saturating_add),
                    crate::pipelines::Work::Raster { vertices, .. } => *vertices,
                });
            let mut workgroups = Some(workgroups);
            if let Some(&(_, r, word)) = self.indirect.iter().find(|x| x.0 == i) {
                workgroups = if self.memory.aliases.iter().any(|&(a, b)| a == r || b == r) {
                    None
                } else {
                    self.read_words(r)?.get(word).copied()
                };
            }
            out.push(PassTiming {
                pass: p,
                name: g.passes[p].name.clone(),
                queue: g.passes[p].queue,
                family: self.gpu.queues[q].family,
                workgroups,
                millis,
                span,
            });
        }
        Ok(out)
    }

    /// Records the frame's upload prologue into a fresh command buffer.
    fn record_prologue(&mut self, inputs: &Upload) -> Result<vk::CommandBuffer, AshError> {
        let d = &self.gpu.device;
        let g = &self.plan.graph;
        let first_frame = self.frames == 0;
        // SAFETY: the previous frame (and its prologue) completed: nothing
        // from this pool is pending.
        unsafe { d.reset_command_pool(self.util_pool, vk::CommandPoolResetFlags::empty()) }
            .ctx("vkResetCommandPool")?;
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.util_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: valid pool.
        let cmd = unsafe { d.allocate_command_buffers(&info) }.ctx("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: fresh command buffer.
        unsafe { d.begin_command_buffer(cmd, &begin) }.ctx("vkBeginCommandBuffer")?;
        let wait_all = Scope {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::NONE,
        };
        let copy_write = Scope {
            stages: vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::CLEAR,
            access: vk::AccessFlags2::TRANSFER_WRITE,
        };
        let everything = Scope {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            access: vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
        };
        let mut to_dst = Vec::new();
        let mut buffer_work = Vec::new();
        let mut image_work = Vec::new();
        for (&r, &at) in &self.staging_at {
            let res = &g.resources[r];
            let given = inputs.resources.get(&res.name).map(|w| w.len() as u64 * 4);
            let history = res.decl.lifetime() == LifetimeClass::History;
            let upload = given.filter(|_| first_frame || !history);
            match &self.memory.res[r] {
                Some(Res::Buffer { buffer, size, .. }) => {
                    buffer_work.push((*buffer, *size, at, upload));
                }
                Some(res_img @ Res::Image { image, extent, .. }) => {
                    let old = self
                        .layouts
                        .get(&r)
                        .copied()
                        .unwrap_or(vk::ImageLayout::UNDEFINED);
                    let range = full_range(res_img.aspect(), extent[2]);
                    if first_frame || upload.is_some() {
                        to_dst.push(image_barrier(
                            *image,
                            range,
                            if first_frame {
                                vk::ImageLayout::UNDEFINED
                            } else {
                                old
                            },
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            wait_all,
                            copy_write,
                        ));
                    }
                    image_work.push((r, *image, range, *extent, res_img.aspect(), at, upload, old));
                }
                None => {}
            }
        }
        let cmd_barrier = |images: &[vk::ImageMemoryBarrier2<'_>],
                           global: &[vk::MemoryBarrier2<'_>]| {
            if images.is_empty() && global.is_empty() {
                return;
            }
            let info = vk::DependencyInfo::default()
                .image_memory_barriers(images)
                .memory_barriers(global);
            // SAFETY: recording.
            unsafe { d.cmd_pipeline_barrier2(cmd, &info) };
        };
        // Everything the previous frame did is done (semaphore waits with
        // ALL_COMMANDS); the copies follow that.
        let start = [vk::MemoryBarrier2::default()
            .src_stage_mask(wait_all.stages)
            .dst_stage_mask(copy_write.stages)
            .dst_access_mask(copy_write.access)];
        cmd_barrier(&to_dst, &start);
        // First frame: zero-fill (wgpu and the CPU backend start from zeros).
        if first_frame {
            for &(buffer, size, _, _) in &buffer_work {
                // SAFETY: recording; size is a multiple of 4.
                unsafe { d.cmd_fill_buffer(cmd, buffer, 0, size, 0) };
            }
            for &(_, image, range, _, aspect, _, _, _) in &image_work {
                // SAFETY: recording; the image is in TRANSFER_DST_OPTIMAL.
                unsafe {
                    if aspect == vk::ImageAspectFlags::DEPTH {
                        d.cmd_clear_depth_stencil_image(
                            cmd,
                            image,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &vk::ClearDepthStencilValue {
                                depth: 0.0,
                                stencil: 0,
                            },
                            &[range],
                        );
                    } else {
                        d.cmd_clear_color_image(
                            cmd,
                            image,
                            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                            &vk::ClearColorValue { uint32: [0; 4] },
                            &[range],
                        );
                    }
                }
            }
            let after_clear = [vk::MemoryBarrier2::default()
                .src_stage_mask(copy_write.stages)
                .src_access_mask(copy_write.access)
                .dst_stage_mask(copy_write.stages)
                .dst_access_mask(copy_write.access)];
            cmd_barrier(&[], &after_clear);
        }
        for &(buffer, _, at, upload) in &buffer_work {
            if let Some(bytes) = upload.filter(|&b| b > 0) {
                let region = vk::BufferCopy {
                    src_offset: at,
                    dst_offset: 0,
                    size: bytes,
                };
                // SAFETY: recording; in bounds (checked in `run`).
                unsafe { d.cmd_copy_buffer(cmd, self.staging.buffer, buffer, &[region]) };
            }
        }
        let mut to_first = Vec::new();
        for &(r, image, range, extent, aspect, at, upload, old) in &image_work {
            let first = self
                .sync
                .first_layout
                .get(&r)
                .copied()
                .unwrap_or(vk::ImageLayout::GENERAL);
            if let Some(bytes) = upload.filter(|&b| b > 0) {
                let texel = match &self.memory.res[r] {
                    Some(Res::Image { texel_bytes, .. }) => u64::from(*texel_bytes),
                    _ => 4,
                };
                let row = u64::from(extent[0]) * texel;
                let rows = (bytes.div_ceil(row.max(1)))
                    .min(u64::from(extent[1]) * u64::from(extent[2]))
                    as u32;
                // Whole rows given: copy them (CPU layout: rows of texels, layers after each other).
                let layers = (rows / extent[1].max(1)).max(u32::from(rows > 0));
                let height = if layers > 1 {
                    extent[1]
                } else {
                    rows.min(extent[1])
                };
                let region = vk::BufferImageCopy {
                    buffer_offset: at,
                    buffer_row_length: 0,
                    buffer_image_height: 0,
                    image_subresource: vk::ImageSubresourceLayers {
                        aspect_mask: aspect,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: layers.min(extent[2]),
                    },
                    image_offset: vk::Offset3D::default(),
                    image_extent: vk::Extent3D {
                        width: extent[0],
                        height,
                        depth: 1,
                    },
                };
                // SAFETY: recording; the image is in TRANSFER_DST_OPTIMAL.
                unsafe {
                    d.cmd_copy_buffer_to_image(
                        cmd,
                        self.staging.buffer,
                        image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[region],
                    )
                };
            }
            let from = if first_frame || upload.is_some() {
                vk::ImageLayout::TRANSFER_DST_OPTIMAL
            } else {
                old
            };
            if from != first || from == vk::ImageLayout::TRANSFER_DST_OPTIMAL {
                to_first.push(image_barrier(
                    image,
                    range,
                    from,
                    first,
                    copy_write.or(wait_all),
                    everything,
                ));
            }
        }
        cmd_barrier(&to_first, &[]);
        // SAFETY: recording.
        unsafe { d.end_command_buffer(cmd) }.ctx("vkEndCommandBuffer")?;
        Ok(cmd)
    }
}

pub(crate) fn image_barrier(
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    old: vk::ImageLayout,
    new: vk::ImageLayout,
    src: Scope,
    dst: Scope,
) -> vk::ImageMemoryBarrier2<'static> {
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(src.stages)
        .src_access_mask(src.access)
        .dst_stage_mask(dst.stages)
        .dst_access_mask(dst.access)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)
}
