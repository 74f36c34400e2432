//! Instance, validation messenger, physical device, queue families and the
//! logical device with exactly the features the plan's passes need.

use crate::error::{AshError, VkContext};
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
}

pub(crate) struct Gpu {
    /// Keeps the Vulkan loader loaded while the instance lives.
    _entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    messages: Option<Messages>,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
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
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    // SAFETY: `user` is the `Mutex` inside the `Arc` that `Gpu` keeps alive
    // until the messenger is destroyed; `data` is valid for this call.
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

impl Gpu {
    pub fn new(backend: &AshBackend, needs: &Needs) -> Result<Gpu, AshError> {
        // Best effort: where it fails, the instance below says why.
        let _ = crate::loader::keep_driver_loaded();
        let entry = crate::loader::entry()?;
        let validate = backend.validation == Validation::Sync;
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
        let mut features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enables);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validate {
            info = info.push_next(&mut features);
        }
        // SAFETY: the create info and everything it points to outlive the call.
        let instance = unsafe { entry.create_instance(&info, None) }.ctx("vkCreateInstance")?;
        let mut gpu_debug = None;
        let mut messages = None;
        if validate {
            let shared: Messages = Arc::default();
            let loader = ext::debug_utils::Instance::new(&entry, &instance);
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
            // SAFETY: `shared` is kept in `messages` until the messenger is destroyed.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) };
            match messenger {
                Ok(m) => gpu_debug = Some((loader, m)),
                Err(e) => {
                    // SAFETY: nothing else was created from the instance.
                    unsafe { instance.destroy_instance(None) };
                    return Err(AshError::vk("vkCreateDebugUtilsMessengerEXT", e));
                }
            }
            messages = Some(shared);
        }
        let mut partial = Partial {
            instance: Some(instance),
            debug: gpu_debug,
        };
        let gpu = Self::with_device(backend, needs, &entry, &mut partial)?;
        let (instance, debug) = (partial.instance.take(), partial.debug.take());
        let (
            physical,
            device,
            props,
            memory_props,
            queues,
            subgroup,
            enabled,
            spirv_caps,
            zero_init_native,
        ) = gpu;
        Ok(Gpu {
            _entry: entry,
            instance: instance.expect("instance kept until the device exists"),
            debug,
            messages,
            physical,
            device,
            name: name_of(&props),
            props,
            memory_props,
            queues,
            subgroup_size: subgroup.subgroup_size,
            enabled,
            spirv_caps,
            zero_init_native,
        })
    }

    #[allow(clippy::type_complexity)]
    fn with_device(
        backend: &AshBackend,
        needs: &Needs,
        _entry: &ash::Entry,
        partial: &mut Partial,
    ) -> Result<
        (
            vk::PhysicalDevice,
            ash::Device,
            vk::PhysicalDeviceProperties,
            vk::PhysicalDeviceMemoryProperties,
            Vec<QueueInfo>,
            vk::PhysicalDeviceSubgroupProperties<'static>,
            Vec<String>,
            Vec<naga::back::spv::Capability>,
            bool,
        ),
        AshError,
    > {
        let instance = partial.instance.as_ref().expect("instance");
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
        let Some(&(physical, props)) = candidates.first() else {
            return Err(AshError::NoDevice(format!(
                "{} (Vulkan 1.3 devices: {names:?})",
                backend
                    .device_name
                    .as_ref()
                    .map(|n| format!(" named like `{n}`"))
                    .unwrap_or_default()
            )));
        };
        let name = name_of(&props);

        // Features the device has.
        let mut f11 = vk::PhysicalDeviceVulkan11Features::default();
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f11)
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: the chain lives on this stack frame.
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        let core = f2.features;
        let (has12, has13) = (
            (f12.timeline_semaphore, f12.shader_buffer_int64_atomics),
            (f13.synchronization2, f13.dynamic_rendering),
        );
        let zero_init_native = f13.shader_zero_initialize_workgroup_memory == vk::TRUE;
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
        // SAFETY: as above.
        unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
        let subgroup = vk::PhysicalDeviceSubgroupProperties {
            p_next: std::ptr::null_mut(),
            ..subgroup
        };

