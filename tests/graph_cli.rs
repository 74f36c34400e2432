//! End-to-end tests of `strandgraph graph`: the plan printout, the exports,
//! and diagnostics with exit code 2.

use std::path::Path;
use std::process::{Command, Output, Stdio};

fn strandgraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_strandgraph"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("strandgraph runs")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn kulikov_plan_shows_async_compute_sync_points_and_memory() {
    let out = strandgraph(&["graph", "scenes/graphs/kulikov.ron"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = stdout(&out);
    for expected in [
        "async-compute  clear_cull",
        "graphics signals",
        "async-compute waits before `cull`",
        "graphics waits before `compose`",
        "Transient lifetimes",
        "Peak transient memory:",
        "with aliasing",
    ] {
        assert!(text.contains(expected), "missing `{expected}` in:\n{text}");
    }
}

#[test]
fn every_shipped_graph_compiles_through_the_cli() {
    for entry in
        std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/graphs")).unwrap()
    {
        let path = entry.unwrap().path();
        let out = strandgraph(&["graph", "--quiet", path.to_str().unwrap()]);
        assert!(
            out.status.success(),
            "{}: {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn dot_export_renders_with_graphviz() {
    let out = strandgraph(&[
        "graph",
        "--quiet",
        "--dot",
        "-",
        "scenes/graphs/kulikov.ron",
    ]);
    assert!(out.status.success());
    let dot = stdout(&out);
    assert!(dot.starts_with("digraph \"kulikov\""));
    let mut child = Command::new("dot")
        .arg("-Tsvg")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect(
            "Graphviz `dot` must be installed to check the DOT export (apt-get install graphviz)",
        );
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(dot.as_bytes())
        .unwrap();
    let rendered = child.wait_with_output().unwrap();
    assert!(
        rendered.status.success(),
        "dot rejected the export: {}",
        String::from_utf8_lossy(&rendered.stderr)
    );
    let svg = String::from_utf8_lossy(&rendered.stdout);
    assert!(
        svg.contains("<svg") && svg.contains("raster"),
        "unexpected SVG"
    );
}

#[test]
fn json_export_holds_plan_and_memory() {
    let out = strandgraph(&[
        "graph",
        "--quiet",
        "--json",
        "-",
        "--set",
        "width=1280",
        "--set",
        "height=720",
        "scenes/graphs/lipp.ron",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
    assert_eq!(v["plan"]["name"], "lipp");
    assert!(!v["plan"]["sync_points"].as_array().unwrap().is_empty());
    assert_eq!(v["instance"]["quantities"]["width"], 1280);
    let with = v["instance"]["memory"]["bytes_with_aliasing"]
        .as_u64()
        .unwrap();
    let without = v["instance"]["memory"]["bytes_without_aliasing"]
        .as_u64()
        .unwrap();
    assert!(with > 0 && with <= without + 4096, "{with} vs {without}");
}

#[test]
fn bad_graph_prints_a_diagnostic_and_exits_2() {
    let dir = std::env::temp_dir().join(format!("strandgraph-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.ron");
    std::fs::write(
        &path,
        "Graph(\n  name: \"g\",\n  resources: [],\n  passes: [\n    Pass(name: \"p\", kind: \"kulikov.raster\", reads: [\"nowhere\"]),\n  ],\n  outputs: [],\n)\n",
    )
    .unwrap();
    let out = strandgraph(&["graph", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.ron:5:"), "no file:line in: {err}");
    assert!(err.contains("nowhere"), "resource not named in: {err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn missing_file_exits_2() {
    let out = strandgraph(&["graph", "does/not/exist.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("does/not/exist.ron"));
}

#[test]
fn scene_sizes_the_plan_and_supplies_the_graph() {
    let out = strandgraph(&["graph", "--scene", "scenes/showcase.ron"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = stdout(&out);
    assert!(
        text.contains("graph `kulikov`"),
        "showcase runs the Kulikov graph:\n{text}"
    );
    // Sizes come from the scene, not the built-in example.
    let example = stdout(&strandgraph(&["graph", "scenes/graphs/kulikov.ron"]));
    let mem = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("Memory for"))
            .unwrap_or("")
            .to_string()
    };
    assert_ne!(mem(&text), mem(&example));
}

/// `--param` is checked like the graph's own parameters: a misspelt key
/// fails before anything renders, naming the pass, its kind and the closest
/// valid key; so does a value of the wrong type.
#[test]
fn misspelt_param_override_names_the_closest_key() {
    let out = strandgraph(&[
        "render",
        "scenes/showcase.ron",
        "--size",
        "64x36",
        "--param",
        "raster.loop_flatening=false",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    for expected in [
        "raster.loop_flatening=false",
        "kulikov.raster",
        "`loop_flatening`",
        "did you mean `loop_flattening`?",
    ] {
        assert!(err.contains(expected), "missing `{expected}` in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");

    let out = strandgraph(&[
        "render",
        "scenes/showcase.ron",
        "--size",
        "64x36",
        "--param",
        "raster.loop_flattening=3",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`loop_flattening`") && err.contains("boolean"),
        "{err}"
    );
}
