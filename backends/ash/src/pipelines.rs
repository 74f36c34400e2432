//! Shader modules, pipeline layouts and pipelines of every pass, built once
//! per session. Compute passes are compute pipelines with one dispatch per
//! descriptor set; raster passes (raster.rs) are one graphics pipeline per
//! `Draw` of their `RasterState`, as on wgpu. Descriptor sets and parameter
//! blocks are descriptors.rs.

use crate::barriers::SyncPlan;
use crate::descriptors::{SetPlan, Sets, fill_sets};
use crate::device::Gpu;
use crate::error::{AshError, VkContext};
use crate::memory::{Memory, Res};
use crate::owned::Owned;
use crate::prepare::Prepared;
use crate::raster::raster_work;
use crate::spirv::{Spirv, translate};
use ash::vk;
use strandgraph_graph::resolve::PassId;
use strandgraph_graph::{Instance, Plan};
use strandgraph_passes::Dispatch;
use strandgraph_passes::raster_state::{Geometry, RasterState};

/// How a compute dispatch gets its workgroup count.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Launch {
    Direct(u32),
    /// Resource id and byte offset of the `[x, y, z]` arguments.
    Indirect(usize, u64),
}

pub(crate) enum Work {
    Compute {
        pipeline: Owned<vk::Pipeline>,
        /// Descriptor sets are filled in once every pass is built.
        dispatches: Vec<(vk::DescriptorSet, Launch)>,
    },
    Raster {
        pipelines: Vec<Owned<vk::Pipeline>>,
        set: vk::DescriptorSet,
        /// Physical resource ids of the colour attachments and the depth one.
        color: Vec<usize>,
        depth: Option<usize>,
        state: RasterState,
        call: DrawCall,
        extent: [u32; 2],
    },
}

/// How a raster pass's draws are issued ([`Geometry`]).
#[derive(Clone)]
pub(crate) enum DrawCall {
    Vertices(u32),
    /// The arguments' physical resource and byte offset.
    Indirect(usize, u64),
    /// Task workgroups, with VK_EXT_mesh_shader's commands.
    MeshTasks(u32, ash::ext::mesh_shader::Device),
}

/// One pass's pipelines and what they were made from. Fields drop in
/// order: pipelines before their layouts, layouts before the modules.
pub(crate) struct Built {
    pub p: PassId,
    pub work: Work,
    pub layout: Owned<vk::PipelineLayout>,
    pub set_layout: Owned<vk::DescriptorSetLayout>,
    _modules: Modules,
    /// `(binding, type)` the shader declares, for its descriptor sets.
    pub descriptors: Vec<(u32, vk::DescriptorType)>,
}

pub(crate) struct Pipelines {
    pub built: Vec<Built>,
    /// The descriptor pool (its sets go with it) and the parameter blocks
    /// the sets point into.
    _sets: Sets,
}

/// What building a pass needs of the session.
pub(crate) struct Context<'a> {
    pub gpu: &'a Gpu,
    pub plan: &'a Plan,
    pub instance: &'a Instance,
    pub memory: &'a Memory,
}

impl Context<'_> {
    /// An error naming pass `p`.
    pub fn pass_error(&self, p: PassId, message: String) -> AshError {
        AshError::Pass {
            pass: self.plan.graph.passes[p].name.clone(),
            message,
        }
    }
}

