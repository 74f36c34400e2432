//! Lanes, batches and their command buffers, recorded once per session.
//!
//! Each plan lane (`graph/src/schedule.rs`) runs on a backend queue:
//! Graphics and Transfer on the graphics family, AsyncCompute on the
//! compute-only family when there is one. Lanes that land on one queue are
//! merged in plan order, and their sync points become the plain barriers of
//! their dependencies (barriers.rs). A lane is cut into *batches* at its sync
//! points: a batch ends after a pass another queue waits for (it signals the
//! lane's timeline semaphore with the pass's 1-based lane position, the
//! plan's `SyncPoint::value`) and starts before a pass that waits. The
//! command buffers do not change between frames; only the timeline values
//! (offset per frame) do, so frames resubmit them.

use crate::Barriers;
use crate::barriers::{Barrier, SyncPlan, Target};
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::memory::{Memory, Res, full_range};
use crate::owned::{Device, Owned};
use crate::pipelines::{Built, DrawCall, Launch, Pipelines, Work};
use crate::timing::Timestamps;
use ash::vk;
use std::sync::Arc;
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::{Plan, Queue};
use strandgraph_passes::raster_state::{ColorLoad, DepthLoad};

/// Which backend queue a plan queue runs on.
pub(crate) fn backend_queue(q: Queue, has_compute: bool) -> usize {
    match q {
        Queue::AsyncCompute if has_compute => 1,
        _ => 0,
    }
}

/// Where a frame's command buffers write timestamps: the same work is
/// recorded once for each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stamps {
    /// Before and after every pass (`2k`, `2k + 1` for lane position `k`).
    Passes = 0,
    /// Only before the lane's first pass (query 0) and after its last
    /// (query `2n - 1`): the frame with no query between its passes.
    Frame = 1,
    /// At each batch's start, after its waits (query `2f` for the batch's
    /// first position `f`), and after each of its levels' passes (`2f + 1
    /// + k` for level `k`): the frame with its passes overlapping as they
    /// do untimed, timed level by level ([`crate::level_timing`]).
    Levels = 2,
}

impl Stamps {
    pub const ALL: [Stamps; 3] = [Stamps::Passes, Stamps::Frame, Stamps::Levels];
}

pub(crate) struct Batch {
    /// The batch's command buffer per [`Stamps`] (indexed by it).
    pub cmds: [vk::CommandBuffer; 3],
    /// Range of lane positions (0-based, inclusive).
    pub first: usize,
    pub last: usize,
    /// `(lane, 1-based position)` this batch waits for.
    pub waits: Vec<(usize, u64)>,
    /// The batch's positions grouped between barriers ([`Lanes::group`]).
    pub levels: Vec<Vec<usize>>,
}

pub(crate) struct Lane {
    /// Backend queue index.
    pub queue: usize,
    pub passes: Vec<PassId>,
    /// Command buffers from `pool`, freed with it.
    pub batches: Vec<Batch>,
    pub semaphore: Owned<vk::Semaphore>,
    pool: Owned<vk::CommandPool>,
}

impl Lane {
    pub fn position(&self, p: PassId) -> Option<usize> {
        self.passes.iter().position(|&x| x == p)
    }
}

pub(crate) struct Lanes {
    pub lanes: Vec<Lane>,
    /// Lane index of every pass (by pass id).
    pub lane_of: Vec<usize>,
}

impl Lanes {
    /// Groups each batch's passes between barriers as `barriers` says:
    /// one pass a group, or [`levels`] of the passes' waits in `sync`.
    pub fn group(&mut self, plan: &Plan, sync: &SyncPlan, barriers: Barriers) {
        for lane in &mut self.lanes {
            for (b, batch) in lane.batches.iter_mut().enumerate() {
                let range = batch.first..=batch.last;
                batch.levels = match barriers {
                    Barriers::PerPass => range.map(|i| vec![i]).collect(),
                    Barriers::Levels => levels(&lane.passes, range, &sync.waits_on),
                };
                let names: Vec<Vec<&str>> = batch
                    .levels
                    .iter()
                    .map(|l| l.iter().map(|&i| plan.pass_name(lane.passes[i])).collect())
                    .collect();
                tracing::debug!(queue = lane.queue, batch = b, ?names, "barrier levels");
            }
        }
    }
}

