//! Instance, validation messenger, physical device, queue families and the
//! logical device with exactly the features the plan's passes need.

use crate::error::{AshError, VkContext};
use crate::features::{Supported, Wanted};
use crate::owned::{Device, Instance, Messenger};
use crate::{AshBackend, Validation};
use ash::{ext, vk};
use naga::valid::Capabilities;
use std::ffi::{CStr, c_void};
use std::sync::{Arc, Mutex};

pub(crate) const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Validation messages, shared with the debug-utils callback.
pub(crate) type Messages = Arc<Mutex<Vec<String>>>;

/// One queue the backend submits to.
#[derive(Debug, Clone, Copy)]
pub(crate) struct QueueInfo {
    pub family: u32,
    pub queue: vk::Queue,
    /// `timestampValidBits` of the family; 0: no timestamps there.
    pub timestamp_bits: u32,
    /// A family with COMPUTE and without GRAPHICS.
    pub compute_only: bool,
}

/// What the passes need of the device, each with the first pass that needs it.
#[derive(Debug, Default)]
pub(crate) struct Needs {
    pub caps: Vec<(Capabilities, String, String)>,
    /// A raster pass (dynamic rendering).
    pub raster: Option<String>,
    /// A raster pass that writes storage (its fragment shader's atomics).
    pub fragment_stores: Option<String>,
}

pub(crate) struct Gpu {
    /// The logical device; every object the session creates holds it.
    pub device: Arc<Device>,
    pub instance: Arc<Instance>,
    /// The validation layer's messages, when validating (the messenger
    /// writing them is owned by the device).
    messages: Option<Messages>,
    pub physical: vk::PhysicalDevice,
    pub props: vk::PhysicalDeviceProperties,
    pub memory_props: vk::PhysicalDeviceMemoryProperties,
    /// `[graphics]` or `[graphics, compute-only]`.
    pub queues: Vec<QueueInfo>,
    pub subgroup_size: u32,
    pub name: String,
    /// The features enabled, for the frame notes.
    pub enabled: Vec<String>,
    /// SPIR-V capabilities the enabled features allow.
    pub spirv_caps: Vec<naga::back::spv::Capability>,
    /// `shaderZeroInitializeWorkgroupMemory` is enabled: WGSL's zeroed
    /// workgroup memory is the driver's job (as wgpu-hal does on 1.3),
    /// not a loop naga adds to every shader.
    pub zero_init_native: bool,
    /// [`crate::AshBackend::loop_counters`].
    pub loop_counters: strandgraph_passes::LoopCounters,
    /// VK_EXT_mesh_shader's commands, where a pass draws with mesh shaders.
    pub mesh: Option<ext::mesh_shader::Device>,
    /// `maxTaskWorkGroupCount[0]` (0 without VK_EXT_mesh_shader).
    pub max_task_groups: u32,
    /// Pipeline statistics, when `STRANDGRAPH_PIPELINE_STATS` asks for them.
    pub(crate) stats: Option<crate::stats::Stats>,
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the `Mutex` inside the `Arc` that the `Messenger`
    // keeps alive until it is destroyed; `data` is valid for this call.
    unsafe {
        let messages = &*(user as *const Mutex<Vec<String>>);
        let text = if data.is_null() || (*data).p_message.is_null() {
            "(no message)".to_string()
        } else {
            CStr::from_ptr((*data).p_message)
                .to_string_lossy()
                .into_owned()
        };
        tracing::warn!(?severity, ?kind, "{text}");
        messages
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(format!("[{severity:?} {kind:?}] {text}"));
    }
    vk::FALSE
}

fn name_of(props: &vk::PhysicalDeviceProperties) -> String {
    props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "?".into())
}

/// An instance with the validation layer and synchronization validation
/// when `validate`.
fn create_instance(entry: &ash::Entry, validate: bool) -> Result<Arc<Instance>, AshError> {
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    if validate {
        // SAFETY: plain enumeration.
        let available = unsafe { entry.enumerate_instance_layer_properties() }
            .ctx("vkEnumerateInstanceLayerProperties")?;
        if !available
            .iter()
            .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER))
        {
            return Err(AshError::LayerMissing(
                VALIDATION_LAYER.to_string_lossy().into_owned(),
            ));
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ext::debug_utils::NAME.as_ptr());
        // Provided by the validation layer (1.3.239 on Debian 12 has no
        // VK_EXT_layer_settings yet).
        extensions.push(ext::validation_features::NAME.as_ptr());
    }
    let app = vk::ApplicationInfo::default()
        .application_name(c"strandgraph")
        .api_version(vk::API_VERSION_1_3);
    let enables = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    if validate {
        info = info.push_next(&mut features);
    }
    // SAFETY: the create info and everything it points to outlive the call.
    let raw = unsafe { entry.create_instance(&info, None) }.ctx("vkCreateInstance")?;
    Ok(Instance::new(entry.clone(), raw))
}