pub(crate) fn build(
    gpu: &Gpu,
    plan: &Plan,
    instance: &Instance,
    prepared: &[Prepared<'_>],
    memory: &Memory,
    sync: &SyncPlan,
) -> Result<Pipelines, AshError> {
    let cx = Context {
        gpu,
        plan,
        instance,
        memory,
    };
    let mut built = Vec::new();
    let mut sets = Vec::new();
    for prep in prepared {
        let (b, pass_sets) = build_pass(&cx, prep, built.len())?;
        built.push(b);
        sets.extend(pass_sets);
    }
    let sets = fill_sets(&cx, sync, &mut built, &sets)?;
    Ok(Pipelines { built, _sets: sets })
}

/// A NUL-terminated entry point name.
pub(crate) fn entry_name(
    cx: &Context<'_>,
    p: PassId,
    name: &str,
) -> Result<std::ffi::CString, AshError> {
    std::ffi::CString::new(name).map_err(|_| cx.pass_error(p, "entry name has a NUL".into()))
}

/// A pass's shader modules: one for every entry point (named ""), or one
/// per entry point.
pub(crate) struct Modules(Vec<(String, Owned<vk::ShaderModule>)>);

impl Modules {
    /// The module holding entry point `entry`.
    pub fn of(&self, entry: &str) -> vk::ShaderModule {
        let found = self.0.iter().find(|(e, _)| e.is_empty() || e == entry);
        found.map_or(vk::ShaderModule::null(), |(_, m)| m.raw())
    }
}

/// The shader modules, layouts and pipelines of one pass (the `index`-th
/// built), and the descriptor sets it needs.
fn build_pass(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    index: usize,
) -> Result<(Built, Vec<SetPlan>), AshError> {
    let gpu = cx.gpu;
    let d = &gpu.device;
    let pass = &cx.plan.graph.passes[prep.p];
    let mut entries = vec![prep.entry];
    if let Some(state) = &prep.raster {
        if let Geometry::MeshTasks { task, .. } = state.geometry {
            entries.push(task);
        }
        entries.extend(state.draws.iter().map(|d| d.fragment));
    }
    let mesh = matches!(&prep.raster, Some(s) if matches!(s.geometry, Geometry::MeshTasks { .. }));
    let spirv_of = |only: Option<&&str>| {
        let entries = only.map_or(&entries[..], std::slice::from_ref);
        translate(
            &prep.composed,
            entries,
            only.copied(),
            gpu.spirv_target(pass.loop_bounding),
            &pass.name,
            &gpu.name,
        )
    };
    // A mesh pipeline gets one module per stage, each holding only its
    // entry point, as wgpu-hal builds them; every other pass one module.
    // On the H100 (driver 580.159.04) one module holding the task, mesh and
    // fragment entry points passed spirv-val, but its first draw never
    // completed; the same stages as three modules render.
    let translated: Vec<(&str, Spirv)> = if mesh {
        let per_entry = entries.iter().map(|e| Ok((*e, spirv_of(Some(e))?)));
        per_entry.collect::<Result<_, AshError>>()?
    } else {
        // "": the module of every entry point.
        vec![("", spirv_of(None)?)]
    };
    let mut descriptors: Vec<(u32, vk::DescriptorType)> = translated
        .iter()
        .flat_map(|(_, s)| s.descriptors.iter().copied())
        .collect();
    descriptors.sort_by_key(|(b, _)| *b);
    descriptors.dedup_by_key(|(b, _)| *b);
    let modules = translated
        .iter()
        .map(|(entry, spirv)| {
            let info = vk::ShaderModuleCreateInfo::default().code(&spirv.words);
            // SAFETY: valid SPIR-V words from naga.
            let module = unsafe { d.create_shader_module(&info, None) }
                .ctx(&format!("pass `{}`: vkCreateShaderModule", pass.name))?;
            Ok((entry.to_string(), d.own(module)))
        })
        .collect::<Result<_, AshError>>()
        .map(Modules)?;
    let stage_flags = match &prep.raster {
        Some(_) if mesh => {
            vk::ShaderStageFlags::TASK_EXT
                | vk::ShaderStageFlags::MESH_EXT
                | vk::ShaderStageFlags::FRAGMENT
        }
        Some(_) => vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
        None => vk::ShaderStageFlags::COMPUTE,
    };
    let (set_layout, layout) = layouts(gpu, &descriptors, stage_flags)?;
    let (work, sets) = match &prep.raster {
        Some(state) => raster_work(cx, prep, state, &modules, layout.raw(), index)?,
        None => compute_work(cx, prep, modules.of(prep.entry), layout.raw(), index)?,
    };
    let built = Built {
        p: prep.p,
        work,
        layout,
        set_layout,
        _modules: modules,
        descriptors,
    };
    Ok((built, sets))
}

/// The descriptor set layout of the shader's bindings (`descriptors`),
/// visible to `stage_flags`, and a pipeline layout of that one set.
fn layouts(
    gpu: &Gpu,
    descriptors: &[(u32, vk::DescriptorType)],
    stage_flags: vk::ShaderStageFlags,
) -> Result<(Owned<vk::DescriptorSetLayout>, Owned<vk::PipelineLayout>), AshError> {
    let d = &gpu.device;
    let bindings: Vec<vk::DescriptorSetLayoutBinding<'_>> = descriptors
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
    let set_layout = d.own(
        unsafe { d.create_descriptor_set_layout(&info, None) }
            .ctx("vkCreateDescriptorSetLayout")?,
    );
    let set_layouts = [set_layout.raw()];
    let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    // SAFETY: valid device and info.
    let layout =
        d.own(unsafe { d.create_pipeline_layout(&info, None) }.ctx("vkCreatePipelineLayout")?);
    Ok((set_layout, layout))
}

/// A compute pass: its pipeline, and its dispatches with their sets.
fn compute_work(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    module: vk::ShaderModule,
    layout: vk::PipelineLayout,
    index: usize,
) -> Result<(Work, Vec<SetPlan>), AshError> {
    let d = &cx.gpu.device;
    let entry = entry_name(cx, prep.p, prep.entry)?;
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(&entry);
    let flags = if cx.gpu.stats.is_some() {
        vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
    } else {
        vk::PipelineCreateFlags::empty()
    };
    let info = vk::ComputePipelineCreateInfo::default()
        .flags(flags)
        .stage(stage)
        .layout(layout);
    // SAFETY: valid module and layout.
    let made = unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
    let pipeline = match made {
        Ok(p) => {
            if let Some(stats) = &cx.gpu.stats {
                stats.log(cx.plan.pass_name(prep.p), p[0]);
            }
            d.own(p[0])
        }
        Err((_, e)) => {
            let what = format!(
                "pass `{}`: vkCreateComputePipelines",
                cx.plan.pass_name(prep.p)
            );
            return Err(AshError::vk(what, e));
        }
    };
    let (launches, sets) = launches(cx, prep, index)?;
    let dispatches = launches
        .into_iter()
        .map(|l| (vk::DescriptorSet::null(), l))
        .collect();
    Ok((
        Work::Compute {
            pipeline,
            dispatches,
        },
        sets,
    ))
}

/// The dispatches of a compute pass and a descriptor set for each: one per
/// written resource (its size in words in the last parameter word) for a
/// pass without fixed bindings, else one by the pass's dispatch rule.
fn launches(
    cx: &Context<'_>,
    prep: &Prepared<'_>,
    index: usize,
) -> Result<(Vec<Launch>, Vec<SetPlan>), AshError> {
    let err = |m: String| cx.pass_error(prep.p, m);
    let max_groups = cx.gpu.props.limits.max_compute_work_group_count[0];
    let check_groups = |groups: u64| {
        u32::try_from(groups)
            .ok()
            .filter(|&n| n <= max_groups)
            .ok_or_else(|| {
                err(format!(
                    "{groups} workgroups exceed the device's {max_groups} per dimension"
                ))
            })
    };
    let words_of = |r: usize| cx.instance.sizes[r].bytes.div_ceil(4);
    let mut launches = Vec::new();
    let mut sets = Vec::new();
    if prep.def.bindings().is_none() {
        let Dispatch::CoverWrites { words_per_group } = prep.def.dispatch() else {
            return Err(err(
                "a pass without fixed bindings must dispatch CoverWrites".into(),
            ));
        };
        for (_, r, _) in &prep.bindings {
            let words = words_of(*r);
            let mut params = prep.params.clone();
            if let Some(last) = params.last_mut() {
                *last = u32::try_from(words).map_err(|_| err(format!("{words} words to clear")))?;
            }
            let groups = check_groups(Dispatch::cover_groups(words, words_per_group))?;
            launches.push(Launch::Direct(groups));
            sets.push(SetPlan {
                built: index,
                params,
                bound: vec![*r],
            });
        }
        return Ok((launches, sets));
    }
    let words = |name: &str| {
        let r = prep.bindings.iter().find(|(n, _, _)| n == name);
        r.map_or(0, |(_, r, _)| words_of(*r))
    };
    prep.def.check_binding_sizes(&words).map_err(err)?;
    let is_buffer = |r: usize| matches!(cx.memory.res[r], Some(Res::Buffer { .. }));
    let most = prep
        .bindings
        .iter()
        .filter(|(_, r, _)| is_buffer(*r))
        .map(|(_, r, _)| words_of(*r))
        .max()
        .unwrap_or(0);
    let dispatch = prep.def.dispatch();
    let launch = match (
        dispatch.direct_groups(&cx.instance.quantities, most),
        dispatch,
    ) {
        (Some(n), _) => Launch::Direct(check_groups(n)?),
        (None, Dispatch::Indirect { binding, word }) => {
            let r = prep
                .bindings
                .iter()
                .find(|(n, _, _)| n == binding)
                .map(|(_, r, _)| *r)
                .ok_or_else(|| err(format!("indirect `{binding}` is not bound")))?;
            Dispatch::check_indirect(binding, word, words_of(r)).map_err(err)?;
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
    Ok((launches, sets))
}