/// A timeline semaphore starting at 0.
pub(crate) fn timeline(d: &Arc<Device>, what: &str) -> Result<Owned<vk::Semaphore>, AshError> {
    let mut ty = vk::SemaphoreTypeCreateInfo::default()
        .semaphore_type(vk::SemaphoreType::TIMELINE)
        .initial_value(0);
    let info = vk::SemaphoreCreateInfo::default().push_next(&mut ty);
    // SAFETY: valid device and info.
    Ok(d.own(unsafe { d.create_semaphore(&info, None) }.ctx(what)?))
}

/// A command pool of queue family `family`.
pub(crate) fn command_pool(
    d: &Arc<Device>,
    family: u32,
    flags: vk::CommandPoolCreateFlags,
) -> Result<Owned<vk::CommandPool>, AshError> {
    let info = vk::CommandPoolCreateInfo::default()
        .flags(flags)
        .queue_family_index(family);
    // SAFETY: valid device and info.
    Ok(d.own(unsafe { d.create_command_pool(&info, None) }.ctx("vkCreateCommandPool")?))
}

/// Splits the plan's passes into lanes per backend queue and batches.
pub(crate) fn make_lanes(gpu: &Gpu, plan: &Plan) -> Result<Lanes, AshError> {
    let has_compute = gpu.queues.len() > 1;
    let g = &plan.graph;
    let mut lane_of = vec![usize::MAX; g.passes.len()];
    let mut lanes: Vec<Lane> = Vec::new();
    for &p in &plan.order {
        let q = backend_queue(g.passes[p].queue, has_compute);
        let l = match lanes.iter().position(|l| l.queue == q) {
            Some(l) => l,
            None => {
                let family = gpu.queues[q].family;
                lanes.push(Lane {
                    queue: q,
                    passes: Vec::new(),
                    batches: Vec::new(),
                    pool: command_pool(&gpu.device, family, vk::CommandPoolCreateFlags::empty())?,
                    semaphore: timeline(&gpu.device, "timeline semaphore")?,
                });
                lanes.len() - 1
            }
        };
        lanes[l].passes.push(p);
        lane_of[p] = l;
    }
    let when = expected(plan, &lane_of, lanes.len());
    let points = cross_points(plan, &lanes, &lane_of, &when);
    for (l, lane) in lanes.iter_mut().enumerate() {
        let order: Vec<When> = lane.passes.iter().map(|&p| when[p]).collect();
        lane.batches = batches(l, &order, &points);
        let info = vk::CommandBufferAllocateInfo::default()
            .command_pool(lane.pool.raw())
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count((Stamps::ALL.len() * lane.batches.len()) as u32);
        // SAFETY: valid pool; the buffers are freed with it.
        let cmds = unsafe { gpu.device.allocate_command_buffers(&info) }
            .ctx("vkAllocateCommandBuffers")?;
        for (b, set) in lane
            .batches
            .iter_mut()
            .zip(cmds.chunks_exact(Stamps::ALL.len()))
        {
            b.cmds = [set[0], set[1], set[2]];
        }
    }
    Ok(Lanes { lanes, lane_of })
}

/// When a pass is expected to run: its position in the plan's order, and
/// its step in a schedule where every pass takes one step and the queues run
/// side by side, a wait starting no earlier than the step after its signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct When {
    order: usize,
    step: usize,
}

impl When {
    /// Whether a pass expected at `self` is done before one at `first` starts.
    fn before(self, first: When) -> bool {
        self.order < first.order && self.step < first.step
    }
}

/// [`When`] of every pass (indexed by pass id), `lane_of` giving its lane.
fn expected(plan: &Plan, lane_of: &[usize], lanes: usize) -> Vec<When> {
    let mut when = vec![
        When {
            order: usize::MAX,
            step: usize::MAX
        };
        lane_of.len()
    ];
    let mut next = vec![0usize; lanes];
    for (order, &p) in plan.order.iter().enumerate() {
        let l = lane_of[p];
        let waits = plan
            .sync_points
            .iter()
            .filter(|s| s.before == p && lane_of[s.after] != l);
        let step = waits.fold(next[l], |t, s| t.max(when[s.after].step.saturating_add(1)));
        when[p] = When { order, step };
        next[l] = step.saturating_add(1);
    }
    when
}

