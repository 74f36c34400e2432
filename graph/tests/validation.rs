//! One small bad graph per validation error. The line the error must point at
//! carries a `// <-` marker; each test checks the kind, that line, and the
//! names the message must mention.

use strandgraph_graph::{ErrorKind, GraphError, KindList, Quantities, compile_str};

fn registry() -> KindList {
    KindList::new(["test.produce", "test.consume", "common.clear", "test.draw"])
}

fn marker_line(src: &str) -> usize {
    src.lines()
        .position(|l| l.contains("// <-"))
        .expect("test source has a `// <-` marker")
        + 1
}

fn expect_error(src: &str, kind: ErrorKind, names: &[&str]) -> GraphError {
    let errors = match compile_str("bad.ron", src, &registry(), 1) {
        Ok(_) => panic!("expected {kind:?}, but the graph compiled"),
        Err(e) => e,
    };
    let err = errors
        .0
        .iter()
        .find(|e| e.kind == kind)
        .unwrap_or_else(|| panic!("expected {kind:?}, got {:?}: {errors}", errors.kinds()))
        .clone();
    assert_eq!(err.line, marker_line(src), "wrong line for: {err}");
    assert_eq!(err.file, "bad.ron");
    for name in names {
        assert!(
            err.message.contains(name),
            "message `{}` does not name `{name}`",
            err.message
        );
    }
    let shown = err.to_string();
    assert!(
        shown.starts_with(&format!("bad.ron:{}:", err.line)),
        "display lacks location: {shown}"
    );
    err
}

#[test]
fn syntax_error_points_at_the_offending_token() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "a", size: Bytes(16), lifetime: Forever), // <-
    ],
    passes: [],
    outputs: [],
)"#;
    expect_error(src, ErrorKind::Syntax, &["Forever"]);
}

#[test]
fn unknown_resource() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "positions", size: PerElement(Vertices, 16), lifetime: Imported),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "skin", kind: "test.produce",
             reads: ["positons"], // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let e = expect_error(src, ErrorKind::UnknownResource, &["positons", "skin"]);
    let help = miette::Diagnostic::help(&e)
        .map(|h| h.to_string())
        .unwrap_or_default();
    assert!(help.contains("positions"), "no suggestion: {help}");
}

#[test]
fn unknown_pass_kind_with_suggestion() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p",
             kind: "test.prodcue", // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let e = expect_error(src, ErrorKind::UnknownPassKind, &["test.prodcue", "`p`"]);
    let help = miette::Diagnostic::help(&e)
        .map(|h| h.to_string())
        .unwrap_or_default();
    assert!(help.contains("test.produce"), "no suggestion: {help}");
}

#[test]
fn duplicate_resource_name() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "a", size: Bytes(16)),
        Buffer(name: "a", size: Bytes(32)), // <-
    ],
    passes: [],
    outputs: [],
)"#;
    expect_error(src, ErrorKind::DuplicateName, &["`a`"]);
}

#[test]
fn duplicate_pass_name() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "test.produce", writes: ["out"]),
        Pass(name: "p", kind: "test.consume", reads: ["out"]), // <-
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::DuplicateName, &["`p`"]);
}

#[test]
fn transient_read_before_any_write() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "scratch", size: Bytes(64)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "use", kind: "test.consume",
             reads: ["scratch"], // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::ReadBeforeWrite, &["use", "scratch"]);
}

#[test]
fn atomic_update_before_any_write() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "counter", size: Bytes(4)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "count", kind: "test.produce",
             atomics: ["counter"]), // <-
        Pass(name: "use", kind: "test.consume", reads: ["counter"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::ReadBeforeWrite, &["count", "counter"]);
}

#[test]
fn history_never_written() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "prev", size: Bytes(64), lifetime: History),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "motion", kind: "test.consume",
             reads: ["prev"], // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::ReadBeforeWrite, &["motion", "prev"]);
}

