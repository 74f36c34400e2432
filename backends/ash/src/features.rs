//! Device features: what the physical device supports, and the features to
//! enable, which are exactly what the plan's passes need (each checked,
//! with the first pass that needs it named in the error), with the SPIR-V
//! capabilities they allow.

use crate::device::Needs;
use crate::error::AshError;
use ash::vk;
use naga::valid::Capabilities;

/// What the physical device supports, of what the passes may need.
pub(crate) struct Supported {
    pub core: vk::PhysicalDeviceFeatures,
    pub timeline_semaphore: bool,
    pub buffer_int64_atomics: bool,
    pub synchronization2: bool,
    pub dynamic_rendering: bool,
    pub zero_init_workgroup_memory: bool,
    pub subgroup_stages: vk::ShaderStageFlags,
    pub subgroup_ops: vk::SubgroupFeatureFlags,
    pub subgroup_size: u32,
    /// VK_EXT_mesh_shader with both `meshShader` and `taskShader`.
    pub mesh_shader: bool,
    /// Its `maxTaskWorkGroupCount[0]` (0 without it).
    pub max_task_groups: u32,
}

impl Supported {
    pub fn query(instance: &ash::Instance, physical: vk::PhysicalDevice) -> Self {
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default()
            .push_next(&mut f12)
            .push_next(&mut f13);
        // SAFETY: the chain lives on this stack frame.
        unsafe { instance.get_physical_device_features2(physical, &mut f2) };
        let core = f2.features;
        let mesh_shader = has_extension(instance, physical, ash::ext::mesh_shader::NAME) && {
            let mut mesh = vk::PhysicalDeviceMeshShaderFeaturesEXT::default();
            let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut mesh);
            // SAFETY: the chain lives on this stack frame; the extension is
            // supported, so its feature struct may be chained.
            unsafe { instance.get_physical_device_features2(physical, &mut f2) };
            mesh.mesh_shader == vk::TRUE && mesh.task_shader == vk::TRUE
        };
        let mut mesh_props = vk::PhysicalDeviceMeshShaderPropertiesEXT::default();
        if mesh_shader {
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut mesh_props);
            // SAFETY: as above.
            unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
        }
        let mut subgroup = vk::PhysicalDeviceSubgroupProperties::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut subgroup);
        // SAFETY: as above.
        unsafe { instance.get_physical_device_properties2(physical, &mut p2) };
        Self {
            core,
            timeline_semaphore: f12.timeline_semaphore == vk::TRUE,
            buffer_int64_atomics: f12.shader_buffer_int64_atomics == vk::TRUE,
            synchronization2: f13.synchronization2 == vk::TRUE,
            dynamic_rendering: f13.dynamic_rendering == vk::TRUE,
            zero_init_workgroup_memory: f13.shader_zero_initialize_workgroup_memory == vk::TRUE,
            subgroup_stages: subgroup.supported_stages,
            subgroup_ops: subgroup.supported_operations,
            subgroup_size: subgroup.subgroup_size,
            mesh_shader,
            max_task_groups: mesh_props.max_task_work_group_count[0],
        }
    }
}

/// Whether `physical` offers device extension `name`.
fn has_extension(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    name: &std::ffi::CStr,
) -> bool {
    // SAFETY: plain query on a live instance.
    unsafe { instance.enumerate_device_extension_properties(physical) }
        .map(|all| all.iter().any(|e| e.extension_name_as_c_str() == Ok(name)))
        .unwrap_or(false)
}

/// The features to enable: exactly what the passes need, each checked
/// against the device with the first pass that needs it in the error.
#[derive(Default)]
pub(crate) struct Wanted {
    pub core: vk::PhysicalDeviceFeatures,
    pub buffer_int64_atomics: bool,
    pub dynamic_rendering: bool,
    pub zero_init_workgroup_memory: bool,
    /// VK_EXT_mesh_shader with `meshShader` and `taskShader`.
    pub mesh_shader: bool,
    /// For the frame notes.
    pub names: Vec<String>,
    pub spirv_caps: Vec<naga::back::spv::Capability>,
}