/// A cross-queue sync point of the plan in backend lanes.
#[derive(Debug, Clone, Copy)]
struct Point {
    /// Signalling lane and its 0-based position there.
    signal: (usize, usize),
    /// Waiting lane and the position of the pass that waits.
    wait: (usize, usize),
    /// When the signalling pass is expected to run.
    signal_when: When,
}

fn cross_points(plan: &Plan, lanes: &[Lane], lane_of: &[usize], when: &[When]) -> Vec<Point> {
    plan.sync_points
        .iter()
        .filter(|s| lane_of[s.after] != lane_of[s.before])
        .map(|s| {
            let (la, lb) = (lane_of[s.after], lane_of[s.before]);
            Point {
                signal: (la, lanes[la].position(s.after).unwrap_or(0)),
                wait: (lb, lanes[lb].position(s.before).unwrap_or(0)),
                signal_when: when[s.after],
            }
        })
        .collect()
}

/// Lane `l`'s passes (`order[k]`: when its `k`th is expected) cut into
/// batches: a batch ends after a pass another lane waits for, and before a
/// pass that waits, unless that wait can move up to the batch's start:
/// Vulkan waits at submission boundaries only, and each boundary costs the
/// queue time (10-20 us on the H100). A wait moves up when its signalling
/// pass is expected done before the batch's first pass ([`When::before`]):
/// it comes earlier in the plan's order, and at an earlier step (Kulikov:
/// the skin shadows' wait for the head's depth joins the batch after
/// skinning). The steps keep a long chain on the other queue that the plan
/// merely lists first (Lipp's deep opacity maps, declared before the
/// per-groom passes) from holding up the passes that do not need it.
/// Waiting earlier is always safe.
fn batches(l: usize, order: &[When], points: &[Point]) -> Vec<Batch> {
    let n = order.len();
    let waits_at = |i: usize| points.iter().filter(move |pt| pt.wait == (l, i));
    let mut out = Vec::new();
    let mut start = 0;
    for i in 0..n {
        let signals = points.iter().any(|pt| pt.signal == (l, i));
        let next_waits_late = waits_at(i + 1).any(|pt| !pt.signal_when.before(order[start]));
        if signals || next_waits_late || i + 1 == n {
            let mut waits: Vec<(usize, u64)> = Vec::new();
            for pt in (start..=i).flat_map(waits_at) {
                let (la, pa) = pt.signal;
                match waits.iter_mut().find(|w| w.0 == la) {
                    Some(w) => w.1 = w.1.max(pa as u64 + 1),
                    None => waits.push((la, pa as u64 + 1)),
                }
            }
            out.push(Batch {
                cmds: [vk::CommandBuffer::null(); 3],
                first: start,
                last: i,
                waits,
                levels: Vec::new(),
            });
            start = i + 1;
        }
    }
    out
}

/// Converts barriers to Vulkan and records them in one `vkCmdPipelineBarrier2`.
pub(crate) fn record_barriers(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    barriers: &[Barrier],
    memory: &Memory,
) {
    if barriers.is_empty() {
        return;
    }
    let mut global = Vec::new();
    let mut buffers = Vec::new();
    let mut images = Vec::new();
    for b in barriers {
        match b.target {
            Target::Global => global.push(
                vk::MemoryBarrier2::default()
                    .src_stage_mask(b.src.stages)
                    .src_access_mask(b.src.access)
                    .dst_stage_mask(b.dst.stages)
                    .dst_access_mask(b.dst.access),
            ),
            Target::Buffer(r) => {
                if let Some(Res::Buffer { buffer, .. }) = &memory.res[r] {
                    buffers.push(
                        vk::BufferMemoryBarrier2::default()
                            .src_stage_mask(b.src.stages)
                            .src_access_mask(b.src.access)
                            .dst_stage_mask(b.dst.stages)
                            .dst_access_mask(b.dst.access)
                            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                            .buffer(buffer.raw())
                            .offset(0)
                            .size(vk::WHOLE_SIZE),
                    );
                }
            }
            Target::Image { resource, old, new } => {
                if let Some(res @ Res::Image { image, extent, .. }) = &memory.res[resource] {
                    images.push(
                        vk::ImageMemoryBarrier2::default()
                            .src_stage_mask(b.src.stages)
                            .src_access_mask(b.src.access)
                            .dst_stage_mask(b.dst.stages)
                            .dst_access_mask(b.dst.access)
                            .old_layout(old)
                            .new_layout(new)
                            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                            .image(image.raw())
                            .subresource_range(full_range(res.aspect(), extent[2])),
                    );
                }
            }
        }
    }
    let info = vk::DependencyInfo::default()
        .memory_barriers(&global)
        .buffer_memory_barriers(&buffers)
        .image_memory_barriers(&images);
    // SAFETY: recording state; every handle is live.
    unsafe { d.cmd_pipeline_barrier2(cmd, &info) };
}

