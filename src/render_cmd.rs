//! `strandgraph render`: run a scene's graph on a backend and write images.

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};
use std::time::Instant;
use strandgraph::demo::Demo;
use strandgraph::frame::{Prepared, parse_size, prepare_with};
use strandgraph::images::{
    Display, Tonemap, coverage, depth_to_view, motion_image, to_linear, to_picture,
};
use strandgraph::runner::{self, Barriers, LoopCounters, OpenOptions, PassTime, frame_millis};
use strandgraph_graph::Plan;
use strandgraph_graph::alias::Aliasing;
use strandgraph_passes::backend::Clock;

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    Cpu,
    Wgpu,
    Ash,
    All,
}

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph render scenes/showcase.ron -o showcase.png
  strandgraph render --demo --size 480x270 -o demo.png            # no checkout needed
  strandgraph render scenes/showcase.ron --graph scenes/graphs/lipp.ron --backend all
  strandgraph render scenes/animated.ron --frames 90 --fps 30 -o turn/   # a sequence (+ MP4 with ffmpeg)")]
pub struct Args {
    /// The scene (RON), e.g. scenes/showcase.ron.
    #[arg(required_unless_present = "demo")]
    pub scene: Option<PathBuf>,
    /// Render the built-in showcase (the scene and its Kulikov graph are in
    /// the binary), from any directory.
    #[arg(long, conflicts_with = "scene")]
    pub demo: bool,
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
    /// Where to write the main image: PNG (sRGB), or linear EXR when the
    /// name ends in `.exr`; other image outputs go beside it. With
    /// `--frames` above 1, a directory for the sequence.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Render this many frames of the scene's animation (hair simulated
    /// frame to frame) as `frame_NNNN.png` into the `-o` directory, and an
    /// MP4 beside them where ffmpeg is installed.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Frames per second of the sequence (the simulation's time step).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f32,
    /// Also write the view depth (metres, EXR) of `scene.depth` here.
    #[arg(long, value_name = "FILE.exr")]
    pub depth: Option<PathBuf>,
    /// Also write the per-pixel motion (pixels, y down; EXR: R = x, G = y)
    /// of `pixel_motion` here. One frame has no previous one: run a
    /// session for motion that is not zero (tests/motion.rs does).
    #[arg(long, value_name = "FILE.exr")]
    pub motion: Option<PathBuf>,
    /// Also write the hair's coverage under the main image (its alpha, a
    /// matte: 0 where no hair, 1 under opaque hair) here, as a 16-bit PNG.
    #[arg(long, value_name = "FILE.png")]
    pub coverage: Option<PathBuf>,
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
    /// Which passes' GPU shaders get naga's loop counters: graph (those
    /// whose graph keeps them), every or none (docs/architecture.md,
    /// "Shaders").
    #[arg(long, default_value = "graph", value_parser = clap::value_parser!(LoopCounters))]
    pub loop_counters: LoopCounters,
    /// How ash separates a queue's passes with pipeline barriers: levels
    /// (passes that wait for none of each other between one barrier and
    /// the next) or per-pass (docs/architecture.md, "Synchronisation").
    #[arg(long, default_value = "levels", value_parser = clap::value_parser!(Barriers))]
    pub barriers: Barriers,
    /// Which transients share bytes: first-fit (any whose lifetimes do not
    /// overlap) or no-new-waits (only where the data flow already orders
    /// them; docs/architecture.md, "Synchronisation").
    #[arg(long, default_value = "first-fit", value_parser = clap::value_parser!(Aliasing))]
    pub aliasing: Aliasing,
    /// The display transform of PNG outputs (EXR stays scene-linear).
    #[arg(long, value_enum, default_value = "aces")]
    pub tonemap: Tonemap,
    /// Exposure in stops, applied before the tone mapper.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Override a pass parameter, as PASS.PARAM=VALUE (repeatable), e.g.
    /// `--param raster.loop_flattening=false`.
    #[arg(long = "param", value_name = "PASS.PARAM=VALUE")]
    pub params: Vec<String>,
}