impl Wanted {
    pub fn choose(have: &Supported, needs: &Needs, device: &str) -> Result<Self, AshError> {
        use naga::back::spv::Capability as C;
        let missing = |feature: &str, pass: &str, why: &str| AshError::MissingFeature {
            device: device.to_string(),
            feature: feature.to_string(),
            pass: pass.to_string(),
            why: why.to_string(),
        };
        let first = needs
            .caps
            .first()
            .map(|(_, p, _)| p.clone())
            .unwrap_or_else(|| "(every pass)".into());
        if !have.synchronization2 {
            return Err(missing("synchronization2", &first, "the plan's barriers"));
        }
        if !have.timeline_semaphore {
            return Err(missing(
                "timelineSemaphore",
                &first,
                "cross-queue sync points",
            ));
        }
        let mut want = Wanted {
            zero_init_workgroup_memory: have.zero_init_workgroup_memory,
            names: vec!["synchronization2".to_string(), "timelineSemaphore".into()],
            spirv_caps: vec![
                C::Shader,
                C::Matrix,
                C::Sampled1D,
                C::Image1D,
                C::ImageQuery,
                C::DerivativeControl,
                C::StorageImageExtendedFormats,
            ],
            ..Wanted::default()
        };
        if have.zero_init_workgroup_memory {
            want.names
                .push("shaderZeroInitializeWorkgroupMemory".into());
        }
        if let Some(pass) = &needs.raster {
            if !have.dynamic_rendering {
                return Err(missing("dynamicRendering", pass, "raster passes"));
            }
            want.dynamic_rendering = true;
            want.names.push("dynamicRendering".into());
        }
        if let Some(pass) = &needs.fragment_stores {
            if have.core.fragment_stores_and_atomics == vk::FALSE {
                return Err(missing(
                    "fragmentStoresAndAtomics",
                    pass,
                    "its fragment shader writes storage buffers",
                ));
            }
            want.core.fragment_stores_and_atomics = vk::TRUE;
            want.names.push("fragmentStoresAndAtomics".into());
        }
        let mut seen = Capabilities::empty();
        for (cap, pass, why) in &needs.caps {
            if !seen.contains(*cap) {
                seen |= *cap;
                want.enable(*cap, have)
                    .map_err(|f| missing(&f, pass, why))?;
            }
        }
        // A mesh shader's subgroup operations run in the task and mesh stages.
        let of_pass = |pass: &str, cap: Capabilities| {
            needs
                .caps
                .iter()
                .any(|(c, p, _)| p == pass && c.contains(cap))
        };
        let mesh_stages = vk::ShaderStageFlags::TASK_EXT | vk::ShaderStageFlags::MESH_EXT;
        for (_, pass, _) in needs
            .caps
            .iter()
            .filter(|(c, _, _)| *c == Capabilities::MESH_SHADER)
        {
            if of_pass(pass, Capabilities::SUBGROUP) && !have.subgroup_stages.contains(mesh_stages)
            {
                return Err(missing(
                    "subgroup operations in task and mesh shaders",
                    pass,
                    "its mesh shader assembles strands with subgroup shuffles",
                ));
            }
        }
        want.spirv_caps.sort_by_key(|c| *c as u32);
        want.spirv_caps.dedup();
        want.names.dedup();
        Ok(want)
    }

    /// Enables what naga capability `cap` needs; the missing feature's name
    /// when the device lacks it.
    fn enable(&mut self, cap: Capabilities, have: &Supported) -> Result<(), String> {
        use naga::back::spv::Capability as C;
        match cap {
            // SPIR-V's EarlyFragmentTests execution mode is core Vulkan.
            Capabilities::EARLY_DEPTH_TEST => {}
            // `sample_index` and sample interpolation: sample-rate shading.
            Capabilities::MULTISAMPLED_SHADING => {
                if have.core.sample_rate_shading == vk::FALSE {
                    return Err("sampleRateShading".into());
                }
                self.core.sample_rate_shading = vk::TRUE;
                self.names.push("sampleRateShading".into());
                self.spirv_caps.push(C::SampleRateShading);
            }
            Capabilities::FLOAT64 => {
                if have.core.shader_float64 == vk::FALSE {
                    return Err("shaderFloat64".into());
                }
                self.core.shader_float64 = vk::TRUE;
                self.names.push("shaderFloat64".into());
                self.spirv_caps.push(C::Float64);
            }
            Capabilities::SHADER_INT64 => {
                if have.core.shader_int64 == vk::FALSE {
                    return Err("shaderInt64".into());
                }
                self.core.shader_int64 = vk::TRUE;
                self.names.push("shaderInt64".into());
                self.spirv_caps.push(C::Int64);
            }
            Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
            | Capabilities::SHADER_INT64_ATOMIC_ALL_OPS => {
                if have.core.shader_int64 == vk::FALSE {
                    return Err("shaderInt64".into());
                }
                if !have.buffer_int64_atomics {
                    return Err("shaderBufferInt64Atomics".into());
                }
                self.core.shader_int64 = vk::TRUE;
                self.buffer_int64_atomics = true;
                self.names.push("shaderBufferInt64Atomics".into());
                self.spirv_caps.extend([C::Int64, C::Int64Atomics]);
            }
            Capabilities::SUBGROUP | Capabilities::SUBGROUP_BARRIER => {
                if !have.subgroup_stages.contains(vk::ShaderStageFlags::COMPUTE) {
                    return Err("subgroup operations in compute shaders".into());
                }
                // Each operation class the device supports allows its
                // SPIR-V capability; naga refuses a shader using another,
                // and the pass then names it (spirv.rs).
                let ops = have.subgroup_ops;
                self.spirv_caps.push(C::GroupNonUniform);
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
                        self.spirv_caps.push(cap);
                    }
                }
                self.names.push(format!("subgroups ({ops:?})"));
            }
            Capabilities::MESH_SHADER => {
                if !have.mesh_shader {
                    return Err("VK_EXT_mesh_shader (meshShader and taskShader)".into());
                }
                self.mesh_shader = true;
                self.names.push("VK_EXT_mesh_shader".into());
                self.spirv_caps.push(C::MeshShadingEXT);
            }
            other => return Err(format!("naga capability {other:?}")),
        }
        Ok(())
    }
}
