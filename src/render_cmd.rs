//! `strandgraph render`: run a scene's graph on a backend and write images.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};
use std::time::Instant;
use strandgraph::frame::{Prepared, parse_size, prepare_with};
use strandgraph::images::{depth_to_view, motion_image, to_linear, to_picture};
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
    /// Where to write the main image: PNG (sRGB), or linear EXR when the
    /// name ends in `.exr`; other image outputs go beside it.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the view depth (metres, EXR) of `scene.depth` here.
    #[arg(long, value_name = "FILE.exr")]
    pub depth: Option<PathBuf>,
    /// Also write the per-pixel motion (pixels, y down; EXR: R = x, G = y)
    /// of `pixel_motion` here. One frame has no previous one: run a
    /// session for motion that is not zero (tests/motion.rs does).
    #[arg(long, value_name = "FILE.exr")]
    pub motion: Option<PathBuf>,
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
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let t0 = Instant::now();
    // Overrides apply before packing and baking (a `"Baked"` override bakes).
    let p = prepare_with(&args.scene, args.graph.as_deref(), size, &args.params)?;
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
    // With several backends the CPU's files keep their names and the others
    // are tagged: showcase.png, showcase.wgpu.png, showcase.ash.png.
    let gpu = if matches!(args.backend, Backend::Wgpu | Backend::All) {
        let tag = cpu.is_some().then_some("wgpu");
        Some(run_wgpu(&p, &tagged(&main, tag), &Extras::of(&args, tag))?)
    } else {
        None
    };
    let ash = if matches!(args.backend, Backend::Ash | Backend::All) {
        let tag = (cpu.is_some() || gpu.is_some()).then_some("ash");
        Some(run_ash(
            &args,
            &p,
            &tagged(&main, tag),
            &Extras::of(&args, tag),
        )?)
    } else {
        None
    };
    if let (Some(cpu), Some(gpu), Some(ash)) = (&cpu, &gpu, &ash) {
        print_three_way(&p.plan, cpu, gpu, ash);
    } else if let (Some(cpu), Some(gpu)) = (&cpu, &gpu) {
        print_side_by_side(&p.plan, cpu, gpu);
    }
    Ok(())
}

/// The images written beside the main one, named for one backend.
struct Extras {
    depth: Option<PathBuf>,
    motion: Option<PathBuf>,
}

impl Extras {
    fn of(args: &Args, tag: Option<&str>) -> Self {
        Self {
            depth: args.depth.as_deref().map(|p| tagged(p, tag)),
            motion: args.motion.as_deref().map(|p| tagged(p, tag)),
        }
    }
}

/// `path` with `.tag` before its extension (`a.png` → `a.wgpu.png`).
fn tagged(path: &Path, tag: Option<&str>) -> PathBuf {
    match (tag, path.extension().and_then(|e| e.to_str())) {
        (Some(tag), Some(ext)) => path.with_extension(format!("{tag}.{ext}")),
        (Some(tag), None) => path.with_extension(tag),
        (None, _) => path.to_path_buf(),
    }
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
    write_outputs(p, main, &Extras::of(args, None), |name| {
        Ok(frame.read(&p.plan, name))
    })?;
    Ok(frame.timings)
}

fn run_wgpu(
    p: &Prepared,
    main: &Path,
    extras: &Extras,
) -> Result<Vec<strandgraph_wgpu::PassTiming>> {
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
    write_outputs(p, main, extras, |name| {
        frame.read(&p.plan, name).into_diagnostic()
    })?;
    Ok(frame.timings)
}

/// The ash backend: one frame on raw Vulkan (`STRANDGRAPH_VK_VALIDATION=1`
/// runs it under the Khronos validation layer, `STRANDGRAPH_VK_DEVICE`
/// picks a device by name).
fn run_ash(
    args: &Args,
    p: &Prepared,
    main: &Path,
    extras: &Extras,
) -> Result<Vec<strandgraph_ash::PassTiming>> {
    let backend = strandgraph_ash::AshBackend {
        alias: !args.no_alias,
        ..strandgraph_ash::AshBackend::default()
    };
    let t1 = Instant::now();
    let (session, frame) = backend
        .execute(&p.plan, &p.instance, &p.upload)
        .into_diagnostic()?;
    let wall = t1.elapsed().as_secs_f64() * 1e3;
    print!(
        "\n  {:<14} {:<16} {:<24} {:>6} {:>9} {:>10} {:>19}\n",
        "queue", "pass", "kind", "family", "groups", "GPU ms", "span ms"
    );
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for t in &frame.timings {
        println!(
            "  {:<14} {:<16} {:<24} {:>6} {:>9} {:>10} {:>19}",
            t.queue.to_string(),
            t.name,
            p.plan.graph.passes[t.pass].kind,
            t.family,
            t.workgroups.map_or("-".to_string(), |n| n.to_string()),
            show(t.millis),
            t.span
                .map_or("-".to_string(), |(a, b)| format!("{a:.3}..{b:.3}"))
        );
    }
    let total: f64 = frame.timings.iter().filter_map(|t| t.millis).sum();
    println!("  sum of passes {total:.3} ms (per-pass timestamps per queue)");
    println!("ash backend: frame {wall:.1} ms wall, including device and pipeline creation");
    for note in &session.notes {
        println!("  {note}");
    }
    write_outputs(p, main, extras, |name| session.read(name).into_diagnostic())?;
    Ok(frame.timings)
}

