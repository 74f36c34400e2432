//! One frame, prepared: the scene loaded and packed, the graph compiled and
//! instantiated for it.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::Path;
use strandgraph_assets::Scene;
use strandgraph_bake::BakeOutcome;
use strandgraph_graph::{Instance, Plan, compile_file};
use strandgraph_passes::Registry;
use strandgraph_passes::kulikov::shade::{SHADE, SelfShadow};
use strandgraph_passes::upload::{SHADOW_SH, Upload, bake_shadow_sh, upload};

pub struct Prepared {
    pub scene: Scene,
    pub upload: Upload,
    pub plan: Plan,
    pub instance: Instance,
}

/// Loads `scene_path`, packs it at `size` (default: the scene's resolution),
/// and compiles `graph` (default: the scene's graph).
pub fn prepare(
    scene_path: &Path,
    graph: Option<&Path>,
    size: Option<(u32, u32)>,
) -> Result<Prepared> {
    prepare_with(scene_path, graph, size, &[])
}

/// [`prepare`] with `--param` overrides ([`override_param`]) applied to the
/// compiled plan before the scene is packed and baked for it, so a bad
/// override fails at once and a `"Baked"` override bakes once.
pub fn prepare_with(
    scene_path: &Path,
    graph: Option<&Path>,
    size: Option<(u32, u32)>,
    overrides: &[String],
) -> Result<Prepared> {
    let scene = Scene::load(scene_path).map_err(|e| miette::miette!("{e}"))?;
    let size = size.unwrap_or(scene.desc.resolution);
    let graph_path = graph.map_or_else(|| scene.graph.clone(), Path::to_path_buf);
    let Planned {
        upload,
        plan,
        instance,
    } = plan_for(&scene, &graph_path, size, overrides)?;
    Ok(Prepared {
        scene,
        upload,
        plan,
        instance,
    })
}

/// A loaded scene's frame for one graph: [`Prepared`] without the scene.
pub struct Planned {
    pub upload: Upload,
    pub plan: Plan,
    pub instance: Instance,
}

/// Compiles `graph` for a loaded `scene` at `(w, h)`, applies `overrides`,
/// packs the scene for it and instantiates the plan: how the viewer opens
/// one graph after another on the scene it holds.
pub fn plan_for(
    scene: &Scene,
    graph: &Path,
    (w, h): (u32, u32),
    overrides: &[String],
) -> Result<Planned> {
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(miette::miette!(
            "{}: resolution {w}x{h} is outside 1..=16384",
            scene.path.display()
        ));
    }
    let mut plan = compile_file(graph, &Registry, scene.grooms.len() as u32)?;
    for spec in overrides {
        override_param(&mut plan, spec)?;
    }
    let mut upload = upload(scene, w, h);
    complete_upload(&plan, scene, &mut upload)?;
    let instance = plan.instantiate(&upload.quantities)?;
    Ok(Planned {
        upload,
        plan,
        instance,
    })
}

/// What `upload` leaves to the plan, because only some graphs need it and
/// it costs time: Scheuermann's hair patches ([`build_patches`]) and
/// Kulikov's baked self-shadowing ([`bake_shadows`]). Call it after
/// `--param` overrides, before instantiating the plan.
pub fn complete_upload(plan: &Plan, scene: &Scene, up: &mut Upload) -> Result<Option<BakeOutcome>> {
    build_patches(plan, scene, up);
    pack_simulation(plan, scene, up);
    bake_shadows(plan, up)
}

/// The simulation's inputs (`strandgraph_passes::sim::upload`), for a graph
/// that imports them: the grooms' head collision fields, baked here, and
/// their rest pose; and for a graph that simulates hair meshes, their
/// bundle chains (`sim::chains`). Does nothing when the upload already
/// holds them.
fn pack_simulation(plan: &Plan, scene: &Scene, up: &mut Upload) {
    use strandgraph_passes::sim::{chains, upload as sim};
    let imports = |name: &str| plan.graph.resource_id(name).is_some();
    if imports(sim::SDF) && !up.resources.contains_key(sim::SDF) {
        sim::pack(scene, up);
        if !imports(sim::REST) {
            up.resources.remove(sim::REST);
        }
    }
    if imports(chains::CHAINS) && !up.resources.contains_key(chains::CHAINS) {
        chains::pack(scene, up);
    }
}

/// Scheuermann's hair patches: built from the grooms (and the patch count
/// set) only for a graph that imports `patches.vertices`, since no other
/// pipeline draws them; likewise his shading inputs on the strands for a
/// graph that imports `scheuermann.strand_shading` (his ground truth). Does
/// nothing when the upload already holds them.
fn build_patches(plan: &Plan, scene: &Scene, up: &mut Upload) {
    use strandgraph_passes::scheuermann::upload::{
        STRAND_SHADING, VERTICES, pack, pack_strand_shading,
    };
    if plan.graph.resource_id(VERTICES).is_some() && !up.resources.contains_key(VERTICES) {
        pack(scene, up);
    }
    let wants = plan.graph.resource_id(STRAND_SHADING).is_some();
    if wants && !up.resources.contains_key(STRAND_SHADING) {
        pack_strand_shading(scene, up);
    }
}

/// Kulikov's precomputed self-shadowing: when a live `kulikov.shade` pass
/// reads `groom.shadow_sh` with `self_shadow: "Baked"`, bakes the SH with
/// that pass's bake settings, or loads it from the on-disk cache
/// (`strandgraph_bake::cache_dir`), so it runs once per groom. Nothing
/// reads it otherwise, and nothing is baked (the backends zero-fill it).
/// Does nothing when the upload already holds it; call it again after
/// [`override_param`] switches the shade pass to `"Baked"`.
pub fn bake_shadows(plan: &Plan, up: &mut Upload) -> Result<Option<BakeOutcome>> {
    let g = &plan.graph;
    let Some(r) = g.resource_id(SHADOW_SH) else {
        return Ok(None);
    };
    if up.resources.contains_key(SHADOW_SH) {
        return Ok(None);
    }
    for (p, pass) in g.passes.iter().enumerate() {
        let reads = pass.accesses.iter().any(|a| g.physical(a.resource) == r);
        if !plan.live[p] || !reads || pass.kind != "kulikov.shade" {
            continue;
        }
        let params = SHADE
            .params(&pass.params)
            .map_err(|e| miette::miette!("{e}"))?;
        if params.self_shadow != SelfShadow::Baked {
            continue;
        }
        let cache = strandgraph_bake::cache_dir();
        let outcome = bake_shadow_sh(up, &params.bake(), cache.as_deref())
            .map_err(|e| miette::miette!("pass `{}`: {e}", pass.name))?;
        return Ok(Some(outcome));
    }
    Ok(None)
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| miette::miette!("--size {s}: expected WxH, e.g. 1280x720"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .into_diagnostic()
            .wrap_err_with(|| format!("--size {s}"))
    };
    Ok((parse(w)?, parse(h)?))
}

/// Applies `PASS.PARAM=VALUE` (VALUE in RON: `false`, `64`, `"Baked"`) or
/// `IMAGE.samples=N` to a compiled plan: how ablations run without editing
/// the graph file ([`strandgraph_passes::params::override_param`]).
pub fn override_param(plan: &mut Plan, spec: &str) -> Result<()> {
    strandgraph_passes::params::override_param(plan, spec).map_err(|e| miette::miette!("{e}"))
}
