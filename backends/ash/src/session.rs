//! A session: device, memory, pipelines and command buffers of one plan,
//! created once; [`Session::run`] uploads a frame's inputs and submits the
//! recorded batches; history resources keep their contents between frames.

use crate::AshBackend;
use crate::barriers::{Placement, SyncPlan, plan_sync};
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::host::HostBuffer;
use crate::memory::{Memory, Res};
use crate::owned::Owned;
use crate::pipelines::{Pipelines, build};
use crate::prepare::{Prepared, prepare};
use crate::record::{Lanes, command_pool, make_lanes, record_all, timeline};
use crate::timing::{PassTiming, Timestamps};
use ash::vk;
use std::collections::BTreeMap;
use std::time::Duration;
use strandgraph_graph::schema::LifetimeClass;
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::wgsl::Shaders;
use strandgraph_passes::{Definitions, Dispatch};

/// One frame's results.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Per-pass GPU times, in plan order.
    pub timings: Vec<PassTiming>,
}

/// A plan on a Vulkan device, ready to run frames. Every Vulkan object is
/// owned by a field; `Drop` waits for the device to go idle, then the fields
/// destroy themselves (the device last: each object holds it).
pub struct Session {
    pub(crate) plan: Plan,
    pub(crate) instance: Instance,
    pub(crate) memory: Memory,
    pub(crate) pipelines: Pipelines,
    pub(crate) lanes: Lanes,
    pub(crate) sync: SyncPlan,
    pub(crate) timestamps: Timestamps,
    pub(crate) staging: HostBuffer,
    /// Byte offset in `staging` of every imported resource.
    pub(crate) staging_at: BTreeMap<usize, u64>,
    pub(crate) upload_semaphore: Owned<vk::Semaphore>,
    /// The upload prologue's and readbacks' command buffers.
    pub(crate) util_pool: Owned<vk::CommandPool>,
    pub(crate) fence: Owned<vk::Fence>,
    /// Frames run so far.
    pub(crate) frames: u64,
    /// Timeline values per frame: more than the longest lane.
    pub(crate) stride: u64,
    /// Current layout of every image, between frames.
    pub(crate) layouts: BTreeMap<usize, vk::ImageLayout>,
    /// `(index in plan order, args resource, word)` of indirect dispatches.
    pub(crate) indirect: Vec<(usize, usize, usize)>,
    pub(crate) timeout: Duration,
    pub(crate) submit: crate::Submit,
    /// The last frame's per-pass GPU times, in plan order.
    pub timings: Vec<PassTiming>,
    /// What the device is and how the plan ran on it.
    pub notes: Vec<String>,
    /// The device's name.
    pub device: String,
    /// The device's subgroup size (the CPU reference should emulate it).
    pub subgroup_size: u32,
    /// Transient bytes allocated, and what they take without aliasing.
    pub transient_bytes: u64,
    pub unaliased_bytes: u64,
    pub(crate) gpu: Gpu,
}

