//! `strandgraph report`: the bench's rows as a page to look at. It runs
//! `strandgraph bench --pictures` into a directory (or takes an earlier
//! run's bench.json) and writes `index.html` there: per view and backend
//! the rows' pictures beside their reference with FLIP maps, a table of
//! time, FLIP and coverage error, a time-versus-FLIP Pareto chart and the
//! rows' passes as stacked bars.
//!
//! `--from` is how a remote GPU's run becomes a page: the bench runs there,
//! its directory comes back, and the page is drawn here.

mod charts;
mod data;
mod html;

use crate::bench_cmd::{self, Choice};
use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph report scenes/distances/*.ron --backend ash -o report/
  strandgraph report scenes/distances/far.ron --quick --row Kulikov -o report/
  strandgraph report --from h100/bench.json -o h100/   (a `bench --out h100/ --pictures` run)")]
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
}

/// The bench run `report` makes: its own flags, pictures on, into `out`.
fn bench_args(args: &Args) -> bench_cmd::Args {
    bench_cmd::Args {
        scenes: args.scenes.clone(),
        backend: args.backend.clone(),
        frames: args.frames,
        warmup: args.warmup,
        size: args.size.clone(),
        rows: args.rows.clone(),
        out: Some(args.out.clone()),
        pictures: true,
        quick: args.quick,
        subgroup: 32,
        params: args.params.clone(),
    }
}

pub fn run(args: Args) -> Result<()> {
    let json = match &args.from {
        Some(path) => path.clone(),
        None => {
            bench_cmd::run(bench_args(&args))?;
            args.out.join("bench.json")
        }
    };
    let bench = data::load(&json)?;
    data::check_pictures(&bench, &json)?;
    std::fs::create_dir_all(&args.out)
        .into_diagnostic()
        .wrap_err_with(|| format!("creating {}", args.out.display()))?;
    let from_dir = json.parent().unwrap_or(Path::new("."));
    if !same_dir(from_dir, &args.out)? {
        copy_run(&bench, &json, &args.out)?;
    }
    let page = html::page(&bench, "bench.json")?;
    let index = args.out.join("index.html");
    std::fs::write(&index, page)
        .into_diagnostic()
        .wrap_err_with(|| format!("writing {}", index.display()))?;
    tracing::info!(sections = data::sections(&bench).len(), "report written");
    println!("wrote {}", index.display());
    Ok(())
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

/// Copies bench.json and every picture it names into `out`, so the page
/// there links them by the same relative paths.
fn copy_run(bench: &data::Bench, json: &Path, out: &Path) -> Result<()> {
    let from = json.parent().unwrap_or(Path::new("."));
    let copy = |src: PathBuf, dst: PathBuf| -> Result<()> {
        if let Some(dir) = dst.parent() {
            std::fs::create_dir_all(dir)
                .into_diagnostic()
                .wrap_err_with(|| format!("creating {}", dir.display()))?;
        }
        std::fs::copy(&src, &dst)
            .into_diagnostic()
            .wrap_err_with(|| format!("copying {} to {}", src.display(), dst.display()))?;
        Ok(())
    };
    copy(json.to_path_buf(), out.join("bench.json"))?;
    let mut files: Vec<&str> = bench.cells.iter().flat_map(data::Cell::files).collect();
    files.sort_unstable();
    files.dedup();
    for rel in files {
        copy(from.join(rel), out.join(rel))?;
    }
    tracing::info!(from = %from.display(), to = %out.display(), "copied the run's pictures");
    Ok(())
}
