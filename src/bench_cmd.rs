//! `strandgraph bench`: pipeline variants × views × backends, as Lipp's
//! Table 1 (GPU frame time per configuration at close, mid and far
//! distance, the raster time in parentheses), with a roofline measured on
//! the same device in the same run.
//!
//! Rows are [`VARIANTS`]: a pipeline's graph plus parameter overrides (the
//! published optimisations are pass parameters, so an ablation is an
//! override, as `render --param`). Columns are the scenes given (by default
//! `scenes/distances/{close,mid,far}.ron`, the showcase and the crowd), each
//! prepared for the row's graph; a graph that cannot run a scene gets its
//! cells marked skipped with the reason.

mod levels;
mod pictures;
mod progress;
mod quality;
mod report;
mod variants;

use miette::{Result, miette};
use progress::Progress;
use report::{Ceilings, Cell, Report, Stats};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use strandgraph::frame::{Prepared, complete_upload, override_param, parse_size, prepare};
use strandgraph::images::{Picture, main_picture};
use strandgraph::runner::{
    self, Backend, Barriers, Clock, LoopCounters, OpenOptions, PassTime, Session, frame_millis,
};
use strandgraph::sequence;
use strandgraph_assets::Scene;
use strandgraph_graph::alias::Aliasing;
use strandgraph_graph::schema::Quantity;
use strandgraph_passes::bench::RasterBenchParams;
use strandgraph_passes::params::check;
use strandgraph_passes::upload::Upload;
use strandgraph_passes::{Definitions, Registry};
pub use variants::{VARIANTS, Variant};

const VIEWS: [&str; 3] = [
    "scenes/distances/close.ron",
    "scenes/distances/mid.ron",
    "scenes/distances/far.ron",
];
/// Whole scenes timed after the views (not by `--quick`): one head, and
/// the crowd of twelve characters.
const SCENES: [&str; 2] = ["scenes/showcase.ron", "scenes/crowd.ron"];
/// The frame rate of timed frames: the simulation's step.
const FPS: f32 = 60.0;
const ROOFLINE: &str = "scenes/graphs/roofline.ron";
/// A GPU cell runs its first frame for at least this long before the
/// warm-up frames, and until its frame time has settled ([`warm_clocks`]),
/// but no longer than [`CLOCK_WARMUP_MAX`].
const CLOCK_WARMUP: std::time::Duration = std::time::Duration::from_millis(300);
const CLOCK_WARMUP_MAX: std::time::Duration = std::time::Duration::from_secs(3);

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Choice {
    Cpu,
    Wgpu,
    Ash,
    /// cpu, and wgpu and ash where they open (a Vulkan device exists).
    All,
}

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph bench --quick
  strandgraph bench --backend ash --row \"Lipp\" --out bench/
  strandgraph bench --quick --out bench/ --pictures   (then: strandgraph report --from bench/bench.json -o bench/)
  strandgraph bench scenes/showcase.ron --backend wgpu,ash --row \"HW mesh\"")]