pub fn run(args: Args) -> Result<()> {
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let t0 = Instant::now();
    let demo = args.demo.then(Demo::write).transpose()?;
    let scene = match (&demo, &args.scene) {
        (Some(d), _) => d.scene.clone(),
        (None, Some(s)) => s.clone(),
        (None, None) => miette::bail!("name a scene, or pass --demo"),
    };
    // Overrides apply before packing and baking (a `"Baked"` override bakes).
    if !(args.fps > 0.0 && args.fps <= 1000.0) {
        miette::bail!("--fps {}: expected a rate in (0, 1000]", args.fps);
    }
    let mut p = prepare_with(&scene, args.graph.as_deref(), size, &args.params)?;
    if args.aliasing != p.plan.aliasing {
        p.plan.aliasing = args.aliasing;
        p.instance = p.plan.instantiate(&p.upload.quantities)?;
    }
    let q = p.upload.quantities;
    println!(
        "scene {}: {} models, {} strands, {} segments, {}x{}; graph `{}`; prepared in {:.0} ms",
        if args.demo {
            "--demo (the built-in showcase)".to_string()
        } else {
            scene.display().to_string()
        },
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
            scene
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("render")
        ))
    });

    let chosen: &[runner::Backend] = match args.backend {
        Backend::Cpu => &[runner::Backend::Cpu],
        Backend::Wgpu => &[runner::Backend::Wgpu],
        Backend::Ash => &[runner::Backend::Ash],
        Backend::All => &runner::Backend::ALL,
    };
    let options = OpenOptions {
        subgroup_width: args.subgroup,
        instrument: args.instrument,
        alias: !args.no_alias,
        loop_counters: args.loop_counters,
        barriers: args.barriers,
    };
    let mut all = Vec::new();
    for (i, &backend) in chosen.iter().enumerate() {
        // With several backends the first one's files keep their names and
        // the others are tagged: showcase.png, showcase.wgpu.png, …
        let tag = (i > 0).then_some(backend.name());
        let t1 = Instant::now();
        let mut session = runner::open(backend, &p.plan, &p.instance, options)?;
        if args.frames > 1 {
            let dir = args
                .output
                .clone()
                .unwrap_or_else(|| main.with_extension(""));
            sequence(&mut p, session.as_mut(), &args, &dir, tag)?;
            continue;
        }
        let times = session.run(&p.upload)?;
        let wall = t1.elapsed().as_secs_f64() * 1e3;
        runner::check_frame(&p.plan, &p.instance, session.as_ref())?;
        print_timings(&p.plan, &times, args.instrument);
        println!(
            "{} backend: frame {wall:.1} ms wall, including device and pipeline creation; {}",
            backend.name(),
            session.device()
        );
        for note in session.notes() {
            println!("  {note}");
        }
        write_outputs(&p, &tagged(&main, tag), &Extras::of(&args, tag), |name| {
            Ok(session.read(name)?)
        })?;
        all.push((backend, times));
    }
    if all.len() > 1 {
        print_side_by_side(&p.plan, &all);
    }
    Ok(())
}

