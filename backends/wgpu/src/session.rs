//! A session: the device, resources, pipelines and bind groups of one plan,
//! created once; each [`Session::run`] uploads a frame's inputs and records
//! the passes. History resources keep their contents between runs.

use super::*;
use crate::memory::{create_memory, upload};
use crate::pipelines::{Built, build};
use crate::prepare::prepare;
use crate::record::{Timestamps, record_and_run};

/// A plan on a wgpu device, ready to run frames.
pub struct Session {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) plan: Plan,
    pub(crate) instance: Instance,
    pub(crate) prepared: Vec<Prepared<'static>>,
    pub(crate) built: Vec<Built>,
    pub(crate) memory: Vec<Option<Memory>>,
    pub(crate) timestamps: Timestamps,
    errors: Arc<Mutex<Vec<String>>>,
    /// The last frame's per-pass GPU times, in plan order.
    pub timings: Vec<PassTiming>,
    /// What the adapter is, and how the plan degraded on wgpu.
    pub notes: Vec<String>,
    pub adapter: String,
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
        let mut shaders = Shaders::open(self.shader_dir.as_deref()).map_err(WgpuError::Shader)?;
        let prepared = prepare(defs, plan, instance, &mut shaders)?;

        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = self.backends;
        let wgpu_instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(wgpu_instance.request_adapter(&Default::default()))
            .map_err(|e| WgpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let adapter_name = format!("{} ({:?}, {})", info.name, info.backend, info.driver);
        let features = required_features(&adapter, &adapter_name, plan, &prepared)?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("strandgraph"),
            required_features: features,
            required_limits: adapter.limits(),
            experimental_features: experimental(features),
            ..Default::default()
        }))
        .map_err(|e| WgpuError::Device(e.to_string()))?;
        let errors: Arc<Mutex<Vec<String>>> = Arc::default();
        {
            let errors = errors.clone();
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                errors
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(e.to_string());
            }));
        }

        let mut notes = vec![
            format!("adapter: {adapter_name}; requested features: {features:?}"),
            "wgpu has one queue: AsyncCompute passes run on it in plan order; the plan's sync points hold trivially".into(),
        ];
        let memory = create_memory(&device, plan, instance, &prepared)?;
        let transient: u64 = instance.memory.placements.iter().map(|p| p.size).sum();
        notes.push(format!(
            "wgpu cannot alias memory: {} transients take {:.2} MiB in separate allocations (the plan's aliased heaps: {:.2} MiB)",
            instance.memory.placements.len(),
            transient as f64 / (1 << 20) as f64,
            instance.memory.bytes_with_aliasing as f64 / (1 << 20) as f64,
        ));
        let built = prepared
            .iter()
            .map(|prep| build(&device, plan, instance, prep, &memory))
            .collect::<Result<Vec<_>, _>>()?;
        let timestamps = Timestamps::new(&device, prepared.len());
        let session = Session {
            device,
            queue,
            plan: plan.clone(),
            instance: instance.clone(),
            prepared,
            built,
            memory,
            timestamps,
            errors,
            timings: Vec::new(),
            notes,
            adapter: adapter_name,
        };
        session.check("creating resources and pipelines")?;
        Ok(session)
    }
}

impl Session {
    /// Uploads `inputs` and runs one frame; returns its per-pass GPU times.
    pub fn run(&mut self, inputs: &Upload) -> Result<&[PassTiming], WgpuError> {
        upload(
            &self.device,
            &self.queue,
            &self.plan,
            &self.instance,
            &self.memory,
            inputs,
        )?;
        let timings = record_and_run(self)?;
        self.check("running the frame")?;
        self.timings = timings;
        Ok(&self.timings)
    }

    /// Fails with every validation error wgpu reported since the last check.
    fn check(&self, what: &str) -> Result<(), WgpuError> {
        let mut errs = self.errors.lock().unwrap_or_else(|e| e.into_inner());
        if errs.is_empty() {
            Ok(())
        } else {
            let all = std::mem::take(&mut *errs).join("\n");
            Err(WgpuError::Validation(format!("{what}: {all}")))
        }
    }
}

/// Only the features the plan's passes need, each missing one named with
/// the pass that needs it.
/// wgpu 30 exposes mesh shaders only to a device created with its
/// experimental-features token; ask for it only when a pass needs them.
fn experimental(features: wgpu::Features) -> wgpu::ExperimentalFeatures {
    if features.contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER) {
        // SAFETY: the token acknowledges that experimental APIs may have
        // bugs; only the mesh-shader pass (`hw_strands.mesh`) uses one, and
        // it is checked against the CPU simulator (tests/diff_hw_mesh.rs).
        #[allow(unsafe_code)]
        unsafe {
            wgpu::ExperimentalFeatures::enabled()
        }
    } else {
        wgpu::ExperimentalFeatures::disabled()
    }
}

fn required_features(
    adapter: &wgpu::Adapter,
    adapter_name: &str,
    plan: &Plan,
    prepared: &[Prepared<'_>],
) -> Result<wgpu::Features, WgpuError> {
    let available = adapter.features();
    let mut features = wgpu::Features::empty();
    let mut need = |feature: wgpu::Features, name: &'static str, pass: &str, why: String| {
        if available.contains(feature) {
            features |= feature;
            Ok(())
        } else {
            Err(WgpuError::MissingFeature {
                adapter: adapter_name.to_string(),
                feature: name,
                pass: pass.to_string(),
                why,
            })
        }
    };
    for prep in prepared {
        let name = plan.pass_name(prep.p);
        need(
            wgpu::Features::TIMESTAMP_QUERY,
            "TIMESTAMP_QUERY",
            name,
            "per-pass GPU times".into(),
        )?;
        for (cap, feature, feature_name) in CAPABILITY_FEATURES {
            if prep.composed.needs.contains(cap) {
                need(
                    feature,
                    feature_name,
                    name,
                    format!("{} uses {cap:?}", prep.def.shader().file),
                )?;
            }
        }
        for &(_, r) in &prep.bindings {
            let ResourceDecl::Image {
                format, samples, ..
            } = plan.graph.resources[r].decl
            else {
                continue;
            };
            let format = crate::texture_format(format);
            let guaranteed = format.guaranteed_format_features(wgpu::Features::empty());
            if samples > 1 && !guaranteed.flags.sample_count_supported(samples) {
                let why = format!(
                    "{samples} samples of {format:?} (`{}`)",
                    plan.graph.resources[r].name
                );
                need(
                    wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
                    "TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES",
                    name,
                    why.clone(),
                )?;
                if !adapter
                    .get_texture_format_features(format)
                    .flags
                    .sample_count_supported(samples)
                {
                    return Err(WgpuError::MissingFeature {
                        adapter: adapter_name.to_string(),
                        feature: "a multisampled format",
                        pass: name.to_string(),
                        why,
                    });
                }
            }
        }
        if let Some(format) = read_only_storage_texture_needs(&prep.composed.module) {
            need(
                wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
                "TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES",
                name,
                format!("read_write storage texture of {format:?}"),
            )?;
        }
    }
    Ok(features)
}