pub struct Args {
    /// Scenes, one column each (default: scenes/distances/{close,mid,far}.ron,
    /// then scenes/showcase.ron and scenes/crowd.ron unless --quick).
    pub scenes: Vec<PathBuf>,
    /// Backends to time (repeatable, or comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "cpu")]
    pub backend: Vec<Choice>,
    /// Timed frames per cell.
    #[arg(long, default_value_t = 10)]
    pub frames: usize,
    /// Untimed frames per cell before the timed ones.
    #[arg(long, default_value_t = 2)]
    pub warmup: usize,
    /// Resolution as WxH (default: each scene's, 1920x1080 for the views).
    #[arg(long)]
    pub size: Option<String>,
    /// Only rows whose "pipeline: variant" contains this (repeatable).
    #[arg(long = "row")]
    pub rows: Vec<String>,
    /// Write bench.csv, bench.json and bench.txt here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also save every measured cell's last frame, its FLIP error map and
    /// its reference as PNG under OUT/pictures/ (what `report` shows).
    #[arg(long, requires = "out")]
    pub pictures: bool,
    /// CI smoke run: 320x180, 2 frames, no warm-up (unless given), VoxelMarch
    /// shadows, seven rows (each pipeline as published and one ablation).
    #[arg(long)]
    pub quick: bool,
    /// Emulated subgroup width of the CPU backend (timed and counting runs).
    #[arg(long, default_value_t = 32)]
    pub subgroup: u32,
    /// Override a pass parameter in every row, after the row's own
    /// overrides, as PASS.PARAM=VALUE (repeatable); the report notes it.
    #[arg(long = "param", value_name = "PASS.PARAM=VALUE")]
    pub params: Vec<String>,
    /// Put naga's loop counters in every row's GPU shaders as this says
    /// (graph, every or none; docs/architecture.md, "Shaders") rather than
    /// as each row does; the report notes it.
    #[arg(long, value_parser = clap::value_parser!(LoopCounters))]
    pub loop_counters: Option<LoopCounters>,
    /// Separate ash's passes with barriers as this says (levels or
    /// per-pass; docs/architecture.md, "Synchronisation") rather than as
    /// each row does; the report notes it.
    #[arg(long, value_parser = clap::value_parser!(Barriers))]
    pub barriers: Option<Barriers>,
    /// Plan transient memory as this says (first-fit or no-new-waits;
    /// docs/architecture.md, "Synchronisation") rather than as each row
    /// does; the report notes it.
    #[arg(long, value_parser = clap::value_parser!(Aliasing))]
    pub aliasing: Option<Aliasing>,
    /// Also time each ash cell's frame level by level (as many frames
    /// again): every batch's start and each dependency level's end, the
    /// medians in bench.json's `levels`; where a frame's time goes with its
    /// queues overlapping (docs/architecture.md, "Synchronisation").
    #[arg(long)]
    pub levels: bool,
}

/// `rel` under the working directory, else under the checkout the binary
/// was built from (the device machine runs from a copy of the tree).
pub(crate) fn locate(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        return here;
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    if built.exists() { built } else { here }
}

/// The backends to time, in order; `all` takes wgpu only if it opens.
fn backends(args: &Args) -> Vec<(Backend, bool)> {
    let mut out: Vec<(Backend, bool)> = Vec::new();
    let mut add = |b: Backend, required: bool| {
        if !out.iter().any(|(x, _)| *x == b) {
            out.push((b, required));
        }
    };
    for c in &args.backend {
        match c {
            Choice::Cpu => add(Backend::Cpu, true),
            Choice::Wgpu => add(Backend::Wgpu, true),
            Choice::Ash => add(Backend::Ash, true),
            Choice::All => {
                add(Backend::Cpu, true);
                add(Backend::Wgpu, false);
                add(Backend::Ash, false);
            }
        }
    }
    out
}

/// Why `graph` cannot run yet: the first live pass kind without a definition.
fn missing_kernel(graph: &Path) -> Result<Option<String>> {
    // Which kinds a graph uses does not depend on the model count.
    let plan = strandgraph_graph::compile_file(graph, &Registry, 1)?;
    Ok(plan
        .order
        .iter()
        .map(|&id| &plan.graph.passes[id])
        .find(|pass| Registry.definition(&pass.kind).is_none())
        .map(|pass| format!("pass `{}` ({}) has no kernels yet", pass.name, pass.kind)))
}

/// [`prepare`], with `--quick`'s graph-wide override applied before the
/// self-shadow bake: quick runs shade with `VoxelMarch` self-shadowing, as
/// the offline bake (`frame::bake_shadows`, run by `frame::complete_upload`) takes minutes per groom on a
/// 2-core CI machine and its cache is per machine. Full runs keep the
/// graph's `Baked`, baked once and then read from the cache.
pub(crate) fn prepare_graph(
    scene_path: &Path,
    graph: &Path,
    size: Option<(u32, u32)>,
    quick: bool,
) -> Result<Prepared> {
    if !quick {
        return prepare(scene_path, Some(graph), size);
    }
    let scene = Scene::load(scene_path).map_err(|e| miette!("{e}"))?;
    let (w, h) = size.unwrap_or(scene.desc.resolution);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(miette!("--size {w}x{h} is outside 1..=16384"));
    }
    let mut plan = strandgraph_graph::compile_file(graph, &Registry, scene.grooms.len() as u32)?;
    let shade: Vec<String> = plan
        .graph
        .passes
        .iter()
        .filter(|p| p.kind == "kulikov.shade")
        .map(|p| p.name.clone())
        .collect();
    for name in shade {
        override_param(&mut plan, &format!("{name}.{QUICK_SHADOW}"))?;
    }
    let mut upload = strandgraph_passes::upload::upload(&scene, w, h);
    complete_upload(&plan, &scene, &mut upload)?;
    let instance = plan.instantiate(&upload.quantities)?;
    Ok(Prepared {
        scene,
        upload,
        plan,
        instance,
    })
}

