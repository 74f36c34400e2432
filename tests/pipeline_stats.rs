//! `STRANDGRAPH_PIPELINE_STATS=1` on the ash backend, under the validation
//! layer: a device without `VK_KHR_pipeline_executable_properties` (lavapipe
//! in CI) renders exactly as without the variable; one with it (the H100)
//! logs every compute pipeline's statistics, and asking for them must not
//! upset the device (feature, extension and pipeline flag enabled together).

mod common;

use std::process::Command;

fn render(stats: bool, out: &std::path::Path) -> (bool, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_strandgraph"));
    cmd.args(["render", "scenes/distances/far.ron", "--backend", "ash"])
        .args(["--size", "96x54", "-o"])
        .arg(out)
        .current_dir(common::root())
        .env("STRANDGRAPH_VK_VALIDATION", "1")
        .env("RUST_LOG", "strandgraph_ash=info");
    if stats {
        cmd.env("STRANDGRAPH_PIPELINE_STATS", "1");
    } else {
        cmd.env_remove("STRANDGRAPH_PIPELINE_STATS");
    }
    let out = cmd.output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn pipeline_statistics_change_nothing_but_the_log() {
    let dir = common::out_dir("pipeline_stats");
    let (with, without) = (dir.join("with.png"), dir.join("without.png"));
    let (ok, log) = render(true, &with);
    assert!(ok, "{log}");
    let (ok_plain, plain_log) = render(false, &without);
    assert!(ok_plain, "{plain_log}");
    assert_eq!(
        std::fs::read(&with).unwrap(),
        std::fs::read(&without).unwrap(),
        "the same picture"
    );
    assert!(!plain_log.contains("pipeline statistics"));
    let logged = log.matches("pipeline statistics").count();
    eprintln!("{logged} pipelines reported statistics");
    if logged > 0 {
        // Every compute pass of the Lipp graph, not a few.
        assert!(logged >= 15, "{logged} of the graph's compute passes");
        assert!(log.contains("\"raster\""), "{log}");
    }
}