        let missing = |feature: &str, pass: &str, why: &str| AshError::MissingFeature {
            device: name.clone(),
            feature: feature.to_string(),
            pass: pass.to_string(),
            why: why.to_string(),
        };
        let first = needs
            .caps
            .first()
            .map(|(_, p, _)| p.clone())
            .unwrap_or_else(|| "(every pass)".into());
        if has13.0 == vk::FALSE {
            return Err(missing("synchronization2", &first, "the plan's barriers"));
        }
        if has12.0 == vk::FALSE {
            return Err(missing(
                "timelineSemaphore",
                &first,
                "cross-queue sync points",
            ));
        }
        let mut enabled = vec!["synchronization2".to_string(), "timelineSemaphore".into()];
        if zero_init_native {
            enabled.push("shaderZeroInitializeWorkgroupMemory".into());
        }
        let mut want_core = vk::PhysicalDeviceFeatures::default();
        let mut want12 = vk::PhysicalDeviceVulkan12Features::default().timeline_semaphore(true);
        let mut want13 = vk::PhysicalDeviceVulkan13Features::default()
            .synchronization2(true)
            .shader_zero_initialize_workgroup_memory(zero_init_native);
        use naga::back::spv::Capability as C;
        let mut spirv_caps = vec![
            C::Shader,
            C::Matrix,
            C::Sampled1D,
            C::Image1D,
            C::ImageQuery,
            C::DerivativeControl,
            C::StorageImageExtendedFormats,
        ];
        if let Some(pass) = &needs.raster {
            if has13.1 == vk::FALSE {
                return Err(missing("dynamicRendering", pass, "raster passes"));
            }
            want13 = want13.dynamic_rendering(true);
            enabled.push("dynamicRendering".into());
        }
        let mut seen = Capabilities::empty();
        for (cap, pass, why) in &needs.caps {
            if seen.contains(*cap) {
                continue;
            }
            seen |= *cap;
            match *cap {
                Capabilities::FLOAT64 => {
                    if core.shader_float64 == vk::FALSE {
                        return Err(missing("shaderFloat64", pass, why));
                    }
                    want_core.shader_float64 = vk::TRUE;
                    enabled.push("shaderFloat64".into());
                    spirv_caps.push(C::Float64);
                }
                Capabilities::SHADER_INT64 => {
                    if core.shader_int64 == vk::FALSE {
                        return Err(missing("shaderInt64", pass, why));
                    }
                    want_core.shader_int64 = vk::TRUE;
                    enabled.push("shaderInt64".into());
                    spirv_caps.push(C::Int64);
                }
                Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
                | Capabilities::SHADER_INT64_ATOMIC_ALL_OPS => {
                    if core.shader_int64 == vk::FALSE {
                        return Err(missing("shaderInt64", pass, why));
                    }
                    if has12.1 == vk::FALSE {
                        return Err(missing("shaderBufferInt64Atomics", pass, why));
                    }
                    want_core.shader_int64 = vk::TRUE;
                    want12 = want12.shader_buffer_int64_atomics(true);
                    enabled.push("shaderBufferInt64Atomics".into());
                    spirv_caps.extend([C::Int64, C::Int64Atomics]);
                }
                Capabilities::SUBGROUP | Capabilities::SUBGROUP_BARRIER => {
                    if !subgroup
                        .supported_stages
                        .contains(vk::ShaderStageFlags::COMPUTE)
                    {
                        return Err(missing("subgroup operations in compute shaders", pass, why));
                    }
                    // Each operation class the device supports allows its
                    // SPIR-V capability; naga refuses a shader using another,
                    // and the pass then names it (spirv.rs).
                    let ops = subgroup.supported_operations;
                    spirv_caps.push(C::GroupNonUniform);
                    for (bit, cap) in [
                        (vk::SubgroupFeatureFlags::VOTE, C::GroupNonUniformVote),
                        (
                            vk::SubgroupFeatureFlags::ARITHMETIC,
                            C::GroupNonUniformArithmetic,
                        ),
                        (vk::SubgroupFeatureFlags::BALLOT, C::GroupNonUniformBallot),
                        (vk::SubgroupFeatureFlags::SHUFFLE, C::GroupNonUniformShuffle),
                        (
                            vk::SubgroupFeatureFlags::SHUFFLE_RELATIVE,
                            C::GroupNonUniformShuffleRelative,
                        ),
                        (vk::SubgroupFeatureFlags::QUAD, C::GroupNonUniformQuad),
                    ] {
                        if ops.contains(bit) {
                            spirv_caps.push(cap);
                        }
                    }
                    enabled.push(format!("subgroups ({ops:?})"));
                }
                other => {
                    return Err(missing(&format!("naga capability {other:?}"), pass, why));
                }
            }
        }
        spirv_caps.sort_by_key(|c| *c as u32);
        spirv_caps.dedup();
        enabled.dedup();