/// The rows `--quick` times unless `--row` picks others: each pipeline as
/// published and one ablation of each, so CI exercises both without the
/// multi-sample rows (minutes on lavapipe). CI's lavapipe (Mesa 22.3) has
/// no mesh shaders: its wgpu and ash cells of the mesh row are skipped, the
/// CPU's runs.
const QUICK_ROWS: &[&str] = &[
    "Kulikov: all optimisations",
    "Kulikov: no loop flattening",
    "Lipp: SWR 1+L",
    "Lipp: SWR 1+F+L (as published)",
    "Scheuermann: Z-primed (as published)",
    "HW strands: HW 4+L",
    "HW mesh: MS 4+L",
];

/// Whether a backend refused a row for something the device lacks.
fn lacks_feature(e: &miette::Report) -> bool {
    e.downcast_ref::<runner::Unsupported>().is_some()
}

/// What `--quick` sets on every `kulikov.shade` pass.
const QUICK_SHADOW: &str = "self_shadow=\"VoxelMarch\"";

pub fn run(mut args: Args) -> Result<()> {
    if args.quick {
        args.size.get_or_insert_with(|| "320x180".into());
        if args.frames == 10 {
            args.frames = 2;
        }
        if args.warmup == 2 {
            args.warmup = 0;
        }
    }
    if args.frames == 0 {
        return Err(miette!("--frames must be at least 1"));
    }
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let scenes: Vec<PathBuf> = if args.scenes.is_empty() {
        let whole = if args.quick { &[][..] } else { &SCENES[..] };
        VIEWS.iter().chain(whole).map(|v| locate(v)).collect()
    } else {
        args.scenes.clone()
    };
    let rows: Vec<&Variant> = VARIANTS
        .iter()
        .filter(|v| {
            let label = format!("{}: {}", v.pipeline, v.name);
            match (args.rows.is_empty(), args.quick) {
                (false, _) => args.rows.iter().any(|r| label.contains(r.as_str())),
                (true, true) => QUICK_ROWS.contains(&label.as_str()),
                (true, false) => true,
            }
        })
        .collect();
    let cpu = OpenOptions {
        subgroup_width: args.subgroup,
        ..OpenOptions::default()
    };
    let counting = OpenOptions {
        instrument: true,
        ..cpu
    };
    let t0 = Instant::now();
    let mut report = Report::new(&args, &scenes);
    for spec in &args.params {
        report.note(format!("--param {spec} on every row"));
    }
    if let Some(c) = args.loop_counters {
        report.note(format!(
            "--loop-counters {c} on every row (naga's loop counters)"
        ));
    }
    if let Some(b) = args.barriers {
        report.note(format!("--barriers {b} on every row (ash's barriers)"));
    }
    if let Some(a) = args.aliasing {
        report.note(format!("--aliasing {a} on every row (the memory plan)"));
    }
    if args.quick {
        report.note(format!(
            "--quick: every kulikov.shade pass runs with {QUICK_SHADOW} (no offline bake)"
        ));
    }
    if !args.quick {
        report.note(format!(
            "GPU cells run their first frame for at least {} ms, until its time settles (at most {} s), before the warm-up frames, so the clocks are up whatever ran before; a backend's first GPU cell is measured twice and its first measurement dropped",
            CLOCK_WARMUP.as_millis(),
            CLOCK_WARMUP_MAX.as_secs()
        ));
    }

    // Graphs whose passes lack kernels (Lipp, for now) are listed, not run.
    let mut skipped: BTreeMap<&str, String> = BTreeMap::new();
    for v in &rows {
        if !skipped.contains_key(v.graph)
            && let Some(why) = missing_kernel(&locate(v.graph))?
        {
            skipped.insert(v.graph, why);
        }
    }
    // Each (scene, graph) is loaded and compiled once; rows clone its plan.
    // A pipeline that cannot run a scene (Lipp needs hair meshes) gets its
    // cells marked skipped with the reason, not a failed bench.
    let mut prepared: BTreeMap<(usize, &str), Result<Prepared, String>> = BTreeMap::new();
    // An animated scene's frames, timed in motion (sequence::animation_frames).
    let mut animated: BTreeMap<(usize, &str), Vec<Upload>> = BTreeMap::new();
    for (s, scene) in scenes.iter().enumerate() {
        for graph in rows.iter().map(|v| v.graph) {
            if skipped.contains_key(graph) {
                continue;
            }
            if let std::collections::btree_map::Entry::Vacant(e) = prepared.entry((s, graph)) {
                tracing::info!(scene = %scene.display(), graph, "preparing");
                let mut p = prepare_graph(scene, &locate(graph), size, args.quick);
                if let Ok(p) = &mut p {
                    // The timed frames, then as many again timed at their bounds.
                    let count = args.warmup + 2 * args.frames;
                    if let Some(frames) = sequence::animation_frames(p, count, FPS)? {
                        animated.insert((s, graph), frames);
                    }
                }
                e.insert(p.map_err(|e| format!("{graph} on {}: {e}", scene.display())));
            }
        }
    }
    if !animated.is_empty() {
        report.note(format!(
            "animated scenes run their animation at {FPS} fps from its start (simulation in motion); their FLIP is the mean over the timed frames, each against the reference's same frame, and their flicker compares frame-to-frame change with the reference's"
        ));
    }
    let first = prepared
        .values()
        .find_map(|p| p.as_ref().ok())
        .ok_or_else(|| {
            let why: Vec<&String> = prepared.values().filter_map(|p| p.as_ref().err()).collect();
            miette!("no runnable rows: {skipped:?} {why:?}")
        })?;
    // Raster atomics per (row, view), counted once for every backend.
    let mut counts: BTreeMap<(usize, usize), u64> = BTreeMap::new();
    let chosen = backends(&args);
    let progress = Progress::new((chosen.len() * rows.len() * scenes.len()) as u64);
    let mut references = quality::References::default();
    let mut saver = match (&args.out, args.pictures) {
        (Some(dir), true) => Some(pictures::Saver::new(dir)),
        _ => None,
    };
    'backends: for (backend, required) in chosen {
        // The first GPU cell of a run is measured twice and the first
        // measurement dropped: on the H100 a run's first cell measured 2 to
        // 4 times slow in about half the runs (close view 7.8 ms, then
        // 1.79 ms), every pass alike, whatever the warm-up; later cells
        // seldom did (2 of 65 in one run).
        let mut primed = backend == Backend::Cpu || args.quick;
        // The roofline, on the first scene's screen size. A device that
        // cannot run it (no 64-bit atomics) still gets its rows timed.
        match roofline(backend, first, &args, cpu, counting) {
            Ok(r) => {
                report.device(backend, &r.device, &r.notes);
                report.ceilings(backend, r.ceilings);
            }
            Err(e) => progress.note(&format!("{}: no roofline: {e:?}", backend.name())),
        }
        for (r, v) in rows.iter().enumerate() {
            for s in 0..scenes.len() {
                progress.done();
                if let Some(why) = skipped.get(v.graph) {
                    report.cell(backend, v, s, Cell::Skipped(why.clone()));
                    continue;
                }
                let p = match &prepared[&(s, v.graph)] {
                    Ok(p) => p,
                    Err(why) => {
                        report.cell(backend, v, s, Cell::Skipped(why.clone()));
                        continue;
                    }
                };
                progress.cell(&format!(
                    "{} {}: {} / {}",
                    backend.name(),
                    v.pipeline,
                    v.name,
                    report.views[s]
                ));
                let atomics = match counts.get(&(r, s)) {
                    Some(&n) => n,
                    None => {
                        let n = count_atomics(p, v, &args.params, counting)?;
                        counts.insert((r, s), n);
                        n
                    }
                };
                let inputs = animated.get(&(s, v.graph)).map(Vec::as_slice);
                if !primed {
                    // An error shows in the measurement that follows.
                    let _ = measure(backend, p, v, &args, cpu, atomics, inputs);
                    primed = true;
                }
                match measure(backend, p, v, &args, cpu, atomics, inputs) {
                    Ok((device, notes, mut stats, pictures)) => {
                        report.device(backend, &device, &notes);
                        if let Some(img) = pictures.last() {
                            let setup = quality::Setup {
                                scene: &scenes[s],
                                size,
                                quick: args.quick,
                                cpu,
                                warmup: args.warmup,
                                frames: args.frames,
                            };
                            let judged = references
                                .judge(backend, s, &setup, v, &args.params, &pictures)
                                .map_err(|e| miette!("{}: {}: {e}", v.pipeline, v.name))?;
                            if let Some(j) = &judged {
                                stats.judged(j);
                            }
                            if let Some(saver) = &mut saver {
                                let saved = saver.save(
                                    backend,
                                    &report.views[s],
                                    v,
                                    &img.image,
                                    judged.as_ref(),
                                )?;
                                stats.pictures = Some(saved);
                            }
                        }
                        report.cell(backend, v, s, Cell::Measured(Box::new(stats)));
                    }
                    // `all` takes the backends that open here.
                    Err(e) if !required && !report.has_device(backend) => {
                        progress.note(&format!("skipping {}: {e:?}", backend.name()));
                        continue 'backends;
                    }
                    // A row the device cannot run (lavapipe has no 8x MSAA).
                    Err(e) if lacks_feature(&e) => {
                        progress.note(&format!("skipping the cell: {e}"));
                        report.cell(backend, v, s, Cell::Skipped(e.to_string()));
                    }
                    Err(e) => return Err(e),
                }
            }
            if let Some(dir) = &args.out {
                report.elapsed_s = t0.elapsed().as_secs_f64();
                report.partial = true;
                report.write(dir)?;
            }
        }
    }
    progress.finish();
    report.partial = false;
    for line in references.notes.drain(..) {
        report.note(line);
    }
    report.elapsed_s = t0.elapsed().as_secs_f64();
    print!("{}", report.table());
    if let Some(dir) = &args.out {
        report.write(dir)?;
        println!(
            "wrote {0}/bench.txt, {0}/bench.csv, {0}/bench.json{1}",
            dir.display(),
            if args.pictures { ", pictures/" } else { "" }
        );
    }
    Ok(())
}

