//! `strandgraph agree`: every pass of a scene's graph alone on the CPU
//! simulator and the GPU backends, outputs compared (see `strandgraph::agree`).

use miette::{IntoDiagnostic, Result};
use std::path::PathBuf;
use strandgraph::agree;
use strandgraph::frame::{parse_size, prepare_with};
use strandgraph::runner::Backend;

#[derive(clap::Args)]
pub struct Args {
    /// The scene (RON), e.g. scenes/showcase.ron.
    pub scene: PathBuf,
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
}

pub fn run(args: Args) -> Result<()> {
    let size = args.size.as_deref().map(parse_size).transpose()?;
    let p = prepare_with(&args.scene, args.graph.as_deref(), size, &args.params)?;
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
