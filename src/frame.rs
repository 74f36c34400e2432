//! One frame, prepared: the scene loaded and packed, the graph compiled and
//! instantiated for it.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::Path;
use strandgraph_assets::Scene;
use strandgraph_bake::BakeOutcome;
use strandgraph_graph::unroll::MODEL_INDEX;
use strandgraph_graph::{Instance, PassRegistry, Plan, Usage, compile_file};
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
    let (w, h) = size.unwrap_or(scene.desc.resolution);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(miette::miette!(
            "{}: resolution {w}x{h} is outside 1..=16384",
            scene_path.display()
        ));
    }
    let graph_path = graph.map_or_else(|| scene.graph.clone(), Path::to_path_buf);
    let mut plan = compile_file(&graph_path, &Registry, scene.grooms.len() as u32)?;
    for spec in overrides {
        override_param(&mut plan, spec)?;
    }
    let mut upload = upload(&scene, w, h);
    complete_upload(&plan, &scene, &mut upload)?;
    let instance = plan.instantiate(&upload.quantities)?;
    Ok(Prepared {
        scene,
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
    bake_shadows(plan, up)
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

/// Applies `PASS.PARAM=VALUE` (VALUE in RON: `false`, `64`, `"Baked"`) to a
/// compiled plan: how ablations run without editing the graph file.
pub fn override_param(plan: &mut Plan, spec: &str) -> Result<()> {
    let bad = || {
        miette::miette!(
            "--param {spec}: expected PASS.PARAM=VALUE, e.g. raster.loop_flattening=false"
        )
    };
    let (target, value) = spec.split_once('=').ok_or_else(bad)?;
    if let Some(image) = target.trim().strip_suffix(".samples")
        && plan.graph.resource_id(image).is_some()
    {
        return override_samples(plan, spec, image, value);
    }
    let (pass, param) = target.split_once('.').ok_or_else(bad)?;
    let value: ron::Value = ron::from_str(value.trim())
        .map_err(|e| miette::miette!("--param {spec}: value is not RON: {e}"))?;
    // `raster.x=…` sets every per-model copy (`raster[0]`, `raster[1]`, …).
    let pass = pass.trim();
    let targets: Vec<usize> = (0..plan.graph.passes.len())
        .filter(|&p| {
            let name = &plan.graph.passes[p].name;
            name == pass || strandgraph_graph::base_name(name) == pass
        })
        .collect();
    if targets.is_empty() {
        return Err(miette::miette!(
            "--param {spec}: graph `{}` has no pass `{pass}`",
            plan.graph.name
        ));
    }
    for p in targets {
        let pass = &mut plan.graph.passes[p];
        let mut params = match &pass.params {
            ron::Value::Map(m) => m.clone(),
            _ => ron::Map::new(),
        };
        params.insert(ron::Value::String(param.trim().to_string()), value.clone());
        check_override(&pass.name, &pass.kind, &params, param.trim())
            .map_err(|e| miette::miette!("--param {spec}: {e}"))?;
        pass.params = ron::Value::Map(params);
    }
    Ok(())
}

/// `IMAGE.samples=N`: an attachment's sample count (how a bench row runs
/// one graph at MSAA 1, 4 and 8), checked as the graph compiler checks it.
fn override_samples(plan: &mut Plan, spec: &str, image: &str, value: &str) -> Result<()> {
    use strandgraph_graph::schema::ResourceDecl;
    let n: u32 = value
        .trim()
        .parse()
        .map_err(|_| miette::miette!("--param {spec}: samples must be 1, 2, 4 or 8"))?;
    let g = &mut plan.graph;
    let r = g.physical(g.resource_id(image).expect("checked by the caller"));
    // The image and its versions (`a -> a.final`) share one declaration.
    for v in 0..g.resources.len() {
        if v != r && g.resources[v].version_of != Some(r) {
            continue;
        }
        let ResourceDecl::Image { samples, .. } = &mut g.resources[v].decl else {
            return Err(miette::miette!(
                "--param {spec}: `{image}` is a buffer, not an image"
            ));
        };
        *samples = n;
    }
    if let Some(why) = strandgraph_graph::resolve::samples_problem(&g.resources[r].decl) {
        return Err(miette::miette!("--param {spec}: image `{image}` {why}"));
    }
    let attachment_only = g
        .passes
        .iter()
        .flat_map(|p| &p.accesses)
        .all(|a| g.physical(a.resource) != r || matches!(a.usage, Usage::Color | Usage::Depth));
    if n > 1 && !attachment_only {
        return Err(miette::miette!(
            "--param {spec}: a pass uses `{image}` as more than an attachment, so it cannot be multisampled"
        ));
    }
    Ok(())
}

/// Checks a pass's parameters after an override as the graph compiler
/// checks the file's (unknown key with the closest valid one, type, range).
/// `model_index`, which unrolling adds to per-model passes, is the block's
/// to set, not the command line's.
fn check_override(
    pass: &str,
    kind: &str,
    params: &ron::Map,
    param: &str,
) -> std::result::Result<(), String> {
    if param == MODEL_INDEX {
        return Err(format!(
            "pass `{pass}`: `{param}` is set by the per-model block"
        ));
    }
    let mut written = params.clone();
    written.remove(&ron::Value::String(MODEL_INDEX.into()));
    Registry
        .check_params(kind, &ron::Value::Map(written))
        .map_err(|p| {
            let key = if p.key.is_empty() {
                "params".into()
            } else {
                format!("parameter `{}`", p.key)
            };
            format!("pass `{pass}` ({kind}): {key}: {}", p.message)
        })
}
