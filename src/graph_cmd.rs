//! `strandgraph graph`: compile a graph and print its plan.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::PathBuf;
use strandgraph_assets::{Scene, SceneCounts};
use strandgraph_graph::alias::Aliasing;
use strandgraph_graph::{Quantities, compile_file, export, report};
use strandgraph_passes::Registry;

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph graph scenes/graphs/kulikov.ron
  strandgraph graph scenes/graphs/lipp.ron --dot lipp.dot")]
pub struct Args {
    /// The graph file (RON), e.g. scenes/graphs/kulikov.ron. Defaults to the
    /// graph named by `--scene`.
    #[arg(required_unless_present = "scene")]
    pub file: Option<PathBuf>,
    /// Size resources for this scene's strands, vertices, meshes, lights and resolution.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Write the plan as Graphviz DOT to this file (`-` for stdout).
    #[arg(long)]
    pub dot: Option<PathBuf>,
    /// Write the plan and its memory plan as JSON to this file (`-` for stdout).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Size resources for these quantities instead of the built-in example,
    /// as `name=value` pairs: strands, vertices, segments, bundles, models,
    /// triangles, lights, width, height.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Which transients share bytes: first-fit or no-new-waits
    /// (docs/architecture.md, "Synchronisation").
    #[arg(long, default_value = "first-fit", value_parser = clap::value_parser!(Aliasing))]
    pub aliasing: Aliasing,
    /// Do not print the readable plan (useful with --dot/--json -).
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(args: Args) -> Result<()> {
    let scene = match &args.scene {
        Some(path) => Some(Scene::load(path).map_err(|e| miette::miette!("{e}"))?),
        None => None,
    };
    let file = match (&args.file, &scene) {
        (Some(file), _) => file.clone(),
        (None, Some(scene)) => scene.graph.clone(),
        (None, None) => return Err(miette::miette!("give a graph file or --scene")),
    };
    let base = scene
        .as_ref()
        .map_or_else(Quantities::example, |s| from_scene(s.counts()));
    let quantities = quantities(base, &args.set)?;
    let models = u32::try_from(quantities.models).unwrap_or(u32::MAX);
    let mut plan = compile_file(&file, &Registry, models)?;
    plan.aliasing = args.aliasing;
    let instance = plan.instantiate(&quantities)?;
    tracing::info!(
        passes = plan.order.len(),
        sync_points = plan.sync_points.len(),
        "compiled"
    );
    if !args.quiet {
        print!("{}", report::render(&plan, Some(&instance)));
    }
    if let Some(path) = &args.dot {
        write_out(path, &export::to_dot(&plan))?;
    }
    if let Some(path) = &args.json {
        write_out(path, &export::to_json(&plan, Some(&instance)))?;
    }
    Ok(())
}

fn write_out(path: &PathBuf, text: &str) -> Result<()> {
    if path.as_os_str() == "-" {
        print!("{text}");
        return Ok(());
    }
    std::fs::write(path, text)
        .into_diagnostic()
        .wrap_err_with(|| format!("writing {}", path.display()))
}

fn from_scene(c: SceneCounts) -> Quantities {
    Quantities {
        strands: c.strands,
        vertices: c.vertices,
        segments: c.segments,
        bundles: c.bundles,
        mesh_strands: c.mesh_strands,
        models: c.models,
        // Patches are built only when a graph draws them; estimated here
        // from the default PatchParams (a clump per 48 strands, 3 layers).
        patches: c.strands.div_ceil(48) * 3,
        triangles: c.triangles,
        lights: c.lights,
        width: c.width,
        height: c.height,
    }
}

fn quantities(mut q: Quantities, pairs: &[String]) -> Result<Quantities> {
    for pair in pairs {
        let (name, value) = pair
            .split_once('=')
            .ok_or_else(|| miette::miette!("--set {pair}: expected NAME=VALUE"))?;
        let v: u64 = value
            .trim()
            .parse()
            .map_err(|e| miette::miette!("--set {pair}: {e}"))?;
        let small = || u32::try_from(v).map_err(|_| miette::miette!("--set {pair}: too large"));
        match name.trim() {
            "strands" => q.strands = v,
            "vertices" => q.vertices = v,
            "segments" => q.segments = v,
            "bundles" => q.bundles = v,
            "mesh_strands" => q.mesh_strands = v,
            "models" => q.models = v,
            "patches" => q.patches = v,
            "triangles" => q.triangles = v,
            "lights" => q.lights = v,
            "width" => q.width = small()?,
            "height" => q.height = small()?,
            other => return Err(miette::miette!("--set {pair}: unknown quantity `{other}`")),
        }
    }
    Ok(q)
}
