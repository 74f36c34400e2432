//! Raster passes: one graphics pipeline per `Draw` of the pass's
//! `RasterState` (dynamic rendering, no vertex buffers), as on wgpu.

use crate::descriptors::SetPlan;
use crate::error::AshError;
use crate::memory::Res;
use crate::owned::Owned;
use crate::pipelines::{Context, DrawCall, Modules, Work, entry_name};
use crate::prepare::Prepared;
use ash::vk;
use strandgraph_graph::schema::Usage;
use strandgraph_passes::raster_state::{Blend, Compare, Cull, Draw, Geometry, RasterState};

fn compare(c: Compare) -> vk::CompareOp {
    match c {
        Compare::Always => vk::CompareOp::ALWAYS,
        Compare::Less => vk::CompareOp::LESS,
        Compare::Equal => vk::CompareOp::EQUAL,
    }
}

/// The attachments of a raster pass: formats and the render area.
struct Attachments {
    color: Vec<usize>,
    depth: Option<usize>,
    color_formats: Vec<vk::Format>,
    depth_format: Option<vk::Format>,
    extent: [u32; 2],
    /// Every attachment's sample count, which the draws rasterize with.
    samples: vk::SampleCountFlags,
}

fn attachments(cx: &Context<'_>, prep: &Prepared<'_>) -> Result<Attachments, AshError> {
    let g = &cx.plan.graph;
    let of_usage = |usage: Usage| -> Vec<usize> {
        prep.bindings
            .iter()
            .filter(|(_, _, u)| *u == usage)
            .map(|(_, r, _)| *r)
            .collect()
    };
    let color = of_usage(Usage::Color);
    let depth = of_usage(Usage::Depth).first().copied();
    let format_of = |r: usize| match &cx.memory.res[r] {
        Some(Res::Image { format, extent, .. }) => Ok((*format, *extent)),
        _ => Err(cx.pass_error(
            prep.p,
            format!("attachment `{}` is not an image", g.resources[r].name),
        )),
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
        None => {
            return Err(cx.pass_error(prep.p, "a raster pass without attachments".into()));
        }
    };
    let mut counts = color
        .iter()
        .chain(&depth)
        .map(|&r| g.resources[r].decl.samples());
    let samples = counts.next().unwrap_or(1);
    if counts.any(|n| n != samples) {
        return Err(cx.pass_error(
            prep.p,
            "its attachments have different sample counts".into(),
        ));
    }
    Ok(Attachments {
        samples: vk::SampleCountFlags::from_raw(samples),
        color,
        depth,
        color_formats,
        depth_format,
        extent,
    })
}

/// A raster pass: its pipelines and its one descriptor set (every binding
/// but the attachments).
pub(crate) fn raster_work(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    state: &RasterState,
    modules: &Modules,
    layout: vk::PipelineLayout,
    index: usize,
) -> Result<(Work, Vec<SetPlan>), AshError> {
    let at = attachments(cx, prep)?;
    let pipelines = state
        .draws
        .iter()
        .map(|draw| graphics_pipeline(cx, prep, state, draw, &at, modules, layout))
        .collect::<Result<Vec<_>, _>>()?;
    let call = draw_call(cx, prep, state)?;
    let bound = prep
        .bindings
        .iter()
        .filter(|(_, _, u)| !matches!(u, Usage::Color | Usage::Depth))
        .map(|(_, r, _)| *r)
        .collect();
    let work = Work::Raster {
        pipelines,
        set: vk::DescriptorSet::null(),
        color: at.color,
        depth: at.depth,
        state: state.clone(),
        call,
        extent: at.extent,
    };
    let set = SetPlan {
        built: index,
        params: prep.params.clone(),
        bound,
    };
    Ok((work, vec![set]))
}

/// How the pass's geometry is drawn.
fn draw_call(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    state: &RasterState,
) -> Result<DrawCall, AshError> {
    let too_many = |what: &str, n: u64| cx.pass_error(prep.p, format!("{n} {what} are too many"));
    Ok(match state.geometry {
        Geometry::Vertices(n) => {
            DrawCall::Vertices(u32::try_from(n).map_err(|_| too_many("vertices", n))?)
        }
        Geometry::Indirect(i) => {
            let (_, r, _) = prep
                .bindings
                .iter()
                .find(|(n, _, _)| n == i.binding)
                .ok_or_else(|| {
                    cx.pass_error(prep.p, format!("indirect `{}` is not bound", i.binding))
                })?;
            DrawCall::Indirect(*r, i.word as u64 * 4)
        }
        Geometry::MeshTasks { groups, .. } => {
            let n = u32::try_from(groups).map_err(|_| too_many("task workgroups", groups))?;
            let max = cx.gpu.max_task_groups;
            if n > max {
                return Err(cx.pass_error(
                    prep.p,
                    format!(
                        "{n} task workgroups exceed the device's maxTaskWorkGroupCount[0] of {max}"
                    ),
                ));
            }
            let loader = cx.gpu.mesh.clone().ok_or_else(|| {
                cx.pass_error(
                    prep.p,
                    "draws with mesh shaders on a device without VK_EXT_mesh_shader enabled".into(),
                )
            })?;
            DrawCall::MeshTasks(n, loader)
        }
    })
}

