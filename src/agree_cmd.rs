//! `strandgraph agree`: every pass of a scene's graph alone on the CPU
//! simulator and the GPU backends, outputs compared (see `strandgraph::agree`).

use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::PathBuf;
use strandgraph::agree;
use strandgraph::frame::{parse_size, prepare_with};
use strandgraph::runner::Backend;

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph agree scenes/showcase.ron
  strandgraph agree scenes/showcase.ron --graph scenes/graphs/lipp.ron --pass raster --backend ash")]
pub struct Args {
    /// The scene (RON), e.g. scenes/showcase.ron.
    #[arg(required_unless_present = "summarize")]
    pub scene: Option<PathBuf>,
    /// Run this graph instead of the scene's.
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// The GPU backends to compare with the CPU simulator (repeatable).
    #[arg(long = "backend", value_enum, default_values = ["wgpu", "ash"])]
    pub backends: Vec<Backend>,
    /// Override the resolution, as WxH.
    #[arg(long)]
    pub size: Option<String>,
    /// Only passes whose name contains this.
    #[arg(long)]
    pub pass: Option<String>,
    /// Override a pass parameter, as PASS.PARAM=VALUE (repeatable).
    #[arg(long = "param", value_name = "PASS.PARAM=VALUE")]
    pub params: Vec<String>,
    /// Write the CPU's and the GPU's words of every failing output here.
    #[arg(long, value_name = "DIR")]
    pub dump: Option<PathBuf>,
    /// Also write every check as JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
    /// Run nothing: print Markdown tables of earlier `--json` files (what
    /// README's per-pass agreement tables are generated from).
    #[arg(long, num_args = 1.., value_name = "FILE.json", conflicts_with = "scene")]
    pub summarize: Vec<PathBuf>,
}

fn summarize(files: &[PathBuf]) -> Result<()> {
    for file in files {
        let text = std::fs::read_to_string(file)
            .into_diagnostic()
            .wrap_err_with(|| format!("reading {}", file.display()))?;
        let json: serde_json::Value = serde_json::from_str(&text)
            .into_diagnostic()
            .wrap_err_with(|| format!("parsing {}", file.display()))?;
        let title = file
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let md = agree::summary::markdown(&title, &json)
            .map_err(|e| miette::miette!("{}: {e}", file.display()))?;
        println!("{md}");
    }
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let Some(scene) = &args.scene else {
        return summarize(&args.summarize);
    };
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let p = prepare_with(scene, args.graph.as_deref(), size, &args.params)?;
    let gpus: Vec<Backend> = args
        .backends
        .iter()
        .copied()
        .filter(|b| b.is_gpu())
        .collect();
    let captured = agree::capture(&p)?;
    if let Some(dir) = &args.dump {
        std::fs::create_dir_all(dir).into_diagnostic()?;
    }
    let checks = agree::check_all(
        &p.plan,
        &p.upload,
        &captured,
        &gpus,
        args.pass.as_deref(),
        args.dump.as_deref(),
    )?;
    print!("{}", agree::table(&checks));
    if let Some(path) = &args.json {
        let json = serde_json::to_string_pretty(&checks).into_diagnostic()?;
        std::fs::write(path, json).into_diagnostic()?;
    }
    let failed: Vec<String> = checks
        .iter()
        .filter(|c| !c.passed())
        .map(|c| format!("{} on {}", c.pass, c.backend))
        .collect();
    if failed.is_empty() {
        println!("{} checks: all outputs agree", checks.len());
        Ok(())
    } else {
        Err(miette::miette!("outputs disagree: {}", failed.join(", ")))
    }
}