/// Records every batch of every lane, once per [`Stamps`].
pub(crate) fn record_all(
    gpu: &Gpu,
    plan: &Plan,
    lanes: &Lanes,
    pipelines: &Pipelines,
    memory: &Memory,
    sync: &SyncPlan,
    timestamps: &Timestamps,
) -> Result<(), AshError> {
    let d = &gpu.device;
    for lane in &lanes.lanes {
        let pool = timestamps.pool(lane.queue);
        let n = lane.passes.len();
        for (b, batch) in lane.batches.iter().enumerate() {
            for stamps in Stamps::ALL {
                let cmd = batch.cmds[stamps as usize];
                let begin = vk::CommandBufferBeginInfo::default();
                // SAFETY: a fresh command buffer from this lane's pool.
                unsafe { d.begin_command_buffer(cmd, &begin) }.ctx("vkBeginCommandBuffer")?;
                // The queries this batch writes: (reset range, per-pass stamps).
                let own = (2 * batch.first, 2 * (batch.last - batch.first + 1));
                let (reset, per_pass) = match stamps {
                    Stamps::Passes | Stamps::Levels => (own, stamps == Stamps::Passes),
                    Stamps::Frame if b == 0 => ((0, 2 * n), false),
                    Stamps::Frame => ((0, 0), false),
                };
                let bottom = vk::PipelineStageFlags2::BOTTOM_OF_PIPE;
                // Stamps::Frame's first query, or Stamps::Levels' batch start.
                let start = match stamps {
                    Stamps::Frame => Some(0),
                    Stamps::Levels => Some(2 * batch.first as u32),
                    Stamps::Passes => None,
                };
                if let Some(qp) = pool.filter(|_| reset.1 > 0) {
                    // SAFETY: outside any render pass.
                    unsafe { d.cmd_reset_query_pool(cmd, qp, reset.0 as u32, reset.1 as u32) };
                    if let Some(query) = start {
                        // ALL_COMMANDS, not TOP_OF_PIPE: in a semaphore
                        // wait's second scope TOP_OF_PIPE means no stage, so
                        // a TOP_OF_PIPE stamp first in the batch may be
                        // written before the wait for the frame's uploads
                        // ends, and the frame would include them.
                        let after_wait = vk::PipelineStageFlags2::ALL_COMMANDS;
                        // SAFETY: recording; the query was just reset.
                        unsafe { d.cmd_write_timestamp2(cmd, after_wait, qp, query) };
                    }
                }
                for (k, level) in batch.levels.iter().enumerate() {
                    let before: Vec<Barrier> = level
                        .iter()
                        .flat_map(|&i| sync.before[lane.passes[i]].iter().copied())
                        .collect();
                    record_barriers(d, cmd, &before, memory);
                    for &i in level {
                        let built = built_pass(plan, pipelines, lane.passes[i])?;
                        let qp = pool.filter(|_| per_pass);
                        record_pass(d, cmd, built, memory, sync, qp.map(|qp| (qp, 2 * i as u32)));
                    }
                    if let Some(qp) = pool.filter(|_| stamps == Stamps::Levels) {
                        let query = (2 * batch.first + 1 + k) as u32;
                        // SAFETY: recording; reset at this buffer's start.
                        unsafe { d.cmd_write_timestamp2(cmd, bottom, qp, query) };
                    }
                    let after: Vec<Barrier> = level
                        .iter()
                        .flat_map(|&i| sync.after[lane.passes[i]].iter().copied())
                        .collect();
                    record_barriers(d, cmd, &after, memory);
                }
                if let Some(qp) = pool.filter(|_| stamps == Stamps::Frame && batch.last + 1 == n) {
                    // SAFETY: recording; reset by the lane's first batch.
                    unsafe { d.cmd_write_timestamp2(cmd, bottom, qp, 2 * n as u32 - 1) };
                }
                // SAFETY: recording state.
                unsafe { d.end_command_buffer(cmd) }.ctx("vkEndCommandBuffer")?;
            }
        }
    }
    Ok(())
}

