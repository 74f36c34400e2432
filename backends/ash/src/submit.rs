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
use crate::pipelines::DrawCall;
use crate::record::Stamps;
use crate::session::{Frame, Session};
use crate::timing::PassTiming;
use ash::vk;
use strandgraph_passes::upload::Upload;

impl Session {
    /// Uploads `inputs` (imported resources every frame, history resources on
    /// the first) and runs one frame; returns its per-pass GPU times.
    pub fn run(&mut self, inputs: &Upload) -> Result<Frame, AshError> {
        self.run_with(inputs, Stamps::Passes)?;
        let timings = self.collect_timings()?;
        self.gpu.check("the frame")?;
        self.timings = timings.clone();
        Ok(Frame { timings })
    }

    /// Runs one frame as [`Session::run`] does, with timestamps only where
    /// each queue's part of it begins and ends ([`Stamps::Frame`]); returns
    /// its GPU time in ms, first begin to last end, or `None` where no
    /// queue it ran on has timestamps. Per-pass times keep those of the
    /// last [`Session::run`].
    pub fn run_frame_timed(&mut self, inputs: &Upload) -> Result<Option<f64>, AshError> {
        self.run_with(inputs, Stamps::Frame)?;
        let span = self.frame_span()?;
        self.gpu.check("the frame")?;
        Ok(span)
    }

    pub(crate) fn run_with(&mut self, inputs: &Upload, stamps: Stamps) -> Result<(), AshError> {
        self.stage_inputs(inputs)?;
        let prologue = self.record_prologue(inputs)?;
        self.submit_prologue(prologue)?;
        self.submit_batches(stamps)?;
        self.frames += 1;
        let t0 = std::time::Instant::now();
        self.wait_frame("the frame")?;
        tracing::debug!(ms = t0.elapsed().as_secs_f64() * 1e3, "frame completed");
        for (&r, &l) in &self.sync.last_layout {
            self.layouts.insert(r, l);
        }
        Ok(())
    }

    /// Copies the given inputs into the staging buffer.
    fn stage_inputs(&self, inputs: &Upload) -> Result<(), AshError> {
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
        Ok(())
    }

