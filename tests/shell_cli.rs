//! `strandgraph completions` and `strandgraph man`: generated from the clap
//! definitions, so every subcommand and option appears in both.

use std::process::{Command, Output};

fn strandgraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .args(args)
        .output()
        .expect("strandgraph runs")
}

const SUBCOMMANDS: [&str; 11] = [
    "graph",
    "info",
    "render",
    "bench",
    "agree",
    "compare",
    "report",
    "tables",
    "view",
    "completions",
    "man",
];

#[test]
fn completions_name_every_subcommand_and_option() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = strandgraph(&["completions", shell]);
        assert!(
            out.status.success(),
            "{shell}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let script = String::from_utf8_lossy(&out.stdout);
        // Options bare: fish spells them `-l coverage`.
        for word in SUBCOMMANDS
            .iter()
            .chain(&["coverage", "backend", "tonemap"])
        {
            assert!(script.contains(word), "{shell} completions lack `{word}`");
        }
    }
    let out = strandgraph(&["completions", "tcsh"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "an unknown shell is a usage error"
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("possible values"));
}

#[test]
fn man_writes_a_page_per_subcommand() {
    let dir = std::env::temp_dir().join(format!("strandgraph-man-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = strandgraph(&["man", "--out", dir.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = |name: &str| {
        std::fs::read_to_string(dir.join(format!("{name}.1")))
            .unwrap_or_else(|e| panic!("{name}.1: {e}"))
    };
    assert!(page("strandgraph").contains(".TH strandgraph 1"));
    for sub in SUBCOMMANDS {
        let text = page(&format!("strandgraph-{sub}"));
        assert!(text.contains(&format!(".TH strandgraph-{sub} 1")), "{sub}");
        assert!(
            text.contains(&format!("strandgraph {sub}")),
            "{sub}: no synopsis"
        );
    }
    // The examples of `--help` are in the pages too.
    assert!(page("strandgraph-render").contains("strandgraph render \\-\\-demo"));
    // Without --out: the top page on stdout.
    let top = strandgraph(&["man"]);
    assert!(String::from_utf8_lossy(&top.stdout).starts_with(".ie"));
    let _ = std::fs::remove_dir_all(&dir);
}