fn built_pass<'a>(plan: &Plan, pipelines: &'a Pipelines, p: PassId) -> Result<&'a Built, AshError> {
    pipelines
        .built
        .iter()
        .find(|b| b.p == p)
        .ok_or_else(|| AshError::Pass {
            pass: plan.pass_name(p).to_string(),
            message: "no pipeline was built".into(),
        })
}

/// Lane positions `range` (one batch) in dependency levels, each level in
/// lane order. The barriers a level's passes need go before the level, and
/// its passes are not ordered among themselves: none waits for another, and
/// a barrier waits for every earlier pass anyway.
///
/// A position's level is one more than the highest level of the positions
/// it waits for (`waits_on`, by pass id), 0 when it waits for none in the
/// batch; except that a pass nothing in the batch waits for goes in the
/// last level: started early it takes SMs from the chain that leads to
/// the batch's end, started last it runs beside that chain's last passes
/// (the plan's sinks are short clears). (On an H200 the difference
/// was small: Lipp's close and mid views 1.871 / 0.510 ms with sinks as
/// early as their waits allow, 1.870-1.875 / 0.501-0.510 last;
/// benches/results/barrier-levels-h200.txt, items 2, 4 and 5.)
pub(crate) fn levels(
    passes: &[PassId],
    range: std::ops::RangeInclusive<usize>,
    waits_on: &[Vec<PassId>],
) -> Vec<Vec<usize>> {
    let first = *range.start();
    let positions: Vec<usize> = range.collect();
    let waits = |i: usize, j: usize| waits_on[passes[i]].contains(&passes[j]);
    let mut level_of: Vec<usize> = Vec::with_capacity(positions.len());
    for &i in &positions {
        let level = (first..i)
            .filter(|&j| waits(i, j))
            .map(|j| level_of[j - first] + 1)
            .max()
            .unwrap_or(0);
        level_of.push(level);
    }
    let last = level_of.iter().copied().max().unwrap_or(0);
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); last + 1];
    for &i in &positions {
        let waited_for = positions.iter().any(|&k| k > i && waits(k, i));
        out[if waited_for {
            level_of[i - first]
        } else {
            last
        }]
        .push(i);
    }
    out
}

/// One pass's work between timestamps `query` and `query + 1` of the pool,
/// where given (its barriers are its level's: [`record_all`]).
fn record_pass(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    built: &Built,
    memory: &Memory,
    sync: &SyncPlan,
    stamps: Option<(vk::QueryPool, u32)>,
) {
    // SAFETY: recording; handles live for the session; the queries were
    // reset at the start of this command buffer.
    unsafe {
        if let Some((qp, q)) = stamps {
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::TOP_OF_PIPE, qp, q);
        }
        record_work(d, cmd, built, memory, sync);
        if let Some((qp, q)) = stamps {
            d.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::BOTTOM_OF_PIPE, qp, q + 1);
        }
    }
}

