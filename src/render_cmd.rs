//! `strandgraph render`: run a scene's graph on a backend and write images.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};
use std::time::Instant;
use strandgraph::frame::{Prepared, override_param, parse_size, prepare};
use strandgraph::images::to_picture;
use strandgraph_cpu::{CpuBackend, PassTiming};
use strandgraph_graph::Plan;
use strandgraph_wgpu::WgpuBackend;

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
    if args.backend == Backend::Ash {
        return Err(miette::miette!(
            "the ash backend is not built yet; use --backend cpu, wgpu or all"
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
    let main = args.output.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "{}.png",
            args.scene
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("render")
        ))
    });

    let cpu = if matches!(args.backend, Backend::Cpu | Backend::All) {
        Some(run_cpu(&args, &p, &main)?)
    } else {
        None
    };
    let gpu = if matches!(args.backend, Backend::Wgpu | Backend::All) {
        // With --backend all the CPU images keep the main name.
        let main = if cpu.is_some() {
            main.with_extension("wgpu.png")
        } else {
            main.clone()
        };
        Some(run_wgpu(&p, &main)?)
    } else {
        None
    };
    if let (Some(cpu), Some(gpu)) = (&cpu, &gpu) {
        print_side_by_side(&p.plan, cpu, gpu);
    }
    Ok(())
}

fn run_cpu(args: &Args, p: &Prepared, main: &Path) -> Result<Vec<PassTiming>> {
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
    write_outputs(p, main, |name| Ok(frame.read(&p.plan, name)))?;
    Ok(frame.timings)
}

fn run_wgpu(p: &Prepared, main: &Path) -> Result<Vec<strandgraph_wgpu::PassTiming>> {
    let t1 = Instant::now();
    let frame = WgpuBackend::default()
        .execute(&p.plan, &p.instance, &p.upload)
        .into_diagnostic()?;
    let wall = t1.elapsed().as_secs_f64() * 1e3;
    print!(
        "\n  {:<14} {:<16} {:<24} {:>9} {:>10}\n",
        "queue", "pass", "kind", "groups", "GPU ms"
    );
    for t in &frame.timings {
        println!(
            "  {:<14} {:<16} {:<24} {:>9} {:>10.3}",
            t.queue.to_string(),
            t.name,
            p.plan.graph.passes[t.pass].kind,
            t.workgroups,
            t.millis
        );
    }
    let total: f64 = frame.timings.iter().map(|t| t.millis).sum();
    println!("  one queue      total {total:.3} ms (per-pass GPU timestamps)");
    println!("wgpu backend: frame {wall:.1} ms wall, including device and pipeline creation");
    for note in &frame.notes {
        println!("  {note}");
    }
    write_outputs(p, main, |name| frame.read(&p.plan, name).into_diagnostic())?;
    Ok(frame.timings)
}

/// Writes every image output: the first to `main`, the others beside it.
fn write_outputs(
    p: &Prepared,
    main: &Path,
    read: impl Fn(&str) -> Result<Option<Vec<u32>>>,
) -> Result<()> {
    let q = p.upload.quantities;
    let mut wrote_main = false;
    for &(r, _) in &p.plan.graph.outputs {
        let name = p.plan.graph.resources[r].name.clone();
        let Some(words) = read(&name)? else {
            continue;
        };
        let Some(img) = to_picture(&p.plan, r, &words, q.width, q.height) else {
            continue;
        };
        let path = if wrote_main {
            main.with_extension(format!("{}.png", name.replace('.', "_")))
        } else {
            main.to_path_buf()
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

/// `--backend all`: per-pass times of both backends, in plan order.
fn print_side_by_side(plan: &Plan, cpu: &[PassTiming], gpu: &[strandgraph_wgpu::PassTiming]) {
    println!(
        "\n  {:<16} {:<24} {:>14} {:>14}",
        "pass", "kind", "cpu wall ms", "wgpu GPU ms"
    );
    for &pass in &plan.order {
        let c = cpu.iter().find(|t| t.pass == pass).map(|t| t.millis);
        let g = gpu.iter().find(|t| t.pass == pass).map(|t| t.millis);
        let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
        println!(
            "  {:<16} {:<24} {:>14} {:>14}",
            plan.pass_name(pass),
            plan.graph.passes[pass].kind,
            show(c),
            show(g)
        );
    }
    let sum = |v: &mut dyn Iterator<Item = f64>| v.sum::<f64>();
    println!(
        "  {:<16} {:<24} {:>14.3} {:>14.3}",
        "total",
        "",
        sum(&mut cpu.iter().map(|t| t.millis)),
        sum(&mut gpu.iter().map(|t| t.millis))
    );
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
