//! `strandgraph graph`: compile a graph and print its plan.

#[derive(clap::Args)]
pub struct Args {
    /// The graph file (RON).
    pub file: std::path::PathBuf,
}

pub fn run(args: Args) -> miette::Result<()> {
    Err(miette::miette!("{}: graph compiler not built yet", args.file.display()))
}