#[test]
fn cycle_names_the_passes_on_it() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "a", size: Bytes(16)),
        Buffer(name: "b", size: Bytes(16)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "first", kind: "test.produce", reads: ["b"], writes: ["a"]), // <-
        Pass(name: "second", kind: "test.produce", reads: ["a"], writes: ["b"]),
        Pass(name: "last", kind: "test.consume", reads: ["a"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let e = expect_error(
        src,
        ErrorKind::Cycle,
        &["`first`", "`second`", "(a)", "(b)"],
    );
    assert!(
        !e.message.contains("last"),
        "`last` is not on the cycle: {}",
        e.message
    );
}

#[test]
fn two_unordered_writers() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "lights", size: Bytes(64)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "sun", kind: "test.produce", writes: ["lights"]),
        Pass(name: "lamps", kind: "test.produce",
             writes: ["lights"]), // <-
        Pass(name: "shade", kind: "test.consume", reads: ["lights"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(
        src,
        ErrorKind::UnorderedWriters,
        &["sun", "lamps", "lights"],
    );
}

#[test]
fn ordered_writers_are_accepted() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "x", size: Bytes(64)),
        Buffer(name: "y", size: Bytes(64)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "a", kind: "test.produce", writes: ["x", "y"]),
        Pass(name: "b", kind: "test.produce", reads: ["y"], writes: ["x"]),
        Pass(name: "c", kind: "test.consume", reads: ["x"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let plan = compile_str("ok.ron", src, &registry(), 1).unwrap();
    assert!(
        plan.dependencies
            .iter()
            .any(|d| d.from == 0 && d.to == 1 && d.hazard.short() == "WAW")
    );
}

#[test]
fn two_passes_making_a_version_of_the_same_resource() {
    let src = r#"Graph(
    name: "g",
    resources: [Image(name: "color", format: Rgba16Float, size: Screen, lifetime: Imported)],
    passes: [
        Pass(name: "bloom", kind: "test.produce", writes: ["color -> color.bloom"]),
        Pass(name: "fog", kind: "test.produce",
             writes: ["color -> color.fog"]), // <-
    ],
    outputs: ["color.bloom", "color.fog"],
)"#;
    expect_error(src, ErrorKind::UnorderedWriters, &["bloom", "fog", "color"]);
}

#[test]
fn queue_cannot_rasterize_on_async_compute() {
    let src = r#"Graph(
    name: "g",
    resources: [Image(name: "out", format: Rgba8Unorm, size: Screen, lifetime: Imported)],
    passes: [
        Pass(name: "compose", kind: "test.draw", queue: AsyncCompute,
             writes: ["color:out"]), // <-
    ],
    outputs: ["out"],
)"#;
    expect_error(
        src,
        ErrorKind::QueueCannotAccess,
        &["compose", "async-compute", "color", "out"],
    );
}

#[test]
fn transfer_queue_only_copies() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "src", size: Bytes(64), lifetime: Imported),
        Buffer(name: "out", size: Bytes(64), lifetime: Imported),
    ],
    passes: [
        Pass(name: "upload", kind: "test.produce", queue: Transfer,
             reads: ["copy:src"],
             writes: ["out"]), // <-
    ],
    outputs: ["out"],
)"#;
    expect_error(
        src,
        ErrorKind::QueueCannotAccess,
        &["upload", "transfer", "storage", "out"],
    );
}

#[test]
fn output_nobody_writes() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "in", size: Bytes(16), lifetime: Imported),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [Pass(name: "p", kind: "test.consume", reads: ["in"])],
    outputs: [
        "out", // <-
    ],
)"#;
    expect_error(src, ErrorKind::OutputNotWritten, &["out"]);
}

#[test]
fn sampling_a_buffer_is_a_bad_access() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "depth", size: Bytes(16), lifetime: Imported),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "p", kind: "test.produce",
             reads: ["sampled:depth"], // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::BadAccess, &["sampled:depth", "buffer"]);
}

#[test]
fn sample_counts_are_those_attachments_have() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Image(name: "depth", format: D32Float, size: Screen,
              samples: 3), // <-
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "p", kind: "test.draw", writes: ["depth:depth", "out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::Size, &["depth", "3 samples"]);
}

#[test]
fn a_multisampled_image_is_only_an_attachment() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Image(name: "depth", format: D32Float, size: Screen, samples: 4),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "p", kind: "test.draw", writes: ["depth:depth", "out"]),
        Pass(name: "q", kind: "test.consume",
             reads: ["sampled:depth"], // <-
             writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    expect_error(
        src,
        ErrorKind::BadAccess,
        &["sampled:depth", "multisampled"],
    );
}