/// Runs `warmup` then `frames` frames; per-pass times of each timed frame,
/// and the frame times (CPU: wall time of the frame, its queues overlap;
/// GPU: [`frame_millis`], timestamps only).
fn frames(
    session: &mut dyn Session,
    inputs: &[Upload],
    args: &Args,
) -> Result<(Vec<Vec<PassTime>>, Vec<f64>)> {
    // Frame k runs inputs[k], the last one again once they run out.
    let input = |k: usize| &inputs[k.min(inputs.len() - 1)];
    // A GPU idle during the CPU's work between cells (counting, references,
    // FLIP) drops its clocks, and a few frames of a few milliseconds do not
    // bring them back: frame 0 runs again until its time settles.
    // Frame 0 is where a sequence starts (it resets the simulation), so
    // repeating it changes nothing of what follows.
    // `--quick` (CI's smoke run on a software rasterizer) skips it.
    if session.clock() == Clock::GpuTimestamps && !args.quick {
        warm_clocks(session, input(0))?;
    }
    for k in 0..args.warmup {
        session.run(input(k))?;
    }
    let mut passes = Vec::with_capacity(args.frames);
    let mut totals = Vec::with_capacity(args.frames);
    for k in args.warmup..args.warmup + args.frames {
        let t = Instant::now();
        let times = session.run(input(k))?;
        let wall = t.elapsed().as_secs_f64() * 1e3;
        totals.push(match session.clock() {
            Clock::CpuWall => wall,
            Clock::GpuTimestamps => frame_millis(&times),
        });
        passes.push(times);
    }
    Ok((passes, totals))
}

