//! `strandgraph completions SHELL` and `strandgraph man`: the shell
//! completions and manual pages, generated from the clap definitions so
//! they never disagree with `--help`.

use clap::CommandFactory;
use miette::{IntoDiagnostic, Result, WrapErr};
use std::path::PathBuf;

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph completions bash > ~/.local/share/bash-completion/completions/strandgraph
  strandgraph completions zsh > ~/.zfunc/_strandgraph
  strandgraph completions fish > ~/.config/fish/completions/strandgraph.fish")]
pub struct CompletionsArgs {
    /// The shell to complete for.
    pub shell: clap_complete::Shell,
}

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph man --out ~/.local/share/man/man1   (then: man strandgraph-render)
  strandgraph man | man -l -")]
pub struct ManArgs {
    /// Write strandgraph.1 and one strandgraph-SUBCOMMAND.1 per subcommand
    /// here; without it, print strandgraph.1 to stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Prints the completion script of `args.shell` for the CLI `C`.
pub fn completions<C: CommandFactory>(args: CompletionsArgs) -> Result<()> {
    let mut cmd = C::command();
    clap_complete::generate(args.shell, &mut cmd, "strandgraph", &mut std::io::stdout());
    Ok(())
}

/// Writes the manual pages of the CLI `C`.
pub fn man<C: CommandFactory>(args: ManArgs) -> Result<()> {
    let cmd = C::command();
    let Some(dir) = args.out else {
        return clap_mangen::Man::new(cmd)
            .render(&mut std::io::stdout())
            .into_diagnostic();
    };
    std::fs::create_dir_all(&dir)
        .into_diagnostic()
        .wrap_err_with(|| format!("creating {}", dir.display()))?;
    let mut pages = vec![("strandgraph".to_string(), cmd.clone())];
    pages.extend(
        cmd.get_subcommands()
            .filter(|s| s.get_name() != "help")
            .map(|s| {
                let page = s
                    .clone()
                    .display_name(format!("strandgraph-{}", s.get_name()))
                    .bin_name(format!("strandgraph {}", s.get_name()));
                (format!("strandgraph-{}", s.get_name()), page)
            }),
    );
    for (name, page) in pages {
        let path = dir.join(format!("{name}.1"));
        let mut bytes = Vec::new();
        clap_mangen::Man::new(page)
            .title(name.clone())
            .render(&mut bytes)
            .into_diagnostic()?;
        std::fs::write(&path, bytes)
            .into_diagnostic()
            .wrap_err_with(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
