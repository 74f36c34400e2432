//! WGSL (composed by `strandgraph_passes::wgsl`) to SPIR-V with naga's
//! `spv-out`, and the descriptor layout the module declares.
//!
//! docs/architecture.md, "Shaders": SPIR-V 1.3 or later with an explicit
//! capability set (the device's [`crate::device::Gpu::spirv_caps`]: Int64,
//! Int64Atomics, GroupNonUniform* only where the features were enabled) and
//! `fake_missing_bindings: true`, so `@group(0) @binding(n)` becomes
//! descriptor set 0, binding n as written.

use crate::error::AshError;
use ash::vk;
use naga::back::spv;
use naga::{AddressSpace, ImageClass, TypeInner};
use strandgraph_passes::wgsl::{Composed, all_capabilities, validate};

/// A translated module and the descriptors its entry points use.
pub(crate) struct Spirv {
    pub words: Vec<u32>,
    /// `(binding, type)` in set 0, sorted by binding.
    pub descriptors: Vec<(u32, vk::DescriptorType)>,
}

/// What the SPIR-V is written for: the device's capabilities and how naga
/// writes what WGSL promises beyond SPIR-V.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Target<'a> {
    /// The capabilities the device's enabled features allow.
    pub caps: &'a [spv::Capability],
    /// `shaderZeroInitializeWorkgroupMemory` is enabled (else naga zeroes
    /// workgroup memory in every entry point).
    pub zero_init_native: bool,
    /// naga's forced loop bounding: a counter in every loop that breaks
    /// out after 2^64 iterations ([`crate::AshBackend::loop_counters`]).
    pub loop_bounding: bool,
}

/// Translates `composed` for the entry points `entries` (compute, or vertex
/// and fragments), every entry point of the module or `only` that one;
/// `pass` names the pass in errors.
pub(crate) fn translate(
    composed: &Composed,
    entries: &[&str],
    only: Option<&str>,
    target: Target<'_>,
    pass: &str,
    device: &str,
) -> Result<Spirv, AshError> {
    let Target {
        caps,
        zero_init_native,
        loop_bounding,
    } = target;
    let module = &composed.module;
    let info = validate(module, all_capabilities())
        .map_err(|e| AshError::Shader(format!("pass `{pass}`: {e}")))?;
    let mut descriptors: Vec<(u32, vk::DescriptorType)> = Vec::new();
    for want in entries {
        let Some(index) = module.entry_points.iter().position(|e| e.name == *want) else {
            return Err(AshError::Shader(format!(
                "pass `{pass}`: no entry point `{want}` in the composed module"
            )));
        };
        let uses = info.get_entry_point(index);
        for (handle, var) in module.global_variables.iter() {
            let Some(binding) = &var.binding else {
                continue;
            };
            if uses[handle].is_empty() {
                continue;
            }
            if binding.group != 0 {
                return Err(AshError::Shader(format!(
                    "pass `{pass}`: binding group {} (only group 0 is bound)",
                    binding.group
                )));
            }
            let ty = match (var.space, &module.types[var.ty].inner) {
                (AddressSpace::Uniform, _) => vk::DescriptorType::UNIFORM_BUFFER,
                (AddressSpace::Storage { .. }, _) => vk::DescriptorType::STORAGE_BUFFER,
                (AddressSpace::Handle, TypeInner::Image { class, .. }) => match class {
                    ImageClass::Storage { .. } => vk::DescriptorType::STORAGE_IMAGE,
                    _ => vk::DescriptorType::SAMPLED_IMAGE,
                },
                (AddressSpace::Handle, TypeInner::Sampler { .. }) => vk::DescriptorType::SAMPLER,
                (space, _) => {
                    return Err(AshError::Shader(format!(
                        "pass `{pass}`: binding {} in {space:?} is not a descriptor",
                        binding.binding
                    )));
                }
            };
            if !descriptors.iter().any(|(b, _)| *b == binding.binding) {
                descriptors.push((binding.binding, ty));
            }
        }
    }
    descriptors.sort_by_key(|(b, _)| *b);

    // SPV_EXT_mesh_shader needs SPIR-V 1.4; everything else stays at 1.3.
    let mesh = module
        .entry_points
        .iter()
        .any(|e| matches!(e.stage, naga::ShaderStage::Task | naga::ShaderStage::Mesh));
    let options = spv::Options {
        lang_version: if mesh { (1, 4) } else { (1, 3) },
        flags: spv::WriterFlags::LABEL_VARYINGS,
        fake_missing_bindings: true,
        capabilities: Some(caps.iter().copied().collect()),
        // The same robustness wgpu-hal asks naga for on Vulkan, so
        // out-of-range accesses behave as on the wgpu backend.
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: naga::proc::BoundsCheckPolicy::Restrict,
            buffer: naga::proc::BoundsCheckPolicy::Restrict,
            image_load: naga::proc::BoundsCheckPolicy::Restrict,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        // WGSL zero-initialises workgroup memory: by the driver where
        // shaderZeroInitializeWorkgroupMemory is enabled, else by naga.
        zero_initialize_workgroup_memory: if zero_init_native {
            spv::ZeroInitializeWorkgroupMemoryMode::Native
        } else {
            spv::ZeroInitializeWorkgroupMemoryMode::Polyfill
        },
        force_loop_bounding: loop_bounding,
        ..Default::default()
    };
    let pipeline = only
        .map(|name| {
            let ep = module.entry_points.iter().find(|e| e.name == name);
            ep.map(|ep| spv::PipelineOptions {
                shader_stage: ep.stage,
                entry_point: name.to_string(),
            })
            .ok_or_else(|| AshError::Shader(format!("pass `{pass}`: no entry point `{name}`")))
        })
        .transpose()?;
    let mut words =
        spv::write_vec(module, &info, &options, pipeline.as_ref()).map_err(|e| match e {
            spv::Error::MissingCapabilities(what, missing) => AshError::MissingFeature {
                device: device.to_string(),
                feature: format!("SPIR-V capability {missing:?}"),
                pass: pass.to_string(),
                why: format!("the shader uses {what}"),
            },
            e => AshError::Shader(format!("pass `{pass}`: SPIR-V: {e}")),
        })?;
    // Round every float operation as written, as the CPU simulator does
    // (strandgraph_passes::spirv says why).
    if !strandgraph_passes::spirv::contraction_allowed() {
        strandgraph_passes::spirv::forbid_contraction(&mut words)
            .map_err(|e| AshError::Shader(format!("pass `{pass}`: {e}")))?;
    }
    // naga checks some capabilities against the given set and adds others
    // (Float64, Int64) unchecked: check every declared one here.
    for cap in declared_capabilities(&words) {
        if !caps.iter().any(|c| *c as u32 == cap) {
            return Err(AshError::MissingFeature {
                device: device.to_string(),
                feature: format!("SPIR-V capability {}", capability_name(caps, cap)),
                pass: pass.to_string(),
                why: "the translated shader declares it and the device's enabled features do not allow it".into(),
            });
        }
    }
    Ok(Spirv { words, descriptors })
}

