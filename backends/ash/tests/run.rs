//! The ash backend runs the showcase's Kulikov visibility graph under the
//! Khronos validation layer with synchronization validation: any validation
//! message fails the run (lavapipe in CI; `scripts/test.sh` installs the
//! layer). Correctness against the CPU reference is `tests/diff_ash.rs` at
//! the workspace root.

use std::path::Path;
use strandgraph_ash::{AshBackend, Session, Validation};
use strandgraph_assets::Scene;
use strandgraph_graph::{Plan, compile_file};
use strandgraph_passes::Registry;
use strandgraph_passes::upload::{Upload, upload};

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

fn validated() -> AshBackend {
    AshBackend {
        validation: Validation::Sync,
        ..AshBackend::default()
    }
}

/// The showcase's Kulikov visibility graph at 96x54, opened validated.
fn visibility_session() -> (Plan, Upload, Session) {
    let scene = Scene::load(&root().join("scenes/showcase.ron")).unwrap();
    let plan = compile_file(
        &root().join("scenes/graphs/kulikov_visibility.ron"),
        &Registry,
        scene.counts().models as u32,
    )
    .unwrap();
    let up = upload(&scene, 96, 54);
    let instance = plan.instantiate(&up.quantities).unwrap();
    let session = validated()
        .open(&plan, &instance)
        .unwrap_or_else(|e| panic!("{e}"));
    (plan, up, session)
}

#[test]
fn visibility_graph_runs_clean_under_sync_validation_for_two_frames() {
    let (plan, up, mut session) = visibility_session();
    for n in &session.notes {
        eprintln!("ash: {n}");
    }
    for frame in 0..2 {
        let f = session
            .run(&up)
            .unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        assert_eq!(f.timings.len(), plan.order.len());
        for t in &f.timings {
            eprintln!(
                "{:<16} {:<12} family {} groups {:>10?} {:?} ms",
                t.name,
                t.queue.to_string(),
                t.family,
                t.workgroups,
                t.millis
            );
        }
    }
    let layers = session.read("debug_layers").unwrap().unwrap();
    assert_eq!(layers.len(), 96 * 54);
    assert!(
        layers.iter().any(|&w| w >> 24 != 0),
        "some hair coverage reaches the debug view"
    );
    assert!(session.transient_bytes <= session.unaliased_bytes);
}

/// The smallest graph: one compute pass clearing an imported buffer,
/// read back through the session, twice.
#[test]
fn a_clear_pass_writes_its_value() {
    let plan = strandgraph_graph::compile_str(
        "clear.ron",
        r#"Graph(
            name: "clear",
            resources: [Buffer(name: "out", size: Bytes(1000), lifetime: Imported)],
            passes: [Pass(name: "clear", kind: "common.clear", queue: AsyncCompute, params: {"value": 7}, writes: ["out"])],
            outputs: ["out"],
        )"#,
        &Registry,
        1,
    )
    .unwrap();
    let instance = plan.instantiate(&Default::default()).unwrap();
    let mut session = validated()
        .open(&plan, &instance)
        .unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..2 {
        let frame = session
            .run(&Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(frame.timings.len(), 1);
        assert_eq!(frame.timings[0].workgroups, Some(1));
        assert_eq!(session.read("out").unwrap().unwrap(), vec![7; 250]);
    }
    assert_eq!(session.read("no such resource").unwrap(), None);
}

/// 64-bit atomicMin (the roofline's `bench.atomic_min64`) needs
/// shaderInt64 and shaderBufferInt64Atomics and the Int64/Int64Atomics
/// SPIR-V capabilities, enabled only because that pass needs them.
#[test]
fn int64_atomics_are_enabled_for_the_pass_that_needs_them() {
    let plan = compile_file(&root().join("scenes/graphs/roofline.ron"), &Registry, 1).unwrap();
    let q = strandgraph_graph::Quantities {
        width: 64,
        height: 32,
        ..Default::default()
    };
    let instance = plan.instantiate(&q).unwrap();
    let mut session = validated()
        .open(&plan, &instance)
        .unwrap_or_else(|e| panic!("{e}"));
    let features = &session.notes[0];
    assert!(
        features.contains("shaderBufferInt64Atomics") && features.contains("shaderInt64"),
        "{features}"
    );
    session
        .run(&Default::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let words = session.read("atomics_u64").unwrap().unwrap();
    assert_eq!(words.len(), 64 * 32 * 2);
    assert!(
        words.chunks(2).any(|w| w != [u32::MAX, u32::MAX]),
        "some atomicMin landed"
    );
}

/// A frame timed level by level ([`strandgraph_ash::Session::run_levels_timed`])
/// under synchronization validation: every pass is in exactly one level,
/// a batch's levels follow one another, and the frame's result is the
/// frame's (the debug view has hair in it, as with per-pass stamps).
#[test]
fn a_frame_timed_level_by_level_lists_every_pass_once_in_order() {
    let (plan, up, mut session) = visibility_session();
    session.run(&up).unwrap_or_else(|e| panic!("{e}"));
    let levels = session
        .run_levels_timed(&up)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut named: Vec<&str> = levels
        .iter()
        .flat_map(|l| l.passes.iter().map(String::as_str))
        .collect();
    named.sort_unstable();
    let mut live: Vec<&str> = plan.order.iter().map(|&p| plan.pass_name(p)).collect();
    live.sort_unstable();
    assert_eq!(named, live, "each live pass in one level");
    for pair in levels.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        assert!(a.span.0 >= 0.0 && a.span.0 <= a.span.1, "{a:?}");
        if (a.queue, a.batch) == (b.queue, b.batch) {
            assert_eq!(a.span.1, b.span.0, "{b:?} begins where {a:?} ends");
        }
    }
    let layers = session.read("debug_layers").unwrap().unwrap();
    assert!(layers.iter().any(|&w| w >> 24 != 0));
}