/// After [`frames`]: `frames` more frames timed only at their bounds
/// ([`Session::run_frame_timed`]); empty where the backend cannot. An
/// animated scene goes on (its inputs are each frame's changes from the
/// last); a still one runs its frame again.
fn bounds_frames(session: &mut dyn Session, inputs: &[Upload], args: &Args) -> Result<Vec<f64>> {
    let input = |k: usize| &inputs[k.min(inputs.len() - 1)];
    let mut bounds = Vec::with_capacity(args.frames);
    for k in args.warmup + args.frames..args.warmup + 2 * args.frames {
        match session.run_frame_timed(input(k))? {
            Some(ms) => bounds.push(ms),
            None => break,
        }
    }
    Ok(bounds)
}

/// Runs `input` until [`CLOCK_WARMUP`] has passed and the median GPU time of
/// the last five frames is within 3% of the five before, for at most
/// [`CLOCK_WARMUP_MAX`]. (A run's first cell needs more than this: it is
/// measured twice, see `run`.)
fn warm_clocks(session: &mut dyn Session, input: &Upload) -> Result<()> {
    let t = Instant::now();
    let mut last = f64::NAN;
    loop {
        let mut batch = Vec::with_capacity(5);
        for _ in 0..5 {
            batch.push(frame_millis(&session.run(input)?));
        }
        let now = report::median(&batch);
        let settled = (now - last).abs() <= 0.03 * last;
        if (settled && t.elapsed() >= CLOCK_WARMUP) || t.elapsed() >= CLOCK_WARMUP_MAX {
            return Ok(());
        }
        last = now;
    }
}

