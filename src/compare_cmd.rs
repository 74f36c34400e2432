//! `strandgraph compare`: how two pictures differ, as FLIP (src/compare.rs):
//! a render against the reference, or the reference against itself at more
//! samples (its convergence, docs/reference.md).

use miette::{IntoDiagnostic, Result, WrapErr, miette};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph render scenes/distances/close.ron --graph scenes/graphs/kulikov_reference.ron -o ref.png
  strandgraph render scenes/distances/close.ron -o kulikov.png
  strandgraph compare ref.png kulikov.png --map error.png")]
pub struct Args {
    /// The reference picture (PNG, sRGB).
    pub reference: PathBuf,
    /// The picture to judge, of the same size.
    pub test: PathBuf,
    /// Also write the per-pixel FLIP error (magma colour map) here.
    #[arg(long)]
    pub map: Option<PathBuf>,
}

fn open(path: &Path) -> Result<image::RgbaImage> {
    Ok(image::open(path)
        .into_diagnostic()
        .wrap_err_with(|| format!("reading {}", path.display()))?
        .into_rgba8())
}

pub fn run(args: Args) -> Result<()> {
    let (reference, test) = (open(&args.reference)?, open(&args.test)?);
    let diff = strandgraph::compare::flip(&reference, &test).ok_or_else(|| {
        miette!(
            "{} is {}x{} but {} is {}x{}: FLIP compares pictures of one size",
            args.reference.display(),
            reference.width(),
            reference.height(),
            args.test.display(),
            test.width(),
            test.height()
        )
    })?;
    println!(
        "mean FLIP {:.4}, max {:.4} at {:?}; {} of {} pixels above 0.1",
        diff.mean,
        diff.max,
        diff.max_at,
        diff.pixels_over(0.1),
        reference.width() * reference.height()
    );
    if let Some(path) = &args.map {
        diff.error_map
            .save(path)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
