//! `strandgraph tables`: regenerate (or check) README's tables from the
//! measurements committed under `benches/results/` (see `strandgraph::tables`).

use miette::{IntoDiagnostic, Result, WrapErr, miette};
use std::path::PathBuf;

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph tables README.md --check
  strandgraph tables README.md")]
pub struct Args {
    /// The Markdown file whose generated blocks to rewrite.
    #[arg(default_value = "README.md")]
    pub file: PathBuf,
    /// Write nothing; fail if a block differs from what its inputs give.
    #[arg(long)]
    pub check: bool,
}

pub fn run(args: Args) -> Result<()> {
    let doc = std::fs::read_to_string(&args.file)
        .into_diagnostic()
        .wrap_err_with(|| format!("reading {}", args.file.display()))?;
    // Inputs are named relative to the document's folder.
    let root = args
        .file
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map_or_else(|| PathBuf::from("."), PathBuf::from);
    let (new, changed) = strandgraph::tables::regenerate(&doc, &root)
        .map_err(|e| miette!("{}: {e}", args.file.display()))?;
    let lines = changed
        .iter()
        .map(|l| format!("{}:{l}", args.file.display()))
        .collect::<Vec<_>>();
    if args.check {
        if changed.is_empty() {
            println!("{}: generated tables are current", args.file.display());
            return Ok(());
        }
        return Err(miette!(
            "generated tables are out of date at {} (run `strandgraph tables {}`)",
            lines.join(", "),
            args.file.display()
        ));
    }
    if !changed.is_empty() {
        std::fs::write(&args.file, new)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", args.file.display()))?;
    }
    println!(
        "{}: {} block(s) rewritten",
        args.file.display(),
        changed.len()
    );
    Ok(())
}