/// `v`'s plan for one prepared scene: the graph with the row's overrides,
/// then `extra` (`--param`).
fn variant_plan(p: &Prepared, v: &Variant, extra: &[String]) -> Result<strandgraph_graph::Plan> {
    let mut plan = p.plan.clone();
    for spec in v
        .overrides
        .iter()
        .copied()
        .chain(extra.iter().map(String::as_str))
    {
        override_param(&mut plan, spec)?;
    }
    Ok(plan)
}

/// The raster passes' work in an instrumented CPU run of this
/// configuration, in the unit of the row's ceiling: atomics, or for rows
/// drawn by the hardware rasterizer (ceiling `fragments`) the fragments
/// they shade. GPUs expose no such counters, so GPU rows use this count.
fn count_atomics(
    p: &Prepared,
    v: &Variant,
    extra: &[String],
    counting: OpenOptions,
) -> Result<u64> {
    let plan = variant_plan(p, v, extra)?;
    let mut counter = runner::open(Backend::Cpu, &plan, &p.instance, counting)?;
    let fragments = v.ceiling == "fragments";
    Ok(counter
        .run(&p.upload)?
        .iter()
        .filter(|t| v.raster.contains(&strandgraph_graph::base_name(&t.name)))
        .filter_map(|t| {
            let c = t.counters.as_ref()?;
            Some(if fragments {
                c.pixels_written
            } else {
                c.atomics
            })
        })
        .sum())
}

/// One cell's timed frames: the device, its notes, the statistics, and
/// the pictures its quality is judged on where its pipeline has a
/// reference or `--pictures` asks for them: the last frame's, or every
/// timed frame's of an animated scene.
fn measure(
    backend: Backend,
    p: &Prepared,
    v: &Variant,
    args: &Args,
    cpu: OpenOptions,
    atomics: u64,
    animation: Option<&[Upload]>,
) -> Result<(String, Vec<String>, Stats, Vec<Picture>)> {
    let mut plan = variant_plan(p, v, &args.params)?;
    plan.aliasing = args.aliasing.unwrap_or(v.backend.aliasing);
    // The scene's instance was planned with the default aliasing.
    let instance = if plan.aliasing == p.plan.aliasing {
        Cow::Borrowed(&p.instance)
    } else {
        Cow::Owned(plan.instantiate(&p.upload.quantities)?)
    };
    let cpu = OpenOptions {
        loop_counters: args.loop_counters.unwrap_or(v.backend.loop_counters),
        barriers: args.barriers.unwrap_or(v.backend.barriers),
        ..cpu
    };
    let mut session = runner::open(backend, &plan, &instance, cpu)?;
    // A still scene: a game's frames at 60 fps, the simulation stepping.
    let still = [sequence::running(&p.upload, FPS)];
    let inputs = animation.unwrap_or(&still);
    let (passes, totals) = frames(session.as_mut(), inputs, args)?;
    let bounds = bounds_frames(session.as_mut(), inputs, args)?;
    let levels = if args.levels {
        let next = args.warmup + 2 * args.frames;
        levels::level_frames(session.as_mut(), inputs, next, args)?
    } else {
        Vec::new()
    };
    runner::check_frame(&plan, &instance, session.as_ref())?;
    let mut stats = Stats::new(&passes, &totals, v.raster, atomics);
    if !bounds.is_empty() {
        stats.bounds = Some(report::Spread::of(&bounds));
    }
    stats.levels = levels;
    // Read back only what a reference will be compared with, or
    // `--pictures` saves: the last frame; of an animated scene with a
    // reference, every timed frame, from a second run of the sequence (so
    // the timed frames have no read-back between them).
    let q = p.upload.quantities;
    let judged = quality::reference_graph(v.pipeline).is_some();
    let pictures = match animation {
        Some(inputs) if judged => {
            let mut again = runner::open(backend, &plan, &instance, cpu)?;
            let count = (args.warmup + args.frames).min(inputs.len());
            let inputs = &inputs[..count];
            quality::sequence_pictures(again.as_mut(), &plan, &instance, inputs, args.warmup)?
        }
        _ if args.pictures || judged => picture(&plan, q, session.as_ref()).into_iter().collect(),
        _ => Vec::new(),
    };
    Ok((session.device(), session.notes(), stats, pictures))
}

