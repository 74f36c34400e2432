//! A session: the device, resources, pipelines and bind groups of one plan,
//! created once; each [`Session::run`] uploads a frame's inputs and records
//! the passes. History resources keep their contents between runs.

use super::*;
use crate::gpu::{Gpu, adapter_name, required_features};
use crate::memory::{create_memory, upload};
use crate::pipelines::{Built, build};
use crate::prepare::prepare;
use crate::record::{Timestamps, record_and_run};

/// A plan on a wgpu device, ready to run frames.
pub struct Session {
    pub(crate) plan: Plan,
    pub(crate) instance: Instance,
    pub(crate) prepared: Vec<Prepared<'static>>,
    pub(crate) built: Vec<Built>,
    pub(crate) memory: Vec<Option<Memory>>,
    pub(crate) timestamps: Timestamps,
    /// The device, shared with other sessions and a window where there is one.
    pub(crate) gpu: Gpu,
    /// The last frame's per-pass GPU times, in plan order.
    pub timings: Vec<PassTiming>,
    /// What the adapter is, and how the plan degraded on wgpu.
    pub notes: Vec<String>,
}

/// A session after one frame ([`WgpuBackend::execute`]).
pub type Frame = Session;

impl WgpuBackend {
    /// Runs one frame with the built-in pass definitions.
    pub fn execute(
        &self,
        plan: &Plan,
        instance: &Instance,
        inputs: &Upload,
    ) -> Result<Frame, WgpuError> {
        let mut session = self.open(&Registry, plan, instance)?;
        session.run(inputs)?;
        Ok(session)
    }

    /// Opens a session for `plan` with the definitions in `defs`: finds an
    /// adapter with the features the passes need, creates every resource,
    /// pipeline and bind group.
    pub fn open(
        &self,
        defs: &'static dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Session, WgpuError> {
        let prepared = self.prepare(defs, plan, instance)?;
        let (wgpu_instance, adapter) = self.adapter()?;
        let name = adapter_name(&adapter);
        let features = required_features(&adapter, &name, adapter.features(), plan, &prepared)?;
        let gpu = Gpu::new((wgpu_instance, adapter), features)?;
        Session::new(&gpu, plan, instance, prepared, features)
    }

    /// Opens a session for `plan` on a device shared with others (a
    /// viewer's window, other sessions): as [`WgpuBackend::open`], but the
    /// passes' features must be among the device's.
    pub fn open_on(
        &self,
        gpu: &Gpu,
        defs: &'static dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Session, WgpuError> {
        let prepared = self.prepare(defs, plan, instance)?;
        let features = required_features(
            &gpu.adapter,
            &gpu.name,
            gpu.device.features(),
            plan,
            &prepared,
        )?;
        Session::new(gpu, plan, instance, prepared, features)
    }

    /// Every live pass with its composed shader and parameters.
    fn prepare(
        &self,
        defs: &'static dyn Definitions,
        plan: &Plan,
        instance: &Instance,
    ) -> Result<Vec<Prepared<'static>>, WgpuError> {
        let mut shaders = Shaders::open(self.shader_dir.as_deref()).map_err(WgpuError::Shader)?;
        prepare(defs, plan, instance, &mut shaders, self.loop_counters)
    }
}

impl Session {
    fn new(
        gpu: &Gpu,
        plan: &Plan,
        instance: &Instance,
        prepared: Vec<Prepared<'static>>,
        features: wgpu::Features,
    ) -> Result<Session, WgpuError> {
        let device = &gpu.device;
        let mut notes = vec![
            format!("adapter: {}; requested features: {features:?}", gpu.name),
            "wgpu has one queue: AsyncCompute passes run on it in plan order; the plan's sync points hold trivially".into(),
        ];
        let memory = create_memory(device, plan, instance, &prepared)?;
        let transient: u64 = instance.memory.placements.iter().map(|p| p.size).sum();
        notes.push(format!(
            "wgpu cannot alias memory: {} transients take {:.2} MiB in separate allocations (the plan's aliased heaps: {:.2} MiB)",
            instance.memory.placements.len(),
            transient as f64 / (1 << 20) as f64,
            instance.memory.bytes_with_aliasing as f64 / (1 << 20) as f64,
        ));
        let built = prepared
            .iter()
            .map(|prep| build(device, plan, instance, prep, &memory))
            .collect::<Result<Vec<_>, _>>()?;
        let timestamps = Timestamps::new(device, prepared.len());
        let session = Session {
            plan: plan.clone(),
            instance: instance.clone(),
            prepared,
            built,
            memory,
            timestamps,
            gpu: gpu.clone(),
            timings: Vec::new(),
            notes,
        };
        session.gpu.check("creating resources and pipelines")?;
        Ok(session)
    }

    /// The texture of image resource `name`, for a caller that shows or
    /// copies it on the same device; `None` for buffers and resources
    /// without memory.
    pub fn texture(&self, name: &str) -> Option<&wgpu::Texture> {
        let r = self.plan.graph.physical(self.plan.graph.resource_id(name)?);
        match self.memory[r].as_ref()? {
            Memory::Texture { texture, .. } => Some(texture),
            Memory::Buffer(..) => None,
        }
    }

    /// Uploads `inputs` and runs one frame; returns its per-pass GPU times.
    pub fn run(&mut self, inputs: &Upload) -> Result<&[PassTiming], WgpuError> {
        upload(
            &self.gpu.device,
            &self.gpu.queue,
            &self.plan,
            &self.instance,
            &self.memory,
            inputs,
        )?;
        let timings = record_and_run(self)?;
        self.gpu.check("running the frame")?;
        self.timings = timings;
        Ok(&self.timings)
    }
}