/// A messenger collecting the layer's warnings and errors.
fn create_messenger(instance: &Arc<Instance>) -> Result<(Messenger, Messages), AshError> {
    let shared: Messages = Arc::default();
    let loader = ext::debug_utils::Instance::new(&instance.entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(Arc::as_ptr(&shared) as *mut c_void);
    // SAFETY: the messenger owns a clone of `shared`, which the callback's
    // user data points into, until it is destroyed.
    let raw = unsafe { loader.create_debug_utils_messenger(&info, None) }
        .ctx("vkCreateDebugUtilsMessengerEXT")?;
    Ok((
        Messenger::new(instance, loader, raw, shared.clone()),
        shared,
    ))
}

/// The Vulkan 1.3 device named like `backend.device_name`, else the first
/// by type (discrete, integrated, virtual, other).
fn pick_physical(
    instance: &ash::Instance,
    backend: &AshBackend,
) -> Result<(vk::PhysicalDevice, vk::PhysicalDeviceProperties), AshError> {
    // SAFETY: plain queries on a live instance.
    let physicals =
        unsafe { instance.enumerate_physical_devices() }.ctx("vkEnumeratePhysicalDevices")?;
    let mut candidates: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties)> = physicals
        .into_iter()
        .map(|p| (p, unsafe { instance.get_physical_device_properties(p) }))
        .filter(|(_, props)| props.api_version >= vk::API_VERSION_1_3)
        .collect();
    let names: Vec<String> = candidates.iter().map(|(_, p)| name_of(p)).collect();
    if let Some(want) = &backend.device_name {
        candidates.retain(|(_, p)| name_of(p).contains(want.as_str()));
    }
    let rank = |t: vk::PhysicalDeviceType| match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        _ => 3,
    };
    candidates.sort_by_key(|(_, p)| rank(p.device_type));
    candidates.first().copied().ok_or_else(|| {
        AshError::NoDevice(format!(
            "{} (Vulkan 1.3 devices: {names:?})",
            backend
                .device_name
                .as_ref()
                .map(|n| format!(" named like `{n}`"))
                .unwrap_or_default()
        ))
    })
}

/// One graphics+compute family, and a compute-only one when `async_compute`
/// and the device has one.
fn queue_families(
    families: &[vk::QueueFamilyProperties],
    async_compute: bool,
    name: &str,
) -> Result<(u32, Option<u32>), AshError> {
    let graphics = families
        .iter()
        .position(|f| {
            f.queue_flags
                .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
        })
        .ok_or_else(|| AshError::NoDevice(format!(": `{name}` has no graphics+compute queue")))?;
    let compute = async_compute
        .then(|| {
            families.iter().position(|f| {
                f.queue_flags.contains(vk::QueueFlags::COMPUTE)
                    && !f.queue_flags.contains(vk::QueueFlags::GRAPHICS)
            })
        })
        .flatten();
    Ok((graphics as u32, compute.map(|i| i as u32)))
}

/// The logical device with `want` enabled and one queue of each family.
fn create_device(
    instance: &Arc<Instance>,
    physical: vk::PhysicalDevice,
    want: &Wanted,
    families: &[u32],
    messenger: Option<Messenger>,
    stats: bool,
) -> Result<Arc<Device>, AshError> {
    let priority = [1.0f32];
    let queue_infos: Vec<vk::DeviceQueueCreateInfo<'_>> = families
        .iter()
        .map(|&f| {
            vk::DeviceQueueCreateInfo::default()
                .queue_family_index(f)
                .queue_priorities(&priority)
        })
        .collect();
    let mut want12 = vk::PhysicalDeviceVulkan12Features::default()
        .timeline_semaphore(true)
        .shader_buffer_int64_atomics(want.buffer_int64_atomics);
    let mut want13 = vk::PhysicalDeviceVulkan13Features::default()
        .synchronization2(true)
        .dynamic_rendering(want.dynamic_rendering)
        .shader_zero_initialize_workgroup_memory(want.zero_init_workgroup_memory);
    let mut want_stats = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
        .pipeline_executable_info(true);
    let mut want2 = vk::PhysicalDeviceFeatures2::default()
        .features(want.core)
        .push_next(&mut want12)
        .push_next(&mut want13);
    let mut want_mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default()
        .mesh_shader(true)
        .task_shader(true);
    let mut extensions = Vec::new();
    if stats {
        want2 = want2.push_next(&mut want_stats);
        extensions.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
    }
    if want.mesh_shader {
        want2 = want2.push_next(&mut want_mesh);
        extensions.push(ash::ext::mesh_shader::NAME.as_ptr());
    }
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&extensions)
        .push_next(&mut want2);
    // SAFETY: the create info chain lives on this stack frame.
    let raw = unsafe { instance.create_device(physical, &info, None) }.ctx("vkCreateDevice")?;
    Ok(Device::new(instance, raw, messenger))
}

