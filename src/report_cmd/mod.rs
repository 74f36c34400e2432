//! `strandgraph report`: the bench's rows as a page to look at. It runs
//! `strandgraph bench --pictures` into a directory (or takes an earlier
//! run's bench.json) and writes `index.html` there: per view and backend
//! the rows' pictures beside their reference with FLIP maps, a table of
//! time, FLIP and coverage error, a time-versus-FLIP chart with a Pareto
//! frontier per reference, and each pipeline's rows' passes as stacked
//! bars.
//!
//! `--from` is how a remote GPU's run becomes a page: the bench runs there,
//! its directory comes back, and the page is drawn here. Into another
//! directory, the pictures the page shows are copied, cut by `--crop` and
//! re-encoded by `--jpeg` on the way (a report small enough to commit).

mod charts;
mod crop;
mod data;
mod export;
mod figures;
mod html;

use crate::bench_cmd::{self, Choice};
use miette::{IntoDiagnostic, Result, WrapErr, miette};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph report scenes/distances/*.ron --backend ash -o report/
  strandgraph report scenes/distances/far.ron --quick --row Kulikov -o report/
  strandgraph report --from h100/bench.json -o h100/   (a `bench --out h100/ --pictures` run)
  strandgraph report --from h100/bench.json -o docs/report/ --crop 960x540 --crop far=480x270 --jpeg 85")]
pub struct Args {
    /// Scenes to bench, one section each per backend (default: bench's,
    /// scenes/distances/{close,mid,far}.ron then the showcase and the crowd).
    #[arg(conflicts_with = "from")]
    pub scenes: Vec<PathBuf>,
    /// Backends to time (repeatable, or comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "cpu")]
    pub backend: Vec<Choice>,
    /// Only rows whose "pipeline: variant" contains this (repeatable).
    #[arg(long = "row", conflicts_with = "from")]
    pub rows: Vec<String>,
    /// Resolution as WxH (default: each scene's).
    #[arg(long, conflicts_with = "from")]
    pub size: Option<String>,
    /// Timed frames per cell.
    #[arg(long, default_value_t = 10)]
    pub frames: usize,
    /// Untimed frames per cell before the timed ones.
    #[arg(long, default_value_t = 2)]
    pub warmup: usize,
    /// Bench's CI smoke run: 320x180, 2 frames, VoxelMarch shadows, seven rows.
    #[arg(long, conflicts_with = "from")]
    pub quick: bool,
    /// Override a pass parameter in every row, as PASS.PARAM=VALUE (repeatable).
    #[arg(
        long = "param",
        value_name = "PASS.PARAM=VALUE",
        conflicts_with = "from"
    )]
    pub params: Vec<String>,
    /// Draw the page from this bench.json (written by `report` or by
    /// `bench --out DIR --pictures`) instead of running the bench.
    #[arg(long, value_name = "BENCH_JSON")]
    pub from: Option<PathBuf>,
    /// The directory for bench.json, pictures/ and index.html.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Cut every picture to this 1:1 rectangle, WxH[+X+Y] (default: centred),
    /// or VIEW=WxH[+X+Y] for one view (repeatable). FLIP stays the whole frame's.
    #[arg(long, value_name = "[VIEW=]WxH[+X+Y]")]
    pub crop: Vec<crop::CropArg>,
    /// Write the pictures as JPEG of this quality (1 to 100) instead of PNG.
    #[arg(long, value_name = "Q", value_parser = clap::value_parser!(u8).range(1..=100))]
    pub jpeg: Option<u8>,
}

/// The bench run `report` makes: its own flags, pictures on, into `out`.
fn bench_args(args: &Args, out: &Path) -> bench_cmd::Args {
    bench_cmd::Args {
        scenes: args.scenes.clone(),
        backend: args.backend.clone(),
        frames: args.frames,
        warmup: args.warmup,
        size: args.size.clone(),
        rows: args.rows.clone(),
        out: Some(out.to_path_buf()),
        pictures: true,
        quick: args.quick,
        subgroup: 32,
        params: args.params.clone(),
        loop_counters: None,
        barriers: None,
        aliasing: None,
        levels: false,
    }
}

pub fn run(args: Args) -> Result<()> {
    let opts = export::Options {
        crops: crop::Crops::new(&args.crop)?,
        jpeg: args.jpeg,
    };
    let json = match &args.from {
        Some(path) => path.clone(),
        None => {
            // Cut or re-encoded pictures go beside the bench's own.
            let run = if opts.transforms() {
                args.out.join("full")
            } else {
                args.out.clone()
            };
            bench_cmd::run(bench_args(&args, &run))?;
            run.join("bench.json")
        }
    };
    let bench = data::load(&json)?;
    data::check_pictures(&bench, &json)?;
    std::fs::create_dir_all(&args.out)
        .into_diagnostic()
        .wrap_err_with(|| format!("creating {}", args.out.display()))?;
    let page_json = copy_if_elsewhere(&bench, &json, &args.out, &opts)?;
    let bench = data::load(&page_json)?;
    data::check_pictures(&bench, &page_json)?;
    let page = html::page(&bench, "bench.json")?;
    let index = args.out.join("index.html");
    std::fs::write(&index, page)
        .into_diagnostic()
        .wrap_err_with(|| format!("writing {}", index.display()))?;
    tracing::info!(sections = data::sections(&bench).len(), "report written");
    println!("wrote {}", index.display());
    Ok(())
}

/// The run copied into `out` unless it is there already; the bench.json
/// the page is drawn from.
fn copy_if_elsewhere(
    bench: &data::Bench,
    json: &Path,
    out: &Path,
    opts: &export::Options,
) -> Result<PathBuf> {
    let from_dir = json.parent().unwrap_or(Path::new("."));
    if !same_dir(from_dir, out)? {
        export::export(bench, json, out, opts)?;
        return Ok(out.join("bench.json"));
    }
    if opts.transforms() {
        return Err(miette!(
            help =
                "give -o another directory: the cut or re-encoded pictures and bench.json go there",
            "--crop and --jpeg would replace the run's own pictures in {}",
            out.display()
        ));
    }
    Ok(json.to_path_buf())
}

/// Whether `a` and `b` name one directory (`b` exists by now).
fn same_dir(a: &Path, b: &Path) -> Result<bool> {
    let canon = |p: &Path| {
        let p = if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        };
        p.canonicalize()
            .into_diagnostic()
            .wrap_err_with(|| format!("resolving {}", p.display()))
    };
    Ok(canon(a)? == canon(b)?)
}
