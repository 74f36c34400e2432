//! `strandgraph info`: owned by the assets work (issue 3); replaced there.

#[derive(clap::Args)]
pub struct Args {
    /// A scene (.ron), groom (.hair, .tfx) or mesh (.obj) file.
    pub file: std::path::PathBuf,
}

pub fn run(args: Args) -> miette::Result<()> {
    Err(miette::miette!("{}: `info` is not built yet", args.file.display()))
}