#[test]
fn unknown_usage_prefix() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "test.produce",
             writes: ["texture:out"]), // <-
    ],
    outputs: ["out"],
)"#;
    expect_error(src, ErrorKind::BadAccess, &["texture"]);
}

#[test]
fn zero_sized_resource_is_reported_at_instantiation() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "per_strand", size: PerElement(Strands, 16)), // <-
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "a", kind: "test.produce", writes: ["per_strand"]),
        Pass(name: "b", kind: "test.consume", reads: ["per_strand"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let plan = compile_str("bad.ron", src, &registry(), 1).unwrap();
    let q = Quantities {
        strands: 0,
        ..Quantities::example()
    };
    let err = plan.instantiate(&q).unwrap_err();
    let e = err.first();
    assert_eq!(e.kind, ErrorKind::Size);
    assert_eq!(e.line, marker_line(src));
    assert!(
        e.message.contains("per_strand") && e.message.contains("zero"),
        "{}",
        e.message
    );
}

#[test]
fn optional_scene_content_may_be_absent() {
    // No head mesh: a triangle buffer keeps one placeholder element.
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "triangles", size: PerElement(Triangles, 64), lifetime: Imported),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "b", kind: "test.consume", reads: ["triangles"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let plan = compile_str("no_mesh.ron", src, &registry(), 1).unwrap();
    let q = Quantities {
        triangles: 0,
        ..Quantities::example()
    };
    let instance = plan.instantiate(&q).unwrap();
    assert_eq!(instance.sizes[0].bytes, 64);
}

#[test]
fn a_capped_size_grows_with_the_scene_up_to_its_cap() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "room", size: Capped(quantity: Strands, per: 12, header: 16, at_most: 1000), lifetime: Imported),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "b", kind: "test.consume", reads: ["room"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let plan = compile_str("capped.ron", src, &registry(), 1).unwrap();
    for (strands, bytes) in [(10, 136), (82, 1000), (1 << 40, 1000), (u64::MAX, 1000)] {
        let q = Quantities {
            strands,
            ..Quantities::example()
        };
        let instance = plan.instantiate(&q).unwrap();
        assert_eq!(instance.sizes[0].bytes, bytes, "{strands} strands");
    }
}

#[test]
fn a_pass_keeps_naga_s_loop_counters_where_it_says_so() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Buffer(name: "a", size: Bytes(16)),
        Buffer(name: "out", size: Bytes(16), lifetime: Imported),
    ],
    passes: [
        Pass(name: "make", kind: "test.produce", writes: ["a"], loop_bounding: true),
        Pass(name: "use", kind: "test.consume", reads: ["a"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let plan = compile_str("loops.ron", src, &registry(), 1).unwrap();
    let kept = |name: &str| {
        let p = plan.graph.passes.iter().find(|p| p.name == name).unwrap();
        p.loop_bounding
    };
    assert!(kept("make"));
    assert!(!kept("use"));
}

#[test]
fn several_errors_are_reported_together() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "nope", reads: ["missing"], writes: ["out"]),
    ],
    outputs: ["out"],
)"#;
    let errors = compile_str("bad.ron", src, &registry(), 1).unwrap_err();
    assert_eq!(
        errors.kinds(),
        vec![ErrorKind::UnknownPassKind, ErrorKind::UnknownResource]
    );
}

#[test]
fn versions_order_old_readers_before_the_in_place_writer() {
    let src = r#"Graph(
    name: "g",
    resources: [
        Image(name: "depth", format: D32Float, size: Screen),
        Buffer(name: "hiz", size: Bytes(64)),
        Image(name: "out", format: Rgba8Unorm, size: Screen, lifetime: Imported),
    ],
    passes: [
        Pass(name: "hair", kind: "test.draw", reads: ["hiz"], writes: ["depth:depth -> depth.hair", "color:out"]),
        Pass(name: "prepass", kind: "test.draw", writes: ["depth:depth"]),
        Pass(name: "downsample", kind: "test.produce", reads: ["sampled:depth"], writes: ["hiz"]),
        Pass(name: "fog", kind: "test.produce", reads: ["sampled:depth.hair"], writes: ["out -> out.fogged"]),
    ],
    outputs: ["out.fogged"],
)"#;
    let plan = compile_str("ok.ron", src, &registry(), 1).unwrap();
    let order: Vec<&str> = plan.order.iter().map(|&p| plan.pass_name(p)).collect();
    assert_eq!(order, ["prepass", "downsample", "hair", "fog"]);
    // Versions share their resource's memory: one lifetime, one placement.
    let depth = plan.graph.resource_id("depth").unwrap();
    assert_eq!(
        plan.graph
            .physical(plan.graph.resource_id("depth.hair").unwrap()),
        depth
    );
    let l = plan.lifetimes.iter().find(|l| l.resource == depth).unwrap();
    assert_eq!((l.first, l.last), (0, 3));
    assert!(
        plan.lifetimes
            .iter()
            .all(|l| plan.graph.resources[l.resource].version_of.is_none())
    );
}

