//! A session: device, memory, pipelines and command buffers of one plan,
//! created once; [`Session::run`] uploads a frame's inputs and submits the
//! recorded batches; history resources keep their contents between frames.

use crate::AshBackend;
use crate::barriers::{Placement, SyncPlan, plan_sync};
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::memory::{HostBuffer, Memory, Res};
use crate::pipelines::{Pipelines, build};
use crate::prepare::prepare;
use crate::record::{Lanes, make_lanes, record_all, timeline};
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

/// A plan on a Vulkan device, ready to run frames.
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
    pub(crate) upload_semaphore: vk::Semaphore,
    pub(crate) util_pool: vk::CommandPool,
    pub(crate) fence: vk::Fence,
    /// Frames run so far.
    pub(crate) frames: u64,
    /// Timeline values per frame: more than the longest lane.
    pub(crate) stride: u64,
    /// Current layout of every image, between frames.
    pub(crate) layouts: BTreeMap<usize, vk::ImageLayout>,
    /// `(index in plan order, args resource, word)` of indirect dispatches.
    pub(crate) indirect: Vec<(usize, usize, usize)>,
    pub(crate) timeout: Duration,
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
    // Last: dropped after `Drop for Session` has destroyed everything above.
    pub(crate) gpu: Gpu,
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
        let g = &plan.graph;
        let has_compute = gpu.queues.len() > 1;
        for prep in &prepared {
            let q = crate::record::backend_queue(g.passes[prep.p].queue, has_compute);
            if prep.is_raster() && gpu.queues[q].compute_only {
                return Err(AshError::Pass {
                    pass: g.passes[prep.p].name.clone(),
                    message: "a raster pass cannot run on the compute-only queue (give it queue: Graphics)".into(),
                });
            }
        }
        let families: Vec<u32> = gpu.queues.iter().map(|q| q.family).collect();
        let mut used = vec![false; g.resources.len()];
        for &p in &plan.order {
            for a in &g.passes[p].accesses {
                used[g.physical(a.resource)] = true;
            }
        }
        let mut memory = Memory::create(&gpu, plan, instance, &used, &families, backend.alias)?;
        let mut lanes = match make_lanes(&gpu, plan) {
            Ok(l) => l,
            Err(e) => {
                memory.destroy(&gpu.device);
                return Err(e);
            }
        };
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
        let cleanup = |memory: &mut Memory, lanes: &mut Lanes, gpu: &Gpu| {
            lanes.destroy(&gpu.device);
            memory.destroy(&gpu.device);
        };
        let mut pipelines = match build(&gpu, plan, instance, &prepared, &memory, &sync) {
            Ok(p) => p,
            Err(e) => {
                cleanup(&mut memory, &mut lanes, &gpu);
                return Err(e);
            }
        };
        let per_queue: Vec<usize> = (0..gpu.queues.len())
            .map(|q| {
                lanes
                    .lanes
                    .iter()
                    .filter(|l| l.queue == q)
                    .map(|l| l.passes.len())
                    .sum()
            })
            .collect();
        let mut timestamps = match Timestamps::new(&gpu, &per_queue) {
            Ok(t) => t,
            Err(e) => {
                pipelines.destroy(&gpu.device);
                cleanup(&mut memory, &mut lanes, &gpu);
                return Err(e);
            }
        };
        // Staging for imported and history resources.
        let mut staging_at = BTreeMap::new();
        let mut cursor = 0u64;
        for (r, res) in g.resources.iter().enumerate() {
            if res.version_of.is_none()
                && res.decl.lifetime() != LifetimeClass::Transient
                && memory.res[r].is_some()
            {
                staging_at.insert(r, cursor);
                cursor += instance.sizes[r].bytes.next_multiple_of(16);
            }
        }
        let made = (|| -> Result<_, AshError> {
            let staging = HostBuffer::new(
                &gpu,
                cursor,
                vk::BufferUsageFlags::TRANSFER_SRC,
                "upload staging",
            )?;
            let upload_semaphore = timeline(&gpu.device, "upload semaphore")?;
            let info = vk::CommandPoolCreateInfo::default()
                .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER)
                .queue_family_index(gpu.queues[0].family);
            // SAFETY: valid device and info.
            let util_pool = unsafe { gpu.device.create_command_pool(&info, None) }
                .ctx("vkCreateCommandPool")?;
            // SAFETY: valid device.
            let fence = unsafe {
                gpu.device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
            }
            .ctx("vkCreateFence")?;
            record_all(&gpu, plan, &lanes, &pipelines, &memory, &sync, &timestamps)?;
            Ok((staging, upload_semaphore, util_pool, fence))
        })();
        let (staging, upload_semaphore, util_pool, fence) = match made {
            Ok(x) => x,
            Err(e) => {
                // Objects made inside the closure before the error leak only
                // until the device is destroyed with `gpu` below.
                timestamps.destroy(&gpu.device);
                pipelines.destroy(&gpu.device);
                cleanup(&mut memory, &mut lanes, &gpu);
                return Err(e);
            }
        };

        let mut notes = vec![format!(
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
        )];
        let cross = plan
            .sync_points
            .iter()
            .filter(|s| queue_of[s.after] != queue_of[s.before])
            .count();
        if has_compute {
            notes.push(format!(
                "two queues: AsyncCompute passes on compute-only family {}, Graphics on family {}; \
                 {cross} sync points as timeline-semaphore waits; resources shared CONCURRENT between the families",
                gpu.queues[1].family, gpu.queues[0].family
            ));
        } else {
            let async_passes = plan
                .order
                .iter()
                .filter(|&&p| g.passes[p].queue == strandgraph_graph::Queue::AsyncCompute)
                .count();
            notes.push(format!(
                "one queue (no compute-only family{}): {async_passes} AsyncCompute passes are serialised on the \
                 graphics queue in plan order; the plan's {} sync points become pipeline barriers",
                if backend.async_compute { "" } else { ": async compute off" },
                plan.sync_points.len()
            ));
        }
        notes.push(format!(
            "barriers: {} plan dependencies as vkCmdPipelineBarrier2 barriers, {} carried by semaphores; {} aliasing hand-overs",
            sync.barrier_deps,
            sync.semaphore_deps,
            memory.aliases.len()
        ));
        let mib = |b: u64| b as f64 / (1 << 20) as f64;
        notes.push(format!(
            "memory: transients {:.2} MiB allocated {} ({:.2} MiB without aliasing; the plan's estimate {:.2} MiB aliased, \
             {:.2} MiB not); imported and history {:.2} MiB",
            mib(memory.transient_bytes),
            if backend.alias { "aliased at the plan's offsets" } else { "without aliasing" },
            mib(memory.unaliased_bytes),
            mib(instance.memory.bytes_with_aliasing),
            mib(instance.memory.bytes_without_aliasing),
            mib(memory.owned_bytes),
        ));
        notes.extend(memory.notes.iter().cloned());
        for (q, info) in gpu.queues.iter().enumerate() {
            if info.timestamp_bits == 0 {
                notes.push(format!(
                    "queue family {} has no timestamps: its passes are not timed",
                    gpu.queues[q].family
                ));
            }
        }
        let indirect = plan
            .order
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
            .collect();
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
            indirect,
            timeout: backend.timeout,
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

impl Drop for Session {
    fn drop(&mut self) {
        let d = &self.gpu.device;
        // SAFETY: waits for all work, then destroys children before the device.
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.util_pool, None);
            d.destroy_semaphore(self.upload_semaphore, None);
        }
        self.staging.destroy(d);
        self.timestamps.destroy(d);
        self.lanes.destroy(d);
        self.pipelines.destroy(d);
        self.memory.destroy(d);
    }
}