fn print_three_way(
    plan: &Plan,
    cpu: &[PassTiming],
    gpu: &[strandgraph_wgpu::PassTiming],
    ash: &[strandgraph_ash::PassTiming],
) {
    println!(
        "\n  {:<16} {:<24} {:>14} {:>14} {:>14}",
        "pass", "kind", "cpu wall ms", "wgpu GPU ms", "ash GPU ms"
    );
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for &pass in &plan.order {
        println!(
            "  {:<16} {:<24} {:>14} {:>14} {:>14}",
            plan.pass_name(pass),
            plan.graph.passes[pass].kind,
            show(cpu.iter().find(|t| t.pass == pass).map(|t| t.millis)),
            show(gpu.iter().find(|t| t.pass == pass).map(|t| t.millis)),
            show(ash.iter().find(|t| t.pass == pass).and_then(|t| t.millis)),
        );
    }
    println!(
        "  {:<16} {:<24} {:>14.3} {:>14.3} {:>14.3}",
        "total",
        "",
        cpu.iter().map(|t| t.millis).sum::<f64>(),
        gpu.iter().map(|t| t.millis).sum::<f64>(),
        ash.iter().filter_map(|t| t.millis).sum::<f64>()
    );
}

/// Writes every image output: the first to `main`, the others beside it;
/// and the view depth to `depth` (EXR) when asked.
/// The scene depth every graph keeps (all its versions share the memory, so
/// this reads the last one: with hair depth after `kulikov.compose`).
const DEPTH: &str = "scene.depth";
/// Per-pixel motion (kulikov.pixel_motion).
const MOTION: &str = "pixel_motion";

fn write_outputs(
    p: &Prepared,
    main: &Path,
    extras: &Extras,
    read: impl Fn(&str) -> Result<Option<Vec<u32>>>,
) -> Result<()> {
    let q = p.upload.quantities;
    let mut wrote_main = false;
    for &(r, _) in &p.plan.graph.outputs {
        let name = p.plan.graph.resources[r].name.clone();
        let Some(words) = read(&name)? else {
            continue;
        };
        // `-o NAME.exr`: linear float images; PNG (sRGB, 8 bit) otherwise.
        let exr = main
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        let ext = if exr { "exr" } else { "png" };
        let path = if wrote_main {
            main.with_extension(format!("{}.{ext}", name.replace('.', "_")))
        } else {
            main.to_path_buf()
        };
        let saved = match (exr, to_linear(&p.plan, r, &words, q.width, q.height)) {
            (true, Some(img)) => img.save(&path),
            _ => match to_picture(&p.plan, r, &words, q.width, q.height) {
                Some(img) if !exr => img.save(&path),
                Some(img) => img.save(path.with_extension("png")),
                None => continue,
            },
        };
        saved
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        println!("wrote {} ({name})", path.display());
        wrote_main = true;
    }
    if let Some(motion_path) = &extras.motion {
        let words = read(MOTION)?.ok_or_else(|| {
            miette::miette!("--motion: graph `{}` has no `{MOTION}`", p.plan.graph.name)
        })?;
        let img = motion_image(&words, q.width, q.height).ok_or_else(|| {
            miette::miette!("--motion: `{MOTION}` does not hold two floats per pixel")
        })?;
        img.save(motion_path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", motion_path.display()))?;
        println!(
            "wrote {} (motion in pixels, from {MOTION})",
            motion_path.display()
        );
    }
    if let Some(depth_path) = &extras.depth {
        let (near, far) = p
            .upload
            .frame
            .as_ref()
            .map_or((0.02, 500.0), |f| (f.near, f.far));
        let words = read(DEPTH)?.ok_or_else(|| {
            miette::miette!("--depth: graph `{}` has no `{DEPTH}`", p.plan.graph.name)
        })?;
        let img = depth_to_view(&words, near, far, q.width, q.height).ok_or_else(|| {
            miette::miette!("--depth: `{DEPTH}` is not a screen-sized depth image")
        })?;
        img.save(depth_path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", depth_path.display()))?;
        println!(
            "wrote {} (view depth in metres, from {DEPTH})",
            depth_path.display()
        );
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