/// A registry whose `test.produce` takes one parameter, `tile` (a number up
/// to 64): the compiler must report what the registry says at the key.
struct ParamRegistry(KindList);

impl strandgraph_graph::PassRegistry for ParamRegistry {
    fn contains(&self, kind: &str) -> bool {
        self.0.contains(kind)
    }
    fn kinds(&self) -> Vec<&str> {
        self.0.kinds()
    }
    fn check_params(
        &self,
        kind: &str,
        params: &ron::Value,
    ) -> Result<(), strandgraph_graph::ParamProblem> {
        let problem = |key: &str, message: &str| strandgraph_graph::ParamProblem {
            key: key.into(),
            message: message.into(),
        };
        let ron::Value::Map(m) = params else {
            return match params {
                ron::Value::Unit => Ok(()),
                _ => Err(problem("", "expected a map")),
            };
        };
        for (k, v) in m.iter() {
            let ron::Value::String(k) = k else { continue };
            match (kind, k.as_str(), v) {
                ("test.produce", "tile", ron::Value::Number(n)) if n.into_f64() <= 64.0 => {}
                ("test.produce", "tile", _) => return Err(problem(k, "expected a number <= 64")),
                _ => return Err(problem(k, "unknown, did you mean `tile`?")),
            }
        }
        Ok(())
    }
}

fn expect_param_error(src: &str, names: &[&str]) -> GraphError {
    let registry = ParamRegistry(registry());
    let errors = compile_str("bad.ron", src, &registry, 1).expect_err("graph compiled");
    let err = errors.first().clone();
    assert_eq!(err.kind, ErrorKind::BadParam, "{errors}");
    assert_eq!(err.line, marker_line(src), "wrong line for: {err}");
    for name in names {
        assert!(
            err.message.contains(name),
            "`{}` lacks `{name}`",
            err.message
        );
    }
    err
}

#[test]
fn misspelt_param_points_at_its_key_and_names_the_closest() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "test.produce", writes: ["out"],
             params: {
                 "tile": 16,
                 "tiel": 32, // <-
             }),
    ],
    outputs: ["out"],
)"#;
    let e = expect_param_error(
        src,
        &["`p`", "test.produce", "`tiel`", "did you mean `tile`"],
    );
    // At the key itself: line 8, column 18.
    assert_eq!(e.col, 18);
    assert!(e.to_string().starts_with("bad.ron:8:18: pass `p`"), "{e}");
}

#[test]
fn param_out_of_range_points_at_its_value() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "test.produce", writes: ["out"],
             params: {"tile": 128}), // <-
    ],
    outputs: ["out"],
)"#;
    let e = expect_param_error(src, &["`tile`", "<= 64"]);
    assert_eq!(e.col, 31, "{e}");
}

#[test]
fn params_that_are_not_a_map_point_at_the_params() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [
        Pass(name: "p", kind: "test.produce", writes: ["out"],
             params: [1, 2]), // <-
    ],
    outputs: ["out"],
)"#;
    let e = expect_param_error(src, &["`p`", "expected a map"]);
    assert_eq!(e.col, 22, "{e}");
}

#[test]
fn name_only_registries_accept_any_params() {
    let src = r#"Graph(
    name: "g",
    resources: [Buffer(name: "out", size: Bytes(16), lifetime: Imported)],
    passes: [Pass(name: "p", kind: "test.produce", writes: ["out"], params: {"anything": 1})],
    outputs: ["out"],
)"#;
    compile_str("ok.ron", src, &registry(), 1).unwrap();
}