        // Queue families: one graphics family, and a compute-only one if asked for.
        // SAFETY: plain query.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let graphics = families
            .iter()
            .position(|f| {
                f.queue_flags
                    .contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE)
            })
            .ok_or_else(|| {
                AshError::NoDevice(format!(": `{name}` has no graphics+compute queue"))
            })? as u32;
        let compute = backend
            .async_compute
            .then(|| {
                families.iter().position(|f| {
                    f.queue_flags.contains(vk::QueueFlags::COMPUTE)
                        && !f.queue_flags.contains(vk::QueueFlags::GRAPHICS)
                })
            })
            .flatten()
            .map(|i| i as u32);
        let priority = [1.0f32];
        let mut queue_infos = vec![
            vk::DeviceQueueCreateInfo::default()
                .queue_family_index(graphics)
                .queue_priorities(&priority),
        ];
        if let Some(c) = compute {
            queue_infos.push(
                vk::DeviceQueueCreateInfo::default()
                    .queue_family_index(c)
                    .queue_priorities(&priority),
            );
        }
        let mut want2 = vk::PhysicalDeviceFeatures2::default()
            .features(want_core)
            .push_next(&mut want12)
            .push_next(&mut want13);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .push_next(&mut want2);
        // SAFETY: the create info chain lives on this stack frame.
        let device =
            unsafe { instance.create_device(physical, &info, None) }.ctx("vkCreateDevice")?;
        let mut queues = Vec::new();
        for (family, compute_only) in
            std::iter::once((graphics, false)).chain(compute.map(|c| (c, true)))
        {
            queues.push(QueueInfo {
                family,
                // SAFETY: the queue was requested above.
                queue: unsafe { device.get_device_queue(family, 0) },
                timestamp_bits: families[family as usize].timestamp_valid_bits,
                compute_only,
            });
        }
        // SAFETY: plain query.
        let memory_props = unsafe { instance.get_physical_device_memory_properties(physical) };
        Ok((
            physical,
            device,
            props,
            memory_props,
            queues,
            subgroup,
            enabled,
            spirv_caps,
            zero_init_native,
        ))
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

/// What exists before the device does, destroyed on an early error.
struct Partial {
    instance: Option<ash::Instance>,
    debug: Option<(ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl Drop for Partial {
    fn drop(&mut self) {
        // Only reached with the instance still here when device creation failed.
        if let Some(instance) = self.instance.take() {
            // SAFETY: nothing created from the instance is alive.
            unsafe {
                if let Some((loader, m)) = self.debug.take() {
                    loader.destroy_debug_utils_messenger(m, None);
                }
                instance.destroy_instance(None);
            }
        }
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: the session destroyed every child object before this.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            if let Some((loader, m)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}
