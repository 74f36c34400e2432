//! `strandgraph`: the command-line front end.
//!
//! Each subcommand lives in its own module; `main` only parses arguments,
//! sets up logging and turns errors into diagnostics with exit code 2.

mod agree_cmd;
mod bench_cmd;
mod compare_cmd;
mod graph_cmd;
mod info;
mod render_cmd;
mod report_cmd;
mod shell_cmd;
mod tables_cmd;
mod view_cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "strandgraph", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compile a render graph (RON) and print its plan: queue lanes, lifetimes, aliasing, sync.
    Graph(graph_cmd::Args),
    /// Print strands, points, segments, bounds and memory of a scene, groom or mesh file.
    Info(info::Args),
    /// Render a scene on a backend to PNG and print per-pass times.
    Render(render_cmd::Args),
    /// Time pipeline variants at close/mid/far views on backends, with a roofline (Lipp's Table 1).
    Bench(bench_cmd::Args),
    /// Run every pass of a scene's graph alone on the CPU simulator and the GPU backends, and compare every output.
    Agree(agree_cmd::Args),
    /// How two pictures differ (FLIP): a render against the reference, say.
    Compare(compare_cmd::Args),
    /// Run the bench with pictures and write an HTML page: pictures beside the reference, FLIP maps, time-versus-FLIP chart, per-pass bars.
    Report(report_cmd::Args),
    /// Open a window on a scene: any graph live on wgpu, split-screen A/B, parameters as widgets, per-pass GPU times.
    View(view_cmd::Args),
    /// Regenerate (or --check) README's tables from the measurements under benches/results/.
    Tables(tables_cmd::Args),
    /// Print the shell completion script for bash, zsh, fish, elvish or PowerShell.
    Completions(shell_cmd::CompletionsArgs),
    /// Write the manual pages (roff), one per subcommand.
    Man(shell_cmd::ManArgs),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Graph(args) => graph_cmd::run(args),
        Command::Info(args) => info::run(args),
        Command::Render(args) => render_cmd::run(args),
        Command::Bench(args) => bench_cmd::run(args),
        Command::Agree(args) => agree_cmd::run(args),
        Command::Compare(args) => compare_cmd::run(args),
        Command::Report(args) => report_cmd::run(args),
        Command::Tables(args) => tables_cmd::run(args),
        Command::View(args) => view_cmd::run(args),
        Command::Completions(args) => shell_cmd::completions::<Cli>(args),
        Command::Man(args) => shell_cmd::man::<Cli>(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(report) => {
            eprintln!("{report:?}");
            ExitCode::from(2)
        }
    }
}