/// # Safety
/// `cmd` is recording and every handle is live.
unsafe fn record_work(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    built: &Built,
    memory: &Memory,
    sync: &SyncPlan,
) {
    let layout = built.layout.raw();
    // SAFETY: per the function's contract.
    unsafe {
        match &built.work {
            Work::Compute {
                pipeline,
                dispatches,
            } => {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline.raw());
                for (set, launch) in dispatches {
                    d.cmd_bind_descriptor_sets(
                        cmd,
                        vk::PipelineBindPoint::COMPUTE,
                        layout,
                        0,
                        &[*set],
                        &[],
                    );
                    match *launch {
                        Launch::Direct(n) => d.cmd_dispatch(cmd, n, 1, 1),
                        Launch::Indirect(r, offset) => {
                            if let Some(Res::Buffer { buffer, .. }) = &memory.res[r] {
                                d.cmd_dispatch_indirect(cmd, buffer.raw(), offset);
                            }
                        }
                    }
                }
            }
            Work::Raster { .. } => record_raster(d, cmd, built, memory, sync),
        }
    }
}

/// The attachment infos of a raster pass, in the layouts the pass finds
/// them in: colour ones, and the depth one.
fn attachment_infos(
    work: &Work,
    memory: &Memory,
    layout_of: &dyn Fn(usize) -> vk::ImageLayout,
) -> (
    Vec<vk::RenderingAttachmentInfo<'static>>,
    Option<vk::RenderingAttachmentInfo<'static>>,
) {
    let Work::Raster {
        color,
        depth,
        state,
        ..
    } = work
    else {
        return (Vec::new(), None);
    };
    let view = |r: usize| match &memory.res[r] {
        Some(Res::Image { view, .. }) => view.raw(),
        _ => vk::ImageView::null(),
    };
    let colors = color
        .iter()
        .map(|&r| {
            let (op, clear) = match state.color_load {
                ColorLoad::Load => (vk::AttachmentLoadOp::LOAD, [0.0; 4]),
                ColorLoad::Clear(c) => (vk::AttachmentLoadOp::CLEAR, c),
            };
            vk::RenderingAttachmentInfo::default()
                .image_view(view(r))
                .image_layout(layout_of(r))
                .load_op(op)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue { float32: clear },
                })
        })
        .collect();
    let depth = depth.map(|r| {
        let (op, clear) = match state.depth_load {
            DepthLoad::Load => (vk::AttachmentLoadOp::LOAD, 1.0),
            DepthLoad::Clear(v) => (vk::AttachmentLoadOp::CLEAR, v),
        };
        vk::RenderingAttachmentInfo::default()
            .image_view(view(r))
            .image_layout(layout_of(r))
            .load_op(op)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: clear,
                    stencil: 0,
                },
            })
    });
    (colors, depth)
}

/// # Safety
/// `cmd` is recording and every handle is live; `built` is a raster pass.
unsafe fn record_raster(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    built: &Built,
    memory: &Memory,
    sync: &SyncPlan,
) {
    let Work::Raster {
        pipelines,
        set,
        call,
        extent,
        ..
    } = &built.work
    else {
        return;
    };
    let layout_of = |r: usize| {
        sync.layout_in
            .get(&(built.p, r))
            .copied()
            .unwrap_or(vk::ImageLayout::GENERAL)
    };
    let (colors, depth) = attachment_infos(&built.work, memory, &layout_of);
    let area = vk::Rect2D {
        offset: vk::Offset2D { x: 0, y: 0 },
        extent: vk::Extent2D {
            width: extent[0],
            height: extent[1],
        },
    };
    let mut info = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(&colors);
    if let Some(di) = depth.as_ref() {
        info = info.depth_attachment(di);
    }
    // SAFETY: per the function's contract.
    unsafe {
        d.cmd_begin_rendering(cmd, &info);
        // WGSL's clip space has y up: a negative-height viewport
        // (Vulkan 1.1) flips it, as wgpu-hal does.
        d.cmd_set_viewport(
            cmd,
            0,
            &[vk::Viewport {
                x: 0.0,
                y: extent[1] as f32,
                width: extent[0] as f32,
                height: -(extent[1] as f32),
                min_depth: 0.0,
                max_depth: 1.0,
            }],
        );
        d.cmd_set_scissor(cmd, 0, &[area]);
        for pipeline in pipelines {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw());
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                built.layout.raw(),
                0,
                &[*set],
                &[],
            );
            match call {
                DrawCall::Vertices(0) => {}
                DrawCall::Vertices(n) => d.cmd_draw(cmd, *n, 1, 0, 0),
                DrawCall::Indirect(r, offset) => {
                    if let Some(Res::Buffer { buffer, .. }) = &memory.res[*r] {
                        d.cmd_draw_indirect(cmd, buffer.raw(), *offset, 1, 16);
                    }
                }
                DrawCall::MeshTasks(0, _) => {}
                DrawCall::MeshTasks(groups, mesh) => mesh.cmd_draw_mesh_tasks(cmd, *groups, 1, 1),
            }
        }
        d.cmd_end_rendering(cmd);
    }
}

