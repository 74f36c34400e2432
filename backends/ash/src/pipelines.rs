//! Shader modules, descriptor sets, parameter blocks and pipelines of every
//! pass, built once per session. Compute passes are compute pipelines;
//! raster passes are one graphics pipeline per `Draw` of their
//! `RasterState` (dynamic rendering, no vertex buffers), as on wgpu.

use crate::barriers::SyncPlan;
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::memory::{HostBuffer, Memory, Res};
use crate::prepare::Prepared;
use crate::spirv::translate;
use ash::vk;
use std::collections::BTreeMap;
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::schema::Usage;
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::Dispatch;
use strandgraph_passes::draw::{Blend, Compare, RasterState};

/// How a compute dispatch gets its workgroup count.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Launch {
    Direct(u32),
    /// Resource id and byte offset of the `[x, y, z]` arguments.
    Indirect(usize, u64),
}

pub(crate) enum Work {
    Compute {
        pipeline: vk::Pipeline,
        dispatches: Vec<(vk::DescriptorSet, Launch)>,
    },
    Raster {
        pipelines: Vec<vk::Pipeline>,
        set: vk::DescriptorSet,
        /// Physical resource ids of the colour attachments and the depth one.
        color: Vec<usize>,
        depth: Option<usize>,
        state: RasterState,
        vertices: u32,
        extent: [u32; 2],
    },
}

pub(crate) struct Built {
    pub p: PassId,
    pub work: Work,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    module: vk::ShaderModule,
}

pub(crate) struct Pipelines {
    pub built: Vec<Built>,
    pool: vk::DescriptorPool,
    uniforms: Option<HostBuffer>,
}

impl Pipelines {
    pub fn destroy(&mut self, d: &ash::Device) {
        // SAFETY: the device is idle.
        unsafe {
            for b in self.built.drain(..) {
                match b.work {
                    Work::Compute { pipeline, .. } => d.destroy_pipeline(pipeline, None),
                    Work::Raster { pipelines, .. } => {
                        for p in pipelines {
                            d.destroy_pipeline(p, None);
                        }
                    }
                }
                d.destroy_pipeline_layout(b.layout, None);
                d.destroy_descriptor_set_layout(b.set_layout, None);
                d.destroy_shader_module(b.module, None);
            }
            if self.pool != vk::DescriptorPool::null() {
                d.destroy_descriptor_pool(self.pool, None);
            }
        }
        if let Some(mut u) = self.uniforms.take() {
            u.destroy(d);
        }
    }
}

fn compare(c: Compare) -> vk::CompareOp {
    match c {
        Compare::Always => vk::CompareOp::ALWAYS,
        Compare::Less => vk::CompareOp::LESS,
        Compare::Equal => vk::CompareOp::EQUAL,
    }
}

/// One descriptor set to allocate and fill: the pass, its parameter block
/// and the bound resources for bindings 1.. in order.
struct SetPlan {
    built: usize,
    params: Vec<u32>,
    bound: Vec<usize>,
}

