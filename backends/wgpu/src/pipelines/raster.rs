//! Raster passes: one render pipeline per draw over the same attachments,
//! and the translation of the pass's draw state into wgpu's.

use super::*;
use strandgraph_passes::raster_state::{
    Blend, ColorLoad, Compare, Cull, DepthLoad, Draw, Geometry,
};

/// Which of a raster pass's bindings are attachments, and which are bound.
struct Attachments {
    color: Vec<usize>,
    depth: Option<usize>,
    /// The bindings that are no attachment, bound from binding 1 on.
    bound: Vec<usize>,
    /// The attachments' sample count (the graph's `samples`).
    samples: u32,
}

impl Attachments {
    fn of(cx: &PassContext<'_>) -> Result<Self, WgpuError> {
        let prep = cx.prep;
        let attachment = |usage: Usage| {
            prep.attachments
                .iter()
                .filter(move |(_, u)| *u == usage)
                .map(|(b, _)| *b)
        };
        let samples: Vec<u32> = prep
            .attachments
            .iter()
            .map(|&(b, _)| cx.plan.graph.resources[prep.bindings[b].1].decl.samples())
            .collect();
        if samples.windows(2).any(|w| w[0] != w[1]) {
            return Err(cx.error("its attachments have different sample counts".into()));
        }
        Ok(Self {
            color: attachment(Usage::Color).collect(),
            depth: attachment(Usage::Depth).next(),
            bound: (0..prep.bindings.len())
                .filter(|b| !prep.attachments.iter().any(|(a, _)| a == b))
                .collect(),
            samples: samples.first().copied().unwrap_or(1),
        })
    }
}

pub(super) fn build_raster(cx: &PassContext<'_>, state: &RasterState) -> Result<Built, WgpuError> {
    let at = Attachments::of(cx)?;
    let params = cx.uniform(&cx.prep.params);
    let entries = cx.entries(&params, &at.bound)?;
    let mut draws = Vec::new();
    for d in &state.draws {
        let pipeline = render_pipeline(cx, state, d, &at)?;
        let bind_group = cx.bind_group(&pipeline.get_bind_group_layout(0), &entries);
        draws.push((pipeline, bind_group));
    }
    let call = match state.geometry {
        Geometry::Vertices(n) => DrawCall::Vertices(
            u32::try_from(n).map_err(|_| cx.error(format!("{n} vertices are too many")))?,
        ),
        Geometry::Indirect(i) => {
            let (_, r) = cx
                .prep
                .bindings
                .iter()
                .find(|(n, _)| n == i.binding)
                .ok_or_else(|| cx.error(format!("indirect `{}` is not bound", i.binding)))?;
            DrawCall::Indirect(*r, i.word as u64 * 4)
        }
        Geometry::MeshTasks { groups, .. } => DrawCall::MeshTasks(
            u32::try_from(groups)
                .map_err(|_| cx.error(format!("{groups} task workgroups are too many")))?,
        ),
    };
    Ok(Built::Raster {
        draws,
        color: at
            .color
            .iter()
            .map(|&b| attachment_view(cx, b))
            .collect::<Result<_, _>>()?,
        depth: at.depth.map(|b| attachment_view(cx, b)).transpose()?,
        state: Box::new(state.clone()),
        call,
    })
}