/// The main image of the frame `session` last ran, as the bench shows it.
fn picture(
    plan: &strandgraph_graph::Plan,
    q: strandgraph_graph::Quantities,
    session: &dyn Session,
) -> Option<Picture> {
    main_picture(plan, q.width, q.height, quality::DISPLAY, |name| {
        session.read(name).ok().flatten()
    })
}

/// What the roofline run gives one backend.
struct Roofline {
    device: String,
    notes: Vec<String>,
    ceilings: Ceilings,
}

/// Runs `scenes/graphs/roofline.ron` at `first`'s screen size on `backend`.
fn roofline(
    backend: Backend,
    first: &Prepared,
    args: &Args,
    cpu: OpenOptions,
    counting: OpenOptions,
) -> Result<Roofline> {
    let plan = strandgraph_graph::compile_file(&locate(ROOFLINE), &Registry, 1)?;
    let instance = plan.instantiate(&first.upload.quantities)?;
    let upload = Upload {
        quantities: first.upload.quantities,
        ..Default::default()
    };
    let mut counter = runner::open(Backend::Cpu, &plan, &instance, counting)?;
    let counted = counter.run(&upload)?;
    let ops = |name: &str| {
        counted
            .iter()
            .find(|t| t.name == name)
            .and_then(|t| t.counters.as_ref().map(|c| c.atomics))
            .unwrap_or(0)
    };
    let (atomics32, atomics64) = (ops("atomic_min32"), ops("atomic_min64"));
    drop(counter);

    let mut session = runner::open(backend, &plan, &instance, cpu)?;
    let (passes, _) = frames(session.as_mut(), std::slice::from_ref(&upload), args)?;
    let median = |name: &str| {
        let v: Vec<f64> = passes
            .iter()
            .filter_map(|f| f.iter().find(|t| t.name == name).and_then(|t| t.millis))
            .collect();
        report::median(&v)
    };
    let copy_bytes = plan
        .graph
        .resource_id("copy_dst")
        .map_or(0, |r| instance.sizes[r].bytes);
    // The graphics roofline: triangles and shaded fragments the raster passes drew.
    let q = &instance.quantities;
    let drawn = |name: &str| -> (u64, u64) {
        plan.graph
            .passes
            .iter()
            .find(|p| p.name == name)
            .and_then(|p| check::<RasterBenchParams>(&p.params).ok())
            .map_or((0, 0), |b| {
                let layers = u64::from(b.layers);
                (
                    b.triangles(q.width, q.height),
                    layers * q.count(Quantity::Pixels),
                )
            })
    };
    Ok(Roofline {
        device: session.device(),
        notes: session.notes(),
        ceilings: Ceilings {
            atomic_min32: (atomics32, median("atomic_min32")),
            atomic_min64: (atomics64, median("atomic_min64")),
            copy: (copy_bytes, median("copy")),
            triangles: (drawn("triangles").0, median("triangles")),
            fragments: (drawn("fragments").1, median("fragments")),
        },
    })
}

#[cfg(test)]
mod quick_tests {
    use super::{QUICK_ROWS, VARIANTS};

    #[test]
    fn quick_rows_name_real_variants() {
        for row in QUICK_ROWS {
            assert!(
                VARIANTS
                    .iter()
                    .any(|v| format!("{}: {}", v.pipeline, v.name) == *row),
                "--quick row {row:?} is not a variant"
            );
        }
    }
}