/// A raster pass on the compute-only queue is refused: it has no rasterizer.
fn refuse_raster_on_compute(
    gpu: &Gpu,
    plan: &Plan,
    prepared: &[Prepared<'_>],
) -> Result<(), AshError> {
    let g = &plan.graph;
    let has_compute = gpu.queues.len() > 1;
    for prep in prepared {
        let q = crate::record::backend_queue(g.passes[prep.p].queue, has_compute);
        if prep.is_raster() && gpu.queues[q].compute_only {
            return Err(AshError::Pass {
                pass: g.passes[prep.p].name.clone(),
                message:
                    "a raster pass cannot run on the compute-only queue (give it queue: Graphics)"
                        .into(),
            });
        }
    }
    Ok(())
}

/// Which physical resources live passes access.
fn used_resources(plan: &Plan) -> Vec<bool> {
    let g = &plan.graph;
    let mut used = vec![false; g.resources.len()];
    for &p in &plan.order {
        for a in &g.passes[p].accesses {
            used[g.physical(a.resource)] = true;
        }
    }
    used
}

/// Where each imported or history resource sits in the upload staging
/// buffer, and the buffer's size.
fn staging_layout(
    plan: &Plan,
    instance: &Instance,
    memory: &Memory,
) -> (BTreeMap<usize, u64>, u64) {
    let mut staging_at = BTreeMap::new();
    let mut cursor = 0u64;
    for (r, res) in plan.graph.resources.iter().enumerate() {
        if res.version_of.is_none()
            && res.decl.lifetime() != LifetimeClass::Transient
            && memory.res[r].is_some()
        {
            staging_at.insert(r, cursor);
            cursor += instance.sizes[r].bytes.next_multiple_of(16);
        }
    }
    (staging_at, cursor)
}

/// `(index in plan order, args resource, word)` of every indirect compute dispatch.
fn indirect_dispatches(plan: &Plan, prepared: &[Prepared<'_>]) -> Vec<(usize, usize, usize)> {
    plan.order
        .iter()
        .enumerate()
        .filter_map(|(i, &p)| {
            let prep = prepared.iter().find(|x| x.p == p)?;
            let Dispatch::Indirect { binding, word } = prep.def.dispatch() else {
                return None;
            };
            let r = prep.bindings.iter().find(|(n, _, _)| n == binding)?.1;
            (prep.raster.is_none()).then_some((i, r, word))
        })
        .collect()
}

impl Session {
    pub(crate) fn open(
        backend: &AshBackend,
        defs: &dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Session, AshError> {
        let mut shaders = Shaders::open(backend.shader_dir.as_deref()).map_err(AshError::Shader)?;
        let (prepared, needs) = prepare(defs, plan, instance, &mut shaders)?;
        let gpu = Gpu::new(backend, &needs)?;
        refuse_raster_on_compute(&gpu, plan, &prepared)?;
        let families: Vec<u32> = gpu.queues.iter().map(|q| q.family).collect();
        let used = used_resources(plan);
        let memory = Memory::create(&gpu, plan, instance, &used, &families, backend.alias)?;
        let mut lanes = make_lanes(&gpu, plan)?;
        let queue_of: Vec<usize> = lanes
            .lane_of
            .iter()
            .map(|&l| lanes.lanes.get(l).map_or(0, |l| l.queue))
            .collect();
        let compute_only: Vec<bool> = gpu.queues.iter().map(|q| q.compute_only).collect();
        let is_depth = |r: usize| matches!(memory.res[r], Some(Res::Image { depth: true, .. }));
        let sync = plan_sync(
            plan,
            &Placement {
                queue_of: &queue_of,
                compute_only: &compute_only,
                is_depth: &is_depth,
                aliases: &memory.aliases,
            },
        );
        lanes.group(plan, &sync, backend.barriers);
        let t0 = std::time::Instant::now();
        let pipelines = build(&gpu, plan, instance, &prepared, &memory, &sync)?;
        tracing::debug!(
            ms = t0.elapsed().as_secs_f64() * 1e3,
            passes = prepared.len(),
            "pipelines built"
        );
        let per_queue: Vec<usize> = (0..gpu.queues.len())
            .map(|q| {
                let on_q = lanes.lanes.iter().filter(|l| l.queue == q);
                on_q.map(|l| l.passes.len()).sum()
            })
            .collect();
        let timestamps = Timestamps::new(&gpu, &per_queue)?;
        let (staging_at, staging_bytes) = staging_layout(plan, instance, &memory);
        let src = vk::BufferUsageFlags::TRANSFER_SRC;
        let staging = HostBuffer::new(&gpu, staging_bytes, src, "upload staging")?;
        let d = &gpu.device;
        let upload_semaphore = timeline(d, "upload semaphore")?;
        let reset = vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER;
        let util_pool = command_pool(d, gpu.queues[0].family, reset)?;
        // SAFETY: valid device.
        let fence = d.own(
            unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }
                .ctx("vkCreateFence")?,
        );
        record_all(&gpu, plan, &lanes, &pipelines, &memory, &sync, &timestamps)?;

        let cx = NoteContext {
            backend,
            plan,
            instance,
            gpu: &gpu,
            memory: &memory,
            sync: &sync,
            queue_of: &queue_of,
        };
        let notes = cx.notes();
        let stride = lanes
            .lanes
            .iter()
            .map(|l| l.passes.len() as u64)
            .max()
            .unwrap_or(0)
            + 1;
        let layouts = memory
            .res
            .iter()
            .enumerate()
            .filter(|(_, r)| matches!(r, Some(Res::Image { .. })))
            .map(|(r, _)| (r, vk::ImageLayout::UNDEFINED))
            .collect();
        let session = Session {
            plan: plan.clone(),
            instance: instance.clone(),
            transient_bytes: memory.transient_bytes,
            unaliased_bytes: memory.unaliased_bytes,
            memory,
            pipelines,
            lanes,
            sync,
            timestamps,
            staging,
            staging_at,
            upload_semaphore,
            util_pool,
            fence,
            frames: 0,
            stride,
            layouts,
            indirect: indirect_dispatches(plan, &prepared),
            timeout: wait_limit(backend.timeout, gpu.props.device_type),
            submit: backend.submit,
            timings: Vec::new(),
            notes,
            device: gpu.name.clone(),
            subgroup_size: gpu.subgroup_size,
            gpu,
        };
        session
            .gpu
            .check("creating the device, memory and pipelines")?;
        Ok(session)
    }

    /// The plan this session runs.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }
}

/// What the frame notes describe.
struct NoteContext<'a> {
    backend: &'a AshBackend,
    plan: &'a Plan,
    instance: &'a Instance,
    gpu: &'a Gpu,
    memory: &'a Memory,
    sync: &'a SyncPlan,
    queue_of: &'a [usize],
}

impl NoteContext<'_> {
    /// The device, the queues, the barriers, the memory, untimed queues.
    fn notes(&self) -> Vec<String> {
        let gpu = self.gpu;
        let mut notes = vec![self.device_note(), self.queue_note()];
        notes.push(format!(
            "barriers: {} plan dependencies as vkCmdPipelineBarrier2 barriers, {} carried by semaphores; {} aliasing hand-overs",
            self.sync.barrier_deps,
            self.sync.semaphore_deps,
            self.memory.aliases.len()
        ));
        notes.push(self.memory_note());
        notes.extend(self.memory.notes.iter().cloned());
        for info in &gpu.queues {
            if info.timestamp_bits == 0 {
                notes.push(format!(
                    "queue family {} has no timestamps: its passes are not timed",
                    info.family
                ));
            }
        }
        notes
    }

    fn device_note(&self) -> String {
        let gpu = self.gpu;
        format!(
            "device: {} (Vulkan {}.{}.{}, subgroup size {}); features: {}; validation: {}",
            gpu.name,
            vk::api_version_major(gpu.props.api_version),
            vk::api_version_minor(gpu.props.api_version),
            vk::api_version_patch(gpu.props.api_version),
            gpu.subgroup_size,
            gpu.enabled.join(", "),
            if gpu.validating() {
                "Khronos layer with synchronization validation"
            } else {
                "off"
            }
        )
    }

    fn queue_note(&self) -> String {
        let (gpu, plan) = (self.gpu, self.plan);
        if gpu.queues.len() > 1 {
            let cross = plan
                .sync_points
                .iter()
                .filter(|s| self.queue_of[s.after] != self.queue_of[s.before])
                .count();
            return format!(
                "two queues: AsyncCompute passes on compute-only family {}, Graphics on family {}; \
                 {cross} sync points as timeline-semaphore waits; resources shared CONCURRENT between the families",
                gpu.queues[1].family, gpu.queues[0].family
            );
        }
        let async_passes = plan
            .order
            .iter()
            .filter(|&&p| plan.graph.passes[p].queue == strandgraph_graph::Queue::AsyncCompute)
            .count();
        format!(
            "one queue (no compute-only family{}): {async_passes} AsyncCompute passes are serialised on the \
             graphics queue in plan order; the plan's {} sync points become pipeline barriers",
            if self.backend.async_compute {
                ""
            } else {
                ": async compute off"
            },
            plan.sync_points.len()
        )
    }

    fn memory_note(&self) -> String {
        let (memory, instance) = (self.memory, self.instance);
        let mib = |b: u64| b as f64 / (1 << 20) as f64;
        format!(
            "memory: transients {:.2} MiB allocated {} ({:.2} MiB without aliasing; the plan's estimate {:.2} MiB aliased, \
             {:.2} MiB not); imported and history {:.2} MiB",
            mib(memory.transient_bytes),
            if self.backend.alias {
                "aliased at the plan's offsets"
            } else {
                "without aliasing"
            },
            mib(memory.unaliased_bytes),
            mib(instance.memory.bytes_with_aliasing),
            mib(instance.memory.bytes_without_aliasing),
            mib(memory.owned_bytes),
        )
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // The fields destroy their objects after this; the GPU may still be
        // running the last frame or readback until the wait returns.
        // SAFETY: a live device.
        let _ = unsafe { self.gpu.device.device_wait_idle() };
    }
}

/// How long a wait may take on this device: `timeout`, ten times over on a
/// CPU implementation (lavapipe runs our kernels 500 to 700 times slower
/// than an H100, and the reference's resolve at test sizes nears a minute
/// there on a busy two-core machine), so a slow device is not taken for a
/// hung one.
fn wait_limit(timeout: Duration, device_type: vk::PhysicalDeviceType) -> Duration {
    if device_type == vk::PhysicalDeviceType::CPU {
        timeout.saturating_mul(10)
    } else {
        timeout
    }
}