/// The pass's vertex entry and draw `d`'s fragment entry, writing the
/// attachments `at` as `d` says.
fn render_pipeline(
    cx: &PassContext<'_>,
    state: &RasterState,
    d: &Draw,
    at: &Attachments,
) -> Result<wgpu::RenderPipeline, WgpuError> {
    let targets: Vec<Option<wgpu::ColorTargetState>> = at
        .color
        .iter()
        .map(|&b| attachment_format(cx, b).map(|format| Some(color_target(format, d))))
        .collect::<Result<_, _>>()?;
    let depth_stencil = match at.depth {
        Some(b) => Some(depth_state(attachment_format(cx, b)?, d)),
        None => None,
    };
    let primitive = wgpu::PrimitiveState {
        topology: wgpu::PrimitiveTopology::TriangleList,
        front_face: wgpu::FrontFace::Ccw,
        cull_mode: match state.cull {
            Cull::None => None,
            Cull::Back => Some(wgpu::Face::Back),
            Cull::Front => Some(wgpu::Face::Front),
        },
        ..Default::default()
    };
    let multisample = wgpu::MultisampleState {
        count: at.samples,
        ..Default::default()
    };
    let fragment = Some(wgpu::FragmentState {
        module: &cx.module,
        entry_point: Some(d.fragment),
        compilation_options: Default::default(),
        targets: &targets,
    });
    if let Geometry::MeshTasks { task, .. } = state.geometry {
        return Ok(cx
            .device
            .create_mesh_pipeline(&wgpu::MeshPipelineDescriptor {
                label: Some(cx.name),
                layout: None,
                task: Some(wgpu::TaskState {
                    module: &cx.module,
                    entry_point: Some(task),
                    compilation_options: Default::default(),
                }),
                mesh: wgpu::MeshState {
                    module: &cx.module,
                    entry_point: Some(cx.prep.entry),
                    compilation_options: Default::default(),
                },
                primitive,
                depth_stencil,
                multisample,
                fragment,
                multiview: None,
                cache: None,
            }));
    }
    Ok(cx
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(cx.name),
            layout: None,
            vertex: wgpu::VertexState {
                module: &cx.module,
                entry_point: Some(cx.prep.entry),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive,
            depth_stencil,
            multisample,
            fragment,
            multiview_mask: None,
            cache: None,
        }))
}

fn attachment_format(cx: &PassContext<'_>, b: usize) -> Result<wgpu::TextureFormat, WgpuError> {
    match &cx.memory[cx.prep.bindings[b].1] {
        Some(Memory::Texture { format, .. }) => Ok(*format),
        _ => Err(cx.error(format!(
            "attachment `{}` is not an image",
            cx.prep.bindings[b].0
        ))),
    }
}

fn attachment_view(cx: &PassContext<'_>, b: usize) -> Result<wgpu::TextureView, WgpuError> {
    cx.views[b]
        .clone()
        .ok_or_else(|| cx.error(format!("`{}` has no view", cx.prep.bindings[b].0)))
}

fn color_target(format: wgpu::TextureFormat, d: &Draw) -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format,
        blend: blend(d.blend),
        write_mask: if d.color_writes {
            wgpu::ColorWrites::ALL
        } else {
            wgpu::ColorWrites::empty()
        },
    }
}

fn depth_state(format: wgpu::TextureFormat, d: &Draw) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(d.depth_write),
        depth_compare: Some(compare(d.depth_compare)),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

fn compare(c: Compare) -> wgpu::CompareFunction {
    match c {
        Compare::Always => wgpu::CompareFunction::Always,
        Compare::Less => wgpu::CompareFunction::Less,
        Compare::Equal => wgpu::CompareFunction::Equal,
    }
}

fn blend(b: Blend) -> Option<wgpu::BlendState> {
    match b {
        Blend::Replace => None,
        Blend::PremultipliedOver => Some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
        }),
    }
}

pub(crate) fn color_op(c: ColorLoad) -> wgpu::LoadOp<wgpu::Color> {
    match c {
        ColorLoad::Load => wgpu::LoadOp::Load,
        ColorLoad::Clear([r, g, b, a]) => wgpu::LoadOp::Clear(wgpu::Color {
            r: r.into(),
            g: g.into(),
            b: b.into(),
            a: a.into(),
        }),
    }
}

pub(crate) fn depth_op(d: DepthLoad) -> wgpu::LoadOp<f32> {
    match d {
        DepthLoad::Load => wgpu::LoadOp::Load,
        DepthLoad::Clear(v) => wgpu::LoadOp::Clear(v),
    }
}