pub(crate) fn build(
    gpu: &Gpu,
    plan: &Plan,
    instance: &Instance,
    prepared: &[Prepared<'_>],
    memory: &Memory,
    sync: &SyncPlan,
) -> Result<Pipelines, AshError> {
    let mut out = Pipelines {
        built: Vec::new(),
        pool: vk::DescriptorPool::null(),
        uniforms: None,
    };
    match build_into(&mut out, gpu, plan, instance, prepared, memory, sync) {
        Ok(()) => Ok(out),
        Err(e) => {
            out.destroy(&gpu.device);
            Err(e)
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn build_into(
    out: &mut Pipelines,
    gpu: &Gpu,
    plan: &Plan,
    instance: &Instance,
    prepared: &[Prepared<'_>],
    memory: &Memory,
    sync: &SyncPlan,
) -> Result<(), AshError> {
    let d = &gpu.device;
    let g = &plan.graph;
    let q = &instance.quantities;
    let mut sets: Vec<SetPlan> = Vec::new();
    let mut descriptor_types: Vec<Vec<(u32, vk::DescriptorType)>> = Vec::new();
    for prep in prepared {
        let pass = &g.passes[prep.p];
        let pass_error = |message: String| AshError::Pass {
            pass: pass.name.clone(),
            message,
        };
        let shader = prep.def.shader();
        let mut entries = vec![shader.entry];
        if let Some(state) = &prep.raster {
            entries.extend(state.draws.iter().map(|d| d.fragment));
        }
        let spirv = translate(
            &prep.composed,
            &entries,
            &gpu.spirv_caps,
            gpu.zero_init_native,
            &pass.name,
            &gpu.name,
        )?;
        let info = vk::ShaderModuleCreateInfo::default().code(&spirv.words);
        // SAFETY: valid SPIR-V words from naga.
        let module = unsafe { d.create_shader_module(&info, None) }
            .ctx(&format!("pass `{}`: vkCreateShaderModule", pass.name))?;
        let stage_flags = if prep.raster.is_some() {
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT
        } else {
            vk::ShaderStageFlags::COMPUTE
        };
        let bindings: Vec<vk::DescriptorSetLayoutBinding<'_>> = spirv
            .descriptors
            .iter()
            .map(|&(b, ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(stage_flags)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
        // SAFETY: valid device and info.
        let set_layout = match unsafe { d.create_descriptor_set_layout(&info, None) } {
            Ok(l) => l,
            Err(e) => {
                // SAFETY: unused module.
                unsafe { d.destroy_shader_module(module, None) };
                return Err(AshError::vk("vkCreateDescriptorSetLayout", e));
            }
        };
        let layouts = [set_layout];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts);
        // SAFETY: valid device and info.
        let layout = match unsafe { d.create_pipeline_layout(&info, None) } {
            Ok(l) => l,
            Err(e) => {
                // SAFETY: unused objects.
                unsafe {
                    d.destroy_descriptor_set_layout(set_layout, None);
                    d.destroy_shader_module(module, None);
                }
                return Err(AshError::vk("vkCreatePipelineLayout", e));
            }
        };
        let index = out.built.len();
        // Registered before the pipelines so an error below still frees these.
        out.built.push(Built {
            p: prep.p,
            work: Work::Compute {
                pipeline: vk::Pipeline::null(),
                dispatches: Vec::new(),
            },
            layout,
            set_layout,
            module,
        });
        descriptor_types.push(spirv.descriptors.clone());

        if let Some(state) = &prep.raster {
            let attachment = |usage: Usage| -> Vec<usize> {
                prep.bindings
                    .iter()
                    .filter(|(_, _, u)| *u == usage)
                    .map(|(_, r, _)| *r)
                    .collect()
            };
            let color = attachment(Usage::Color);
            let depth = attachment(Usage::Depth).first().copied();
            let format_of = |r: usize| match &memory.res[r] {
                Some(Res::Image { format, extent, .. }) => Ok((*format, *extent)),
                _ => Err(pass_error(format!(
                    "attachment `{}` is not an image",
                    g.resources[r].name
                ))),
            };
            let color_formats: Vec<vk::Format> = color
                .iter()
                .map(|&r| format_of(r).map(|f| f.0))
                .collect::<Result<_, _>>()?;
            let depth_format = depth.map(|r| format_of(r).map(|f| f.0)).transpose()?;
            let extent = match color.first().or(depth.as_ref()) {
                Some(&r) => {
                    let e = format_of(r)?.1;
                    [e[0], e[1]]
                }
                None => return Err(pass_error("a raster pass without attachments".into())),
            };
            let mut pipelines = Vec::new();
            for draw in &state.draws {
                let vs_name = std::ffi::CString::new(shader.entry)
                    .map_err(|_| pass_error("entry name has a NUL".into()))?;
                let fs_name = std::ffi::CString::new(draw.fragment)
                    .map_err(|_| pass_error("entry name has a NUL".into()))?;
                let stages = [
                    vk::PipelineShaderStageCreateInfo::default()
                        .stage(vk::ShaderStageFlags::VERTEX)
                        .module(module)
                        .name(&vs_name),
                    vk::PipelineShaderStageCreateInfo::default()
                        .stage(vk::ShaderStageFlags::FRAGMENT)
                        .module(module)
                        .name(&fs_name),
                ];
                let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
                let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
                    .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
                let viewport = vk::PipelineViewportStateCreateInfo::default()
                    .viewport_count(1)
                    .scissor_count(1);
                // Counter-clockwise front faces as wgpu-hal maps them, with
                // the same negative-height viewport (record.rs).
                let raster = vk::PipelineRasterizationStateCreateInfo::default()
                    .polygon_mode(vk::PolygonMode::FILL)
                    .cull_mode(if state.cull_back_faces {
                        vk::CullModeFlags::BACK
                    } else {
                        vk::CullModeFlags::NONE
                    })
                    .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
                    .line_width(1.0);
                let multisample = vk::PipelineMultisampleStateCreateInfo::default()
                    .rasterization_samples(vk::SampleCountFlags::TYPE_1);
                let depth_state = vk::PipelineDepthStencilStateCreateInfo::default()
                    .depth_test_enable(depth.is_some())
                    .depth_write_enable(depth.is_some() && draw.depth_write)
                    .depth_compare_op(compare(draw.depth_compare));
                let blend_attachment = |_: &vk::Format| {
                    let mask = if draw.color_writes {
                        vk::ColorComponentFlags::RGBA
                    } else {
                        vk::ColorComponentFlags::empty()
                    };
                    let a = vk::PipelineColorBlendAttachmentState::default().color_write_mask(mask);
                    match draw.blend {
                        Blend::Replace => a,
                        // colour = src + (1 − src.a)·dst; the attachment's alpha stays.
                        Blend::PremultipliedOverKeepAlpha => a
                            .blend_enable(true)
                            .src_color_blend_factor(vk::BlendFactor::ONE)
                            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                            .color_blend_op(vk::BlendOp::ADD)
                            .src_alpha_blend_factor(vk::BlendFactor::ZERO)
                            .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                            .alpha_blend_op(vk::BlendOp::ADD),
                    }
                };
                let blends: Vec<vk::PipelineColorBlendAttachmentState> =
                    color_formats.iter().map(blend_attachment).collect();
                let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
                let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
                let dynamic =
                    vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
                let mut rendering = vk::PipelineRenderingCreateInfo::default()
                    .color_attachment_formats(&color_formats)
                    .depth_attachment_format(depth_format.unwrap_or(vk::Format::UNDEFINED));
                let info = vk::GraphicsPipelineCreateInfo::default()
                    .stages(&stages)
                    .vertex_input_state(&vertex_input)
                    .input_assembly_state(&assembly)
                    .viewport_state(&viewport)
                    .rasterization_state(&raster)
                    .multisample_state(&multisample)
                    .depth_stencil_state(&depth_state)
                    .color_blend_state(&blend)
                    .dynamic_state(&dynamic)
                    .layout(layout)
                    .push_next(&mut rendering);
                // SAFETY: every pointer in `info` lives on this stack frame.
                let made = unsafe {
                    d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
                };
                match made {
                    Ok(p) => pipelines.extend(p),
                    Err((p, e)) => {
                        // SAFETY: pipelines that were created are unused.
                        unsafe {
                            for x in pipelines.into_iter().chain(p) {
                                if x != vk::Pipeline::null() {
                                    d.destroy_pipeline(x, None);
                                }
                            }
                        }
                        return Err(AshError::vk(
                            format!("pass `{}`: vkCreateGraphicsPipelines", pass.name),
                            e,
                        ));
                    }
                }
            }
            let vertices = u32::try_from(state.vertices)
                .map_err(|_| pass_error(format!("{} vertices are too many", state.vertices)))?;
            out.built[index].work = Work::Raster {
                pipelines,
                set: vk::DescriptorSet::null(),
                color,
                depth,
                state: state.clone(),
                vertices,
                extent,
            };
            let bound = prep
                .bindings
                .iter()
                .filter(|(_, _, u)| !matches!(u, Usage::Color | Usage::Depth))
                .map(|(_, r, _)| *r)
                .collect();
            sets.push(SetPlan {
                built: index,
                params: prep.params.clone(),
                bound,
            });
            continue;
        }

        let entry = std::ffi::CString::new(shader.entry)
            .map_err(|_| pass_error("entry name has a NUL".into()))?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(&entry);
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout);
        // SAFETY: valid module and layout.
        let pipeline =
            match unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) } {
                Ok(p) => p[0],
                Err((_, e)) => {
                    return Err(AshError::vk(
                        format!("pass `{}`: vkCreateComputePipelines", pass.name),
                        e,
                    ));
                }
            };
        let max_groups = gpu.props.limits.max_compute_work_group_count[0];
        let check_groups = |groups: u64| {
            u32::try_from(groups)
                .ok()
                .filter(|&n| n <= max_groups)
                .ok_or_else(|| {
                    pass_error(format!(
                        "{groups} workgroups exceed the device's {max_groups} per dimension"
                    ))
                })
        };
        let words_of = |r: usize| instance.sizes[r].bytes.div_ceil(4);
        let is_buffer = |r: usize| matches!(memory.res[r], Some(Res::Buffer { .. }));
        let mut launches = Vec::new();
        if prep.def.bindings().is_none() {
            // One dispatch per written resource, its size in words in the last word.
            let Dispatch::CoverWrites { words_per_group } = prep.def.dispatch() else {
                return Err(pass_error(
                    "a pass without fixed bindings must dispatch CoverWrites".into(),
                ));
            };
            for (_, r, _) in &prep.bindings {
                let words = words_of(*r);
                let mut params = prep.params.clone();
                if let Some(last) = params.last_mut() {
                    *last = u32::try_from(words)
                        .map_err(|_| pass_error(format!("{words} words to clear")))?;
                }
                let groups = check_groups(words.div_ceil(u64::from(words_per_group.max(1))))?;
                launches.push(Launch::Direct(groups));
                sets.push(SetPlan {
                    built: index,
                    params,
                    bound: vec![*r],
                });
            }
        } else {
            let most = prep
                .bindings
                .iter()
                .filter(|(_, r, _)| is_buffer(*r))
                .map(|(_, r, _)| words_of(*r))
                .max()
                .unwrap_or(0);
            let dispatch = prep.def.dispatch();
            let launch = match (dispatch.direct_groups(q, most), dispatch) {
                (Some(n), _) => Launch::Direct(check_groups(n)?),
                (None, Dispatch::Indirect { binding, word }) => {
                    let r = prep
                        .bindings
                        .iter()
                        .find(|(n, _, _)| n == binding)
                        .map(|(_, r, _)| *r)
                        .ok_or_else(|| pass_error(format!("indirect `{binding}` is not bound")))?;
                    Launch::Indirect(r, word as u64 * 4)
                }
                (None, _) => unreachable!("only indirect dispatches have no direct count"),
            };
            launches.push(launch);
            sets.push(SetPlan {
                built: index,
                params: prep.params.clone(),
                bound: prep.bindings.iter().map(|(_, r, _)| *r).collect(),
            });
        }
        out.built[index].work = Work::Compute {
            pipeline,
            dispatches: launches
                .into_iter()
                .map(|l| (vk::DescriptorSet::null(), l))
                .collect(),
        };
    }

    // Parameter blocks, one per set, in one host-visible buffer.
    let align = gpu.props.limits.min_uniform_buffer_offset_alignment.max(16);
    let mut offsets = Vec::new();
    let mut cursor = 0u64;
    for s in &sets {
        offsets.push(cursor);
        cursor += (s.params.len() as u64 * 4).max(16).next_multiple_of(align);
    }
    let uniforms = HostBuffer::new(
        gpu,
        cursor,
        vk::BufferUsageFlags::UNIFORM_BUFFER,
        "parameter blocks",
    )?;
    for (s, &off) in sets.iter().zip(&offsets) {
        uniforms.write(off, &s.params);
    }

    // One pool for every set.
    let mut counts: BTreeMap<i32, u32> = BTreeMap::new();
    for s in &sets {
        for (_, ty) in &descriptor_types[s.built] {
            *counts.entry(ty.as_raw()).or_default() += 1;
        }
    }
    let sizes: Vec<vk::DescriptorPoolSize> = counts
        .iter()
        .map(|(&ty, &n)| vk::DescriptorPoolSize {
            ty: vk::DescriptorType::from_raw(ty),
            descriptor_count: n,
        })
        .collect();
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(sets.len().max(1) as u32)
        .pool_sizes(&sizes);
    // SAFETY: valid device and info.
    out.pool = unsafe { d.create_descriptor_pool(&info, None) }.ctx("vkCreateDescriptorPool")?;
    let layouts: Vec<vk::DescriptorSetLayout> =
        sets.iter().map(|s| out.built[s.built].set_layout).collect();
    let info = vk::DescriptorSetAllocateInfo::default()
        .descriptor_pool(out.pool)
        .set_layouts(&layouts);
    // SAFETY: the pool was sized for these sets.
    let allocated = unsafe { d.allocate_descriptor_sets(&info) }.ctx("vkAllocateDescriptorSets")?;

    let mut next_dispatch: BTreeMap<usize, usize> = BTreeMap::new();
    for ((s, &set), &off) in sets.iter().zip(&allocated).zip(&offsets) {
        let built = &mut out.built[s.built];
        let p = built.p;
        let pass_name = &g.passes[p].name;
        let mut buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = Vec::new();
        let mut image_infos: Vec<[vk::DescriptorImageInfo; 1]> = Vec::new();
        let mut plan_writes: Vec<(u32, vk::DescriptorType, bool, usize)> = Vec::new();
        for &(binding, ty) in &descriptor_types[s.built] {
            if binding == 0 {
                buffer_infos.push([vk::DescriptorBufferInfo {
                    buffer: uniforms.buffer,
                    offset: off,
                    range: (s.params.len() as u64 * 4).max(16),
                }]);
                plan_writes.push((0, ty, true, buffer_infos.len() - 1));
                continue;
            }
            let Some(&r) = s.bound.get(binding as usize - 1) else {
                return Err(AshError::Pass {
                    pass: pass_name.clone(),
                    message: format!(
                        "the shader uses binding {binding}, beyond the pass's bindings"
                    ),
                });
            };
            match (&memory.res[r], ty) {
                (
                    Some(Res::Buffer { buffer, .. }),
                    vk::DescriptorType::STORAGE_BUFFER | vk::DescriptorType::UNIFORM_BUFFER,
                ) => {
                    buffer_infos.push([vk::DescriptorBufferInfo {
                        buffer: *buffer,
                        offset: 0,
                        range: vk::WHOLE_SIZE,
                    }]);
                    plan_writes.push((binding, ty, true, buffer_infos.len() - 1));
                }
                (
                    Some(Res::Image { view, .. }),
                    vk::DescriptorType::SAMPLED_IMAGE | vk::DescriptorType::STORAGE_IMAGE,
                ) => {
                    let layout = if ty == vk::DescriptorType::STORAGE_IMAGE {
                        vk::ImageLayout::GENERAL
                    } else {
                        sync.layout_in
                            .get(&(p, r))
                            .copied()
                            .unwrap_or(vk::ImageLayout::GENERAL)
                    };
                    image_infos.push([vk::DescriptorImageInfo {
                        sampler: vk::Sampler::null(),
                        image_view: *view,
                        image_layout: layout,
                    }]);
                    plan_writes.push((binding, ty, false, image_infos.len() - 1));
                }
                _ => {
                    return Err(AshError::Pass {
                        pass: pass_name.clone(),
                        message: format!(
                            "binding {binding} ({ty:?}) cannot take `{}`",
                            g.resources[r].name
                        ),
                    });
                }
            }
        }
        let writes: Vec<vk::WriteDescriptorSet<'_>> = plan_writes
            .iter()
            .map(|&(binding, ty, is_buffer, i)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(ty);
                if is_buffer {
                    w.buffer_info(&buffer_infos[i])
                } else {
                    w.image_info(&image_infos[i])
                }
            })
            .collect();
        // SAFETY: every info outlives the call; the set is not in use.
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        match &mut built.work {
            Work::Compute { dispatches, .. } => {
                let i = next_dispatch.entry(s.built).or_default();
                dispatches[*i].0 = set;
                *i += 1;
            }
            Work::Raster { set: slot, .. } => *slot = set,
        }
    }
    out.uniforms = Some(uniforms);
    Ok(())
}