#[cfg(test)]
mod tests {
    use super::{Point, When, batches, levels};

    fn at(order: usize, step: usize) -> When {
        When { order, step }
    }

    fn point(signal: (usize, usize), wait: (usize, usize), signal_when: When) -> Point {
        Point {
            signal,
            wait,
            signal_when,
        }
    }

    /// A batch as (first, last, waits).
    type Range = (usize, usize, Vec<(usize, u64)>);

    fn ranges(l: usize, order: &[When], points: &[Point]) -> Vec<Range> {
        batches(l, order, points)
            .into_iter()
            .map(|b| (b.first, b.last, b.waits))
            .collect()
    }

    #[test]
    fn a_wait_cuts_the_lane_unless_its_signal_is_expected_done_first() {
        // Lane 1 at plan positions 0, 1, 6, 7, 8, 9 and steps 0 to 5; it
        // signals after its position 1, and its position 4 waits for lane
        // 0's position 2.
        let order: Vec<When> = [0, 1, 6, 7, 8, 9]
            .iter()
            .enumerate()
            .map(|(k, &o)| at(o, k))
            .collect();
        let signal = point((1, 1), (0, 3), at(1, 1));
        // Lane 0's pass at plan position 5, step 1, comes before the batch's
        // first (6, step 2): the wait joins the batch that starts after the
        // signal.
        let early = [signal, point((0, 2), (1, 4), at(5, 1))];
        assert_eq!(
            ranges(1, &order, &early),
            vec![(0, 1, vec![]), (2, 5, vec![(0, 3)])]
        );
        // At plan position 7 it may not be done when the batch starts: the
        // lane is cut before the waiting pass.
        let late = [signal, point((0, 2), (1, 4), at(7, 1))];
        let cut = vec![(0, 1, vec![]), (2, 3, vec![]), (4, 5, vec![(0, 3)])];
        assert_eq!(ranges(1, &order, &late), cut);
        // Listed first but at the end of a longer chain (step 2, as the
        // batch's first): cut as well.
        let long = [signal, point((0, 2), (1, 4), at(5, 2))];
        assert_eq!(ranges(1, &order, &long), cut);
    }

    #[test]
    fn passes_that_wait_for_none_of_each_other_share_a_level() {
        // Pass ids 10..=15 at lane positions 0..=5. 11 waits for 10; 13
        // waits for 11 and 12; 14 for 10; 15 for nothing. 12 is waited for,
        // so it stays in level 0 beside 10; 14 and 15 are waited for by
        // nothing in the batch, so they go in the last level with 13.
        let passes: Vec<usize> = (10..=15).collect();
        let mut waits_on = vec![Vec::new(); 16];
        waits_on[11] = vec![10];
        waits_on[13] = vec![11, 12];
        waits_on[14] = vec![10];
        assert_eq!(
            levels(&passes, 0..=5, &waits_on),
            vec![vec![0, 2], vec![1], vec![3, 4, 5]]
        );
        // A batch that starts later in the lane: only its own positions,
        // and a wait for a pass before the batch (10) is no wait in it.
        assert_eq!(levels(&passes, 3..=5, &waits_on), vec![vec![3, 4, 5]]);
        assert_eq!(levels(&passes, 1..=3, &waits_on), vec![vec![1, 2], vec![3]]);
        // A chain stays a chain.
        let mut chain = vec![Vec::new(); 16];
        for (p, waits) in chain.iter_mut().enumerate().skip(11) {
            *waits = vec![p - 1];
        }
        let one_each: Vec<Vec<usize>> = (0..=5).map(|i| vec![i]).collect();
        assert_eq!(levels(&passes, 0..=5, &chain), one_each);
    }
}