/// `--frames N`: the animation frame by frame through one session, each
/// frame's images into `dir` (`frame_0000.png`, tagged per backend), then an
/// MP4 of them where ffmpeg is installed.
fn sequence(
    p: &mut Prepared,
    session: &mut dyn runner::Session,
    args: &Args,
    dir: &Path,
    tag: Option<&str>,
) -> Result<()> {
    std::fs::create_dir_all(dir)
        .into_diagnostic()
        .wrap_err_with(|| format!("creating {}", dir.display()))?;
    let bar = indicatif::ProgressBar::new(u64::from(args.frames));
    let extras = Extras {
        depth: None,
        motion: None,
        coverage: None,
        quiet: true,
        ..Extras::of(args, tag)
    };
    let name = |k: u32| tagged(&dir.join(format!("frame_{k:04}.png")), tag);
    let mut frames = Vec::new();
    for k in 0..args.frames {
        let up = strandgraph::sequence::frame_upload(p, k, args.fps)?;
        let times = session.run(&up)?;
        bar.suspend(|| write_outputs(p, &name(k), &extras, |n| Ok(session.read(n)?)))?;
        frames.push(times);
        bar.inc(1);
    }
    bar.finish_and_clear();
    // Per pass, the median over the frames after the first (which starts
    // the simulation and carries no motion).
    let moving = &frames[1..];
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied()
    };
    let mut medians = frames[frames.len() - 1].clone();
    for (i, t) in medians.iter_mut().enumerate() {
        t.millis = median(moving.iter().filter_map(|f| f[i].millis).collect());
        t.span = None;
    }
    print_timings(&p.plan, &medians, false);
    let totals = moving.iter().map(|f| frame_millis(f)).collect();
    println!(
        "{} backend: {} frames into {}, median frame {:.3} ms ({})",
        session.backend(),
        args.frames,
        dir.display(),
        median(totals).unwrap_or(f64::NAN),
        session.device()
    );
    encode_mp4(dir, tag, args.fps);
    Ok(())
}

/// `dir/sequence.mp4` (tagged) from its frames with ffmpeg, when installed.
fn encode_mp4(dir: &Path, tag: Option<&str>, fps: f32) {
    let pattern = tagged(&dir.join("frame_%04d.png"), tag);
    let out = tagged(&dir.join("sequence.mp4"), tag);
    let status = std::process::Command::new("ffmpeg")
        .args([
            "-loglevel",
            "error",
            "-y",
            "-framerate",
            &fps.to_string(),
            "-i",
        ])
        .arg(&pattern)
        .args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18"])
        .arg(&out)
        .status();
    match status {
        Ok(s) if s.success() => println!("wrote {}", out.display()),
        Ok(s) => println!(
            "ffmpeg failed ({s}): no MP4, the frames are in {}",
            dir.display()
        ),
        Err(_) => println!(
            "ffmpeg not found: no MP4, the frames are in {}",
            dir.display()
        ),
    }
}

/// The images written beside the main one, named for one backend.
struct Extras {
    depth: Option<PathBuf>,
    motion: Option<PathBuf>,
    coverage: Option<PathBuf>,
    display: Display,
    /// Say nothing per file (a sequence's frames).
    quiet: bool,
}

