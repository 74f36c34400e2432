//! Every table README generates from `benches/results/` matches its file:
//! a number changed by hand, or a new measurement not carried into README,
//! fails here.

use std::process::Command;

#[test]
fn readme_tables_are_generated_from_committed_results() {
    let root = env!("CARGO_MANIFEST_DIR");
    let out = Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .args(["tables", "--check", &format!("{root}/README.md")])
        .output()
        .expect("running strandgraph tables");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let readme = std::fs::read_to_string(format!("{root}/README.md")).unwrap();
    let blocks = strandgraph::tables::blocks(&readme).unwrap();
    assert!(
        blocks.iter().any(|b| b.command[0] == "agree"),
        "README has no generated per-pass agreement table"
    );
}
