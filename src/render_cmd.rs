//! `strandgraph render`: run a scene's graph on a backend and write images.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::PathBuf;
use std::time::Instant;
use strandgraph::frame::{override_param, parse_size, prepare};
use strandgraph::images::to_picture;
use strandgraph_cpu::{CpuBackend, PassTiming};
use strandgraph_graph::Plan;

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    Cpu,
    Wgpu,
    Ash,
    All,
}

#[derive(clap::Args)]
pub struct Args {
    /// The scene (RON), e.g. scenes/showcase.ron.
    pub scene: PathBuf,
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
    /// Where to write the main image (PNG); other image outputs go beside it.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Run this graph instead of the scene's (A/B-test pipelines on one scene).
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// Override the resolution, as WxH.
    #[arg(long)]
    pub size: Option<String>,
    /// Count lane utilisation, atomics and pixels written per pass.
    #[arg(long)]
    pub instrument: bool,
    /// Emulated subgroup width of the CPU backend.
    #[arg(long, default_value_t = 32)]
    pub subgroup: u32,
    /// Give every transient its own memory instead of the plan's aliasing.
    #[arg(long)]
    pub no_alias: bool,
    /// Override a pass parameter, as PASS.PARAM=VALUE (repeatable), e.g.
    /// `--param raster.loop_flattening=false`.
    #[arg(long = "param", value_name = "PASS.PARAM=VALUE")]
    pub params: Vec<String>,
}

pub fn run(args: Args) -> Result<()> {
    if args.backend != Backend::Cpu {
        return Err(miette::miette!(
            "only the cpu backend is built so far; wgpu and ash arrive with their issues"
        ));
    }
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let t0 = Instant::now();
    let mut p = prepare(&args.scene, args.graph.as_deref(), size)?;
    for spec in &args.params {
        override_param(&mut p.plan, spec)?;
    }
    let q = p.upload.quantities;
    println!(
        "scene {}: {} models, {} strands, {} segments, {}x{}; graph `{}`; prepared in {:.0} ms",
        args.scene.display(),
        q.models,
        q.strands,
        q.segments,
        q.width,
        q.height,
        p.plan.graph.name,
        t0.elapsed().as_secs_f64() * 1e3
    );
    let backend = CpuBackend {
        subgroup_width: args.subgroup.clamp(1, 64),
        instrument: args.instrument,
        alias: !args.no_alias,
        ..CpuBackend::default()
    };
    let t1 = Instant::now();
    let frame = backend
        .execute(&p.plan, &p.instance, &p.upload)
        .into_diagnostic()?;
    let wall = t1.elapsed().as_secs_f64() * 1e3;
    print_timings(&p.plan, &frame.timings, args.instrument);
    println!(
        "cpu backend: frame {wall:.1} ms wall ({} queues on threads, subgroup width {}), transient arena {:.1} MiB ({})",
        p.plan.lanes.len(),
        backend.subgroup_width,
        frame.memory.arena_bytes as f64 / (1 << 20) as f64,
        if backend.alias {
            "aliased"
        } else {
            "not aliased"
        }
    );
    let oob = frame
        .memory
        .out_of_bounds
        .load(std::sync::atomic::Ordering::Relaxed);
    if oob > 0 {
        tracing::warn!(oob, "kernels accessed memory out of range");
    }

    let main = args.output.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "{}.png",
            args.scene
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("render")
        ))
    });
    let mut wrote_main = false;
    for &(r, _) in &p.plan.graph.outputs {
        let name = p.plan.graph.resources[r].name.clone();
        let Some(words) = frame.read(&p.plan, &name) else {
            continue;
        };
        let Some(img) = to_picture(&p.plan, r, &words, q.width, q.height) else {
            continue;
        };
        let path = if wrote_main {
            main.with_extension(format!("{}.png", name.replace('.', "_")))
        } else {
            main.clone()
        };
        img.save(&path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        println!("wrote {} ({name})", path.display());
        wrote_main = true;
    }
    if !wrote_main {
        return Err(miette::miette!(
            "graph `{}` has no image output to write",
            p.plan.graph.name
        ));
    }
    Ok(())
}

fn print_timings(plan: &Plan, timings: &[PassTiming], instrument: bool) {
    print!(
        "\n  {:<14} {:<16} {:<24} {:>9} {:>10}",
        "queue", "pass", "kind", "groups", "ms"
    );
    if instrument {
        print!(" {:>8} {:>12} {:>12}", "lanes", "atomics", "pixels");
    }
    println!();
    for t in timings {
        let kind = &plan.graph.passes[t.pass].kind;
        print!(
            "  {:<14} {:<16} {:<24} {:>9} {:>10.2}",
            t.queue.to_string(),
            t.name,
            kind,
            t.workgroups,
            t.millis
        );
        if instrument {
            let c = &t.counters;
            let lanes = c
                .lane_utilisation()
                .map_or("-".to_string(), |u| format!("{:.1}%", 100.0 * u));
            print!(" {lanes:>8} {:>12} {:>12}", c.atomics, c.pixels_written);
        }
        println!();
    }
    for lane in &plan.lanes {
        let sum: f64 = timings
            .iter()
            .filter(|t| t.queue == lane.queue)
            .map(|t| t.millis)
            .sum();
        println!("  {:<14} total {sum:.2} ms", lane.queue.to_string());
    }
}