impl Extras {
    fn of(args: &Args, tag: Option<&str>) -> Self {
        Self {
            depth: args.depth.as_deref().map(|p| tagged(p, tag)),
            motion: args.motion.as_deref().map(|p| tagged(p, tag)),
            coverage: args.coverage.as_deref().map(|p| tagged(p, tag)),
            display: Display {
                tonemap: args.tonemap,
                exposure: args.exposure,
            },
            quiet: false,
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

/// Writes every image output: the first to `main`, the others beside it;
/// and the view depth to `depth` (EXR) when asked.
/// Depth images, first found wins: hair over the scene (`kulikov.compose`
/// writes it), else the scene depth every graph keeps (all its versions
/// share the memory, so this reads the last one).
const DEPTHS: [&str; 2] = ["hair_depth", "scene.depth"];
/// Per-pixel motion (kulikov.compose).
const MOTION: &str = "pixel_motion";

/// The main image's alpha (the hair's coverage) as a 16-bit grey PNG.
fn write_coverage(p: &Prepared, r: usize, words: &[u32], path: &Path) -> Result<()> {
    let q = p.upload.quantities;
    let alpha = coverage(&p.plan, r, words, q.width, q.height).ok_or_else(|| {
        miette::miette!("--coverage: the main image has no alpha (not Rgba16Float)")
    })?;
    let grey: Vec<u16> = alpha
        .iter()
        .map(|a| (a.clamp(0.0, 1.0) * 65535.0).round() as u16)
        .collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(q.width, q.height, grey)
        .expect("one value per pixel")
        .save(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("writing {}", path.display()))?;
    println!("wrote {} (hair coverage)", path.display());
    Ok(())
}

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
        // The float image only for EXR: at 16384x16384 it is 4 GiB.
        let linear = exr
            .then(|| to_linear(&p.plan, r, &words, q.width, q.height))
            .flatten();
        let saved = match (exr, linear) {
            (true, Some(img)) => img.save(&path),
            _ => match to_picture(&p.plan, r, &words, q.width, q.height, extras.display) {
                Some(img) if !exr => img.save(&path),
                Some(img) => img.save(path.with_extension("png")),
                None => continue,
            },
        };
        saved
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        if !extras.quiet {
            println!("wrote {} ({name})", path.display());
        }
        if let (false, Some(matte)) = (wrote_main, &extras.coverage) {
            write_coverage(p, r, &words, matte)?;
        }
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
        let mut found = None;
        for name in DEPTHS {
            if let Some(words) = read(name)? {
                found = Some((name, words));
                break;
            }
        }
        let (name, words) = found.ok_or_else(|| {
            miette::miette!(
                "--depth: graph `{}` has none of {DEPTHS:?}",
                p.plan.graph.name
            )
        })?;
        let img = depth_to_view(&words, near, far, q.width, q.height).ok_or_else(|| {
            miette::miette!("--depth: `{name}` is not a screen-sized depth image")
        })?;
        img.save(depth_path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", depth_path.display()))?;
        println!(
            "wrote {} (view depth in metres, from {name})",
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

/// `--backend all`: per-pass times of every backend, in plan order.
fn print_side_by_side(plan: &Plan, all: &[(runner::Backend, Vec<PassTime>)]) {
    print!("\n  {:<16} {:<24}", "pass", "kind");
    for (b, _) in all {
        // The clock says what the column measures: "cpu wall ms", "ash GPU ms".
        let clock = match b.clock() {
            Clock::CpuWall => "wall",
            Clock::GpuTimestamps => "GPU",
        };
        print!(" {:>14}", format!("{} {clock} ms", b.name()));
    }
    println!();
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for &pass in &plan.order {
        print!(
            "  {:<16} {:<24}",
            plan.pass_name(pass),
            plan.graph.passes[pass].kind
        );
        for (_, times) in all {
            let t = times.iter().find(|t| t.pass == pass).and_then(|t| t.millis);
            print!(" {:>14}", show(t));
        }
        println!();
    }
    print!("  {:<16} {:<24}", "frame", "");
    for (_, times) in all {
        print!(" {:>14.3}", frame_millis(times));
    }
    println!();
}

/// One backend's per-pass times, with the counters of an instrumented CPU run.
fn print_timings(plan: &Plan, times: &[PassTime], instrument: bool) {
    print!(
        "\n  {:<14} {:<16} {:<24} {:>9} {:>10} {:>17}",
        "queue", "pass", "kind", "groups", "ms", "span ms"
    );
    if instrument {
        print!(" {:>8} {:>12} {:>12}", "lanes", "atomics", "pixels");
    }
    println!();
    let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    for t in times {
        print!(
            "  {:<14} {:<16} {:<24} {:>9} {:>10} {:>17}",
            t.queue.to_string(),
            t.name,
            plan.graph.passes[t.pass].kind,
            t.workgroups.map_or("-".to_string(), |n| n.to_string()),
            show(t.millis),
            t.span
                .map_or("-".to_string(), |(a, b)| format!("{a:.3}..{b:.3}"))
        );
        if let (true, Some(c)) = (instrument, &t.counters) {
            let lanes = c
                .lane_utilisation()
                .map_or("-".to_string(), |u| format!("{:.1}%", 100.0 * u));
            print!(" {lanes:>8} {:>12} {:>12}", c.atomics, c.pixels_written);
        }
        println!();
    }
    for lane in &plan.lanes {
        let sum: f64 = times
            .iter()
            .filter(|t| t.queue == lane.queue)
            .filter_map(|t| t.millis)
            .sum();
        println!("  {:<14} total {sum:.3} ms", lane.queue.to_string());
    }
    println!("  frame {:.3} ms", frame_millis(times));
}
