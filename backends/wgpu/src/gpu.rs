//! The wgpu device sessions run on. [`WgpuBackend::open`] creates one per
//! session with only the features its plan needs; a viewer creates one
//! [`Gpu`] with every feature a shipped pass may use ([`WgpuBackend::gpu`]),
//! presents to its window from it, and opens a session per graph on it
//! ([`WgpuBackend::open_on`]).

use super::*;
use crate::shaders::CAPABILITY_FEATURES;

/// A wgpu instance, adapter, device and queue, and the validation errors
/// the device reported (every session on it checks them).
#[derive(Clone)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The adapter's name, backend and driver.
    pub name: String,
    pub(crate) errors: Arc<Mutex<Vec<String>>>,
}

impl WgpuBackend {
    /// A device with every feature any pass may need that the adapter has
    /// (timestamps, the shader capabilities, adapter-specific formats);
    /// sessions opened on it check their own needs against it.
    pub fn gpu(&self) -> Result<Gpu, WgpuError> {
        let adapter = self.adapter()?;
        let mut wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        for (_, feature, _) in CAPABILITY_FEATURES {
            wanted |= feature;
        }
        let features = adapter.1.features() & wanted;
        Gpu::new(adapter, features)
    }

    /// The instance and the first adapter on [`WgpuBackend::backends`].
    pub(crate) fn adapter(&self) -> Result<(wgpu::Instance, wgpu::Adapter), WgpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = self.backends;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
            .map_err(|e| WgpuError::NoAdapter(e.to_string()))?;
        Ok((instance, adapter))
    }
}

impl Gpu {
    /// Creates the device with `features` and collects its uncaptured errors.
    pub(crate) fn new(
        (instance, adapter): (wgpu::Instance, wgpu::Adapter),
        features: wgpu::Features,
    ) -> Result<Gpu, WgpuError> {
        let name = adapter_name(&adapter);
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
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            name,
            errors,
        })
    }

    /// Fails with every validation error wgpu reported since the last check.
    pub fn check(&self, what: &str) -> Result<(), WgpuError> {
        let mut errs = self.errors.lock().unwrap_or_else(|e| e.into_inner());
        if errs.is_empty() {
            Ok(())
        } else {
            let all = std::mem::take(&mut *errs).join("\n");
            Err(WgpuError::Validation(format!("{what}: {all}")))
        }
    }
}

/// The adapter's name, backend and driver, as errors and notes give it.
pub(crate) fn adapter_name(adapter: &wgpu::Adapter) -> String {
    let info = adapter.get_info();
    format!("{} ({:?}, {})", info.name, info.backend, info.driver)
}

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

/// The features the plan's passes need, each missing one named with the
/// pass that needs it. `available` is what the adapter (for a new device)
/// or the shared device has.
pub(crate) fn required_features(
    adapter: &wgpu::Adapter,
    adapter_name: &str,
    available: wgpu::Features,
    plan: &Plan,
    prepared: &[Prepared<'_>],
) -> Result<wgpu::Features, WgpuError> {
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