    /// A wait for (or signal of) `value` on `semaphore`, covering all commands.
    pub(crate) fn at(semaphore: vk::Semaphore, value: u64) -> vk::SemaphoreSubmitInfo<'static> {
        vk::SemaphoreSubmitInfo::default()
            .semaphore(semaphore)
            .value(value)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
    }

    /// Waits for every lane's last value of the last frame (none before the first).
    pub(crate) fn after_last_frame(&self) -> Vec<vk::SemaphoreSubmitInfo<'static>> {
        let Some(f) = self.frames.checked_sub(1) else {
            return Vec::new();
        };
        self.lanes
            .lanes
            .iter()
            .map(|lane| {
                let last = f * self.stride + lane.passes.len() as u64;
                Self::at(lane.semaphore.raw(), last)
            })
            .collect()
    }

    /// Submits the prologue: after every lane's previous frame; signals the
    /// upload semaphore with `frame + 1`.
    fn submit_prologue(&self, prologue: vk::CommandBuffer) -> Result<(), AshError> {
        let waits = self.after_last_frame();
        let signal = [Self::at(self.upload_semaphore.raw(), self.frames + 1)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(prologue)];
        let submit = vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signal);
        let gq = self.gpu.queues[0].queue;
        // SAFETY: recorded command buffer; semaphores live.
        unsafe {
            self.gpu
                .device
                .queue_submit2(gq, &[submit], vk::Fence::null())
        }
        .ctx("vkQueueSubmit2 (upload)")
    }

    /// Submits every batch of the frame, ordered by their first pass in plan
    /// order: a signal's batch ends at or before the pass its wait starts
    /// with, so every signal is submitted before its wait. With
    /// [`crate::Submit::PerQueue`], one call per queue takes that queue's
    /// batches in that order.
    fn submit_batches(&self, stamps: Stamps) -> Result<(), AshError> {
        let f = self.frames;
        let pos = |p| self.plan.position(p).unwrap_or(usize::MAX);
        let mut order: Vec<(usize, usize)> = Vec::new();
        for (l, lane) in self.lanes.lanes.iter().enumerate() {
            order.extend((0..lane.batches.len()).map(|b| (l, b)));
        }
        order.sort_by_key(|&(l, b)| {
            let lane = &self.lanes.lanes[l];
            pos(lane.passes[lane.batches[b].first])
        });
        // Per batch: its queue, waits, signal and command buffer, kept alive
        // until the submit calls below.
        let mut parts = Vec::with_capacity(order.len());
        for &(l, b) in &order {
            let lane = &self.lanes.lanes[l];
            let batch = &lane.batches[b];
            // ALL_COMMANDS: the plan's happens-before chains run through
            // lane order after the wait (schedule.rs).
            let mut waits: Vec<vk::SemaphoreSubmitInfo<'_>> = batch
                .waits
                .iter()
                .map(|&(other, k)| {
                    Self::at(self.lanes.lanes[other].semaphore.raw(), f * self.stride + k)
                })
                .collect();
            if b == 0 {
                waits.push(Self::at(self.upload_semaphore.raw(), f + 1));
            }
            let last = f * self.stride + batch.last as u64 + 1;
            let signal = [Self::at(lane.semaphore.raw(), last)];
            let cmds =
                [vk::CommandBufferSubmitInfo::default()
                    .command_buffer(batch.cmds[stamps as usize])];
            parts.push((lane.queue, waits, signal, cmds));
        }
        let submits: Vec<(usize, vk::SubmitInfo2<'_>)> = parts
            .iter()
            .map(|(q, waits, signal, cmds)| {
                let info = vk::SubmitInfo2::default()
                    .wait_semaphore_infos(waits)
                    .command_buffer_infos(cmds)
                    .signal_semaphore_infos(signal);
                (*q, info)
            })
            .collect();
        let per_queue = self.submit == crate::Submit::PerQueue;
        let calls: Vec<(usize, Vec<vk::SubmitInfo2<'_>>)> = if per_queue {
            // Timeline semaphores may be waited on before their signal is
            // submitted.
            (0..self.gpu.queues.len())
                .map(|q| {
                    (
                        q,
                        submits.iter().filter(|s| s.0 == q).map(|s| s.1).collect(),
                    )
                })
                .filter(|(_, v): &(usize, Vec<_>)| !v.is_empty())
                .collect()
        } else {
            submits.iter().map(|&(q, s)| (q, vec![s])).collect()
        };
        for (q, infos) in calls {
            let queue = self.gpu.queues[q].queue;
            // SAFETY: recorded command buffers; the previous frame completed.
            unsafe {
                self.gpu
                    .device
                    .queue_submit2(queue, &infos, vk::Fence::null())
            }
            .ctx("vkQueueSubmit2")?;
        }
        Ok(())
    }

    /// Waits on the host for every lane's last value of the last frame.
    pub(crate) fn wait_frame(&self, what: &str) -> Result<(), AshError> {
        if self.frames == 0 {
            return Ok(());
        }
        let f = self.frames - 1;
        let semaphores: Vec<vk::Semaphore> =
            self.lanes.lanes.iter().map(|l| l.semaphore.raw()).collect();
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
                what: format!("waiting for {what}{}", self.unfinished(f)),
                millis: self.timeout.as_millis(),
            }),
            Err(e) => Err(AshError::vk(format!("waiting for {what}"), e)),
        }
    }

    /// The passes frame `f` is stuck at: per lane, the first pass whose
    /// batch has not signalled its timeline value (a hung shader is in it,
    /// or in a pass submitted in the same batch after it).
    fn unfinished(&self, f: u64) -> String {
        let g = &self.plan.graph;
        let mut stuck = Vec::new();
        for lane in &self.lanes.lanes {
            // SAFETY: a live timeline semaphore.
            let value = unsafe {
                self.gpu
                    .device
                    .get_semaphore_counter_value(lane.semaphore.raw())
            };
            let done = value.map_or(0, |v| v.saturating_sub(f * self.stride)) as usize;
            if let Some(&p) = lane.passes.get(done) {
                stuck.push(format!(
                    "pass `{}` (queue {}, {done} of {} passes done)",
                    g.passes[p].name,
                    lane.queue,
                    lane.passes.len()
                ));
            }
        }
        if stuck.is_empty() {
            String::new()
        } else {
            format!(" (unfinished: {})", stuck.join(", "))
        }
    }

    /// The last frame's first lane begin to last lane end, from the
    /// queries [`Stamps::Frame`] writes.
    fn frame_span(&self) -> Result<Option<f64>, AshError> {
        let period = f64::from(self.gpu.props.limits.timestamp_period);
        let mut spans = Vec::new();
        for lane in &self.lanes.lanes {
            let q = lane.queue;
            let last = 2 * lane.passes.len() as u32 - 1;
            if let Some((a, b)) = self.timestamps.read_pair(&self.gpu, q, 0, last)? {
                spans.push((
                    a,
                    a.wrapping_add(b.wrapping_sub(a) & self.timestamps.mask(q)),
                ));
            }
        }
        let begin = spans.iter().map(|s| s.0).min();
        let end = spans.iter().map(|s| s.1).max();
        Ok(begin
            .zip(end)
            .map(|(a, b)| b.saturating_sub(a) as f64 * period / 1e6))
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
                    crate::pipelines::Work::Raster { call, .. } => match call {
                        DrawCall::Vertices(n) | DrawCall::MeshTasks(n, _) => *n,
                        DrawCall::Indirect(..) => 0,
                    },
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