/// Colour blending of one attachment for `draw`.
fn blend_attachment(draw: &Draw) -> vk::PipelineColorBlendAttachmentState {
    let mask = if draw.color_writes {
        vk::ColorComponentFlags::RGBA
    } else {
        vk::ColorComponentFlags::empty()
    };
    let a = vk::PipelineColorBlendAttachmentState::default().color_write_mask(mask);
    match draw.blend {
        Blend::Replace => a,
        // colour = src + (1 − src.a)·dst, alpha likewise.
        Blend::PremultipliedOver => a
            .blend_enable(true)
            .src_color_blend_factor(vk::BlendFactor::ONE)
            .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .color_blend_op(vk::BlendOp::ADD)
            .src_alpha_blend_factor(vk::BlendFactor::ONE)
            .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
            .alpha_blend_op(vk::BlendOp::ADD),
    }
}

/// The graphics pipeline of one draw: the pass's vertex entry and the
/// draw's fragment entry, its depth test and blending.
fn graphics_pipeline(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    state: &RasterState,
    draw: &Draw,
    at: &Attachments,
    modules: &Modules,
    layout: vk::PipelineLayout,
) -> Result<Owned<vk::Pipeline>, AshError> {
    let d = &cx.gpu.device;
    let first_name = entry_name(cx, prep.p, prep.entry)?;
    let fs_name = entry_name(cx, prep.p, draw.fragment)?;
    let task = match state.geometry {
        Geometry::MeshTasks { task, .. } => Some(entry_name(cx, prep.p, task)?),
        _ => None,
    };
    let stage = |flags, entry: &str, name| {
        vk::PipelineShaderStageCreateInfo::default()
            .stage(flags)
            .module(modules.of(entry))
            .name(name)
    };
    // Vertex and fragment, or task, mesh and fragment.
    let stages: Vec<vk::PipelineShaderStageCreateInfo<'_>> = match (&task, state.geometry) {
        (Some(task), Geometry::MeshTasks { task: t, .. }) => vec![
            stage(vk::ShaderStageFlags::TASK_EXT, t, task),
            stage(vk::ShaderStageFlags::MESH_EXT, prep.entry, &first_name),
            stage(vk::ShaderStageFlags::FRAGMENT, draw.fragment, &fs_name),
        ],
        _ => vec![
            stage(vk::ShaderStageFlags::VERTEX, prep.entry, &first_name),
            stage(vk::ShaderStageFlags::FRAGMENT, draw.fragment, &fs_name),
        ],
    };
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    // Counter-clockwise front faces as wgpu-hal maps them, with the same
    // negative-height viewport (record.rs).
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(match state.cull {
            Cull::None => vk::CullModeFlags::NONE,
            Cull::Back => vk::CullModeFlags::BACK,
            Cull::Front => vk::CullModeFlags::FRONT,
        })
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(at.samples);
    let depth_state = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(at.depth.is_some())
        .depth_write_enable(at.depth.is_some() && draw.depth_write)
        .depth_compare_op(compare(draw.depth_compare));
    let blends: Vec<vk::PipelineColorBlendAttachmentState> = at
        .color_formats
        .iter()
        .map(|_| blend_attachment(draw))
        .collect();
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(&at.color_formats)
        .depth_attachment_format(at.depth_format.unwrap_or(vk::Format::UNDEFINED));
    let mut info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth_state)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    // A mesh pipeline has no vertex input or input assembly.
    if task.is_none() {
        info = info
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly);
    }
    // SAFETY: every pointer in `info` lives on this stack frame.
    let made = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
    match made {
        Ok(p) => Ok(d.own(p[0])),
        Err((_, e)) => Err(AshError::vk(
            format!(
                "pass `{}`: vkCreateGraphicsPipelines",
                cx.plan.pass_name(prep.p)
            ),
            e,
        )),
    }
}