/// The operands of every `OpCapability` (opcode 17) in a SPIR-V module.
pub(crate) fn declared_capabilities(words: &[u32]) -> Vec<u32> {
    let mut out = Vec::new();
    let mut i = 5; // after the header
    while i < words.len() {
        let (count, opcode) = ((words[i] >> 16) as usize, words[i] & 0xFFFF);
        if count == 0 {
            break;
        }
        if opcode == 17 && i + 1 < words.len() {
            out.push(words[i + 1]);
        }
        i += count;
    }
    out
}

fn capability_name(_known: &[spv::Capability], raw: u32) -> String {
    use spv::Capability as C;
    for c in [
        C::Float64,
        C::Int64,
        C::Int64Atomics,
        C::GroupNonUniform,
        C::GroupNonUniformVote,
        C::GroupNonUniformArithmetic,
        C::GroupNonUniformBallot,
        C::GroupNonUniformShuffle,
        C::GroupNonUniformShuffleRelative,
        C::GroupNonUniformQuad,
        C::Int16,
        C::Float16,
    ] {
        if c as u32 == raw {
            return format!("{c:?}");
        }
    }
    format!("#{raw}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use strandgraph_passes::wgsl::Shaders;

    /// `caps`, naga's polyfill for zeroed workgroup memory, no loop bounding.
    fn plain(caps: &[spv::Capability]) -> Target<'_> {
        Target {
            caps,
            zero_init_native: false,
            loop_bounding: false,
        }
    }

    #[test]
    fn clear_translates_with_a_uniform_and_a_storage_buffer() {
        let mut shaders = Shaders::embedded().unwrap();
        let composed = shaders.compose("common/clear.wgsl").unwrap();
        let entry = composed.module.entry_points[0].name.clone();
        let s = translate(
            &composed,
            &[&entry],
            None,
            plain(&[spv::Capability::Shader]),
            "clear",
            "test",
        )
        .unwrap();
        assert_eq!(s.words[0], 0x0723_0203, "SPIR-V magic");
        assert_eq!(
            s.descriptors,
            vec![
                (0, vk::DescriptorType::UNIFORM_BUFFER),
                (1, vk::DescriptorType::STORAGE_BUFFER)
            ]
        );
    }

    #[test]
    fn loop_bounding_adds_naga_s_counter_to_each_loop() {
        let mut shaders = Shaders::embedded().unwrap();
        let composed = shaders.compose("sim/follow.wgsl").unwrap();
        let caps = [spv::Capability::Shader];
        let words = |loop_bounding| {
            let target = Target {
                loop_bounding,
                ..plain(&caps)
            };
            translate(&composed, &["follow"], None, target, "follow", "test")
                .unwrap()
                .words
        };
        let (bounded, free) = (words(true), words(false));
        // OpLoopMerge (opcode 246): the same loops either way.
        let loops = |w: &[u32]| opcodes(w).filter(|&op| op == 246).count();
        assert!(loops(&free) > 0);
        assert_eq!(loops(&bounded), loops(&free));
        // OpVariable (59): the counter, one per loop.
        let vars = |w: &[u32]| opcodes(w).filter(|&op| op == 59).count();
        assert_eq!(vars(&bounded), vars(&free) + loops(&free));
    }

    /// The opcode of every instruction after the header.
    fn opcodes(words: &[u32]) -> impl Iterator<Item = u32> + '_ {
        let mut i = 5;
        std::iter::from_fn(move || {
            let w = *words.get(i)?;
            i += ((w >> 16) as usize).max(1);
            Some(w & 0xFFFF)
        })
    }

    /// `OpEntryPoint` (opcode 15) instructions in a module.
    fn entry_points(words: &[u32]) -> usize {
        opcodes(words).filter(|&op| op == 15).count()
    }

    #[test]
    fn mesh_shaders_translate_to_spirv_1_4_with_mesh_shading() {
        use spv::Capability as C;
        let mut shaders = Shaders::embedded().unwrap();
        let composed = shaders.compose("hw_strands/mesh.wgsl").unwrap();
        let caps = [
            C::Shader,
            C::ImageQuery,
            C::MeshShadingEXT,
            C::SampleRateShading,
            C::Int64,
            C::Int64Atomics,
            C::GroupNonUniform,
            C::GroupNonUniformShuffle,
            C::GroupNonUniformShuffleRelative,
        ];
        let s = translate(
            &composed,
            &["ms_main", "ts_main", "fs_main"],
            None,
            plain(&caps),
            "mesh",
            "test",
        )
        .unwrap();
        assert_eq!(s.words[1], 0x0001_0400, "SPIR-V 1.4");
        // One entry point per module, as the backend builds mesh pipelines.
        for e in ["ms_main", "ts_main", "fs_main"] {
            let one = translate(&composed, &[e], Some(e), plain(&caps), "mesh", "test").unwrap();
            assert_eq!(entry_points(&one.words), 1, "{e}");
        }
        assert!(declared_capabilities(&s.words).contains(&(C::MeshShadingEXT as u32)));
        // Without the capability, the error names it and the pass.
        let without: Vec<C> = caps
            .into_iter()
            .filter(|c| *c != C::MeshShadingEXT)
            .collect();
        let text = translate(
            &composed,
            &["ms_main"],
            Some("ms_main"),
            plain(&without),
            "mesh",
            "test",
        )
        .err()
        .unwrap()
        .to_string();
        assert!(
            text.contains("`mesh`") && text.contains("MeshShading"),
            "{text}"
        );
    }

    #[test]
    fn a_capability_the_device_lacks_names_the_pass() {
        let mut shaders = Shaders::embedded().unwrap();
        let composed = shaders.compose("kulikov/lod.wgsl").unwrap();
        let entry = composed.module.entry_points[0].name.clone();
        // Float64 withheld.
        let err = translate(
            &composed,
            &[&entry],
            None,
            plain(&[spv::Capability::Shader]),
            "lod",
            "test",
        )
        .err()
        .unwrap();
        let text = err.to_string();
        assert!(text.contains("`lod`") && text.contains("Float64"), "{text}");
    }
}