impl Gpu {
    /// What the backend's SPIR-V is written for on this device, for a pass
    /// whose graph keeps naga's loop counters or not (`loop_bounding`).
    pub(crate) fn spirv_target(&self, graph_keeps: bool) -> crate::spirv::Target<'_> {
        crate::spirv::Target {
            caps: &self.spirv_caps,
            zero_init_native: self.zero_init_native,
            loop_bounding: self.loop_counters.for_pass(graph_keeps),
        }
    }

    pub fn new(backend: &AshBackend, needs: &Needs) -> Result<Gpu, AshError> {
        // Best effort: where it fails, the instance below says why.
        let _ = crate::loader::keep_driver_loaded();
        let entry = crate::loader::entry()?;
        let instance = create_instance(&entry, backend.validation == Validation::Sync)?;
        let (messenger, messages) = match backend.validation {
            Validation::Sync => {
                let (m, shared) = create_messenger(&instance)?;
                (Some(m), Some(shared))
            }
            Validation::Off => (None, None),
        };
        let (physical, props) = pick_physical(&instance, backend)?;
        let name = name_of(&props);
        let have = Supported::query(&instance, physical);
        let want = Wanted::choose(&have, needs, &name)?;
        // SAFETY: plain query.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let (graphics, compute) = queue_families(&families, backend.async_compute, &name)?;
        let used: Vec<u32> = std::iter::once(graphics).chain(compute).collect();
        let stats = crate::stats::wanted() && crate::stats::supported(&instance, physical);
        let device = create_device(&instance, physical, &want, &used, messenger, stats)?;
        let queues = used
            .iter()
            .enumerate()
            .map(|(i, &family)| QueueInfo {
                family,
                // SAFETY: the queue was requested at device creation.
                queue: unsafe { device.get_device_queue(family, 0) },
                timestamp_bits: families[family as usize].timestamp_valid_bits,
                compute_only: i > 0,
            })
            .collect();
        // SAFETY: plain query.
        let memory_props = unsafe { instance.get_physical_device_memory_properties(physical) };
        let stats = stats.then(|| crate::stats::Stats::new(&instance, &device));
        let mesh = want
            .mesh_shader
            .then(|| ext::mesh_shader::Device::new(&instance, &device));
        Ok(Gpu {
            device,
            instance,
            messages,
            physical,
            props,
            memory_props,
            queues,
            subgroup_size: have.subgroup_size,
            name,
            enabled: want.names,
            spirv_caps: want.spirv_caps,
            zero_init_native: want.zero_init_workgroup_memory,
            loop_counters: backend.loop_counters,
            mesh,
            max_task_groups: have.max_task_groups,
            stats,
        })
    }

    /// Takes the validation messages collected so far; an error when there are any.
    pub fn check(&self, what: &str) -> Result<(), AshError> {
        let Some(messages) = &self.messages else {
            return Ok(());
        };
        let taken = std::mem::take(&mut *messages.lock().unwrap_or_else(|e| e.into_inner()));
        if taken.is_empty() {
            Ok(())
        } else {
            Err(AshError::Validation {
                what: what.to_string(),
                messages: taken,
            })
        }
    }

    pub fn validating(&self) -> bool {
        self.messages.is_some()
    }

    /// The shared message list, which outlives the device (tests read what
    /// the layer says while a session is destroyed).
    #[cfg(test)]
    pub fn messages(&self) -> Option<Messages> {
        self.messages.clone()
    }

    /// A memory type with `wanted` among `bits`.
    pub fn memory_type(&self, bits: u32, wanted: vk::MemoryPropertyFlags) -> Option<u32> {
        (0..self.memory_props.memory_type_count).find(|&i| {
            bits & (1 << i) != 0
                && self.memory_props.memory_types[i as usize]
                    .property_flags
                    .contains(wanted)
        })
    }
}
