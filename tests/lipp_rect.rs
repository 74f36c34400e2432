//! The groom's screen rectangle (passes/src/lipp/rect.rs, ours) holds every
//! sample the rasterizer wrote, for every groom of the built-in scenes, on
//! the CPU simulator: `lipp.shade` shades nothing outside it, so a sample
//! outside would be hair cut off.
//!
//! Each groom's `lipp.shade` is checked with the bindings it ran with
//! (the simulator's per-pass capture, as the agreement tests use): the
//! G-buffer the rasterizer left, against the one it started from (the
//! clear's, which `lipp.clear_gbuffer` leaves stale outside the rectangle),
//! and the rectangle `lipp.lod_scan` put in `raster_args`.
//!
//! And the rectangle changes no pixel: two grooms drawn one after the other
//! on the simulator with its transients aliased, so that the G-buffer
//! outside the rectangle holds what was there before, give the same
//! output as with `lipp.lod_scan`'s `groom_rect` off (everything shaded
//! and cleared).

use std::collections::HashMap;
use std::path::Path;
use strandgraph::agree::capture;
use strandgraph::frame::{Prepared, prepare_with};
use strandgraph_cpu::CpuBackend;
use strandgraph_passes::lipp::payload::EMPTY;
use strandgraph_passes::lipp::rect::{ARGS_RECT_HI, ARGS_RECT_LO, Rect};

/// Per groom drawn: (its rectangle, its samples); panics on a sample outside.
fn grooms(scene: &str, graph: Option<&str>, (w, h): (u32, u32)) -> Vec<(Rect, usize)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph = graph.map(|g| root.join(g));
    // The capture holds no multisampled image: the hardware rasterizers'
    // graphs are checked at one sample.
    let overrides = match graph.as_deref().and_then(|g| g.file_stem()) {
        Some(s) if s.to_string_lossy().starts_with("hw_") => {
            vec![
                "strand_depth.samples=1".to_string(),
                "filter.msaa=1".to_string(),
            ]
        }
        _ => Vec::new(),
    };
    let p = prepare_with(
        &root.join(scene),
        graph.as_deref(),
        Some((w, h)),
        &overrides,
    )
    .unwrap_or_else(|e| panic!("{scene}: {e:?}"));
    let mut out = Vec::new();
    // Per groom (its G-buffer is its own copy of the transient, and the
    // compiler may interleave the grooms' passes): the G-buffer as the pass
    // after its clear found it, and whether the groom's last pass that
    // bound it was a clear.
    let mut cleared: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut after_clear: HashMap<u32, bool> = HashMap::new();
    for c in capture(&p).unwrap_or_else(|e| panic!("{scene}: {e:?}")) {
        let kind = p.plan.graph.passes[c.pass].kind.as_str();
        // Each unrolled copy carries its groom (graph/src/unroll.rs).
        let groom = p.plan.graph.passes[c.pass].model_index.unwrap_or(0);
        let words = |name: &str| c.bindings.iter().find(|(n, _)| n == name).map(|b| &b.1);
        let Some(g) = words("gbuffer") else { continue };
        if after_clear.get(&groom) == Some(&true) {
            cleared.insert(groom, g.clone());
        }
        after_clear.insert(
            groom,
            kind.ends_with("clear") || kind == "lipp.clear_gbuffer",
        );
        if kind != "lipp.shade" {
            continue;
        }
        let args = words("raster_args").expect("lipp.shade binds raster_args");
        let rect = Rect::from_args(args[ARGS_RECT_LO], args[ARGS_RECT_HI]);
        let before = cleared.get(&groom).expect("a clear before lipp.shade");
        let pixels = (w * h) as usize;
        let mut samples = 0;
        for (slot, pair) in g.chunks_exact(2).enumerate() {
            let was = &before[2 * slot..2 * slot + 2];
            if (pair[0] as u64 | (pair[1] as u64) << 32) == EMPTY || pair == was {
                continue;
            }
            let i = (slot % pixels) as u32;
            let (x, y) = (i % w, i / w);
            assert!(
                rect.contains(x, y),
                "{scene}, {}: a sample at ({x}, {y}) is outside the groom's rectangle {rect:?}",
                p.plan.pass_name(c.pass)
            );
            samples += 1;
        }
        out.push((rect, samples));
    }
    assert!(!out.is_empty(), "{scene}: no lipp.shade pass ran");
    out
}

fn area(r: &Rect) -> u32 {
    (r.x1 - r.x0) * (r.y1 - r.y0)
}

#[test]
fn every_sample_lies_in_its_grooms_rectangle() {
    let size = (480, 270);
    for scene in ["scenes/distances/close.ron", "scenes/distances/mid.ron"] {
        let g = grooms(scene, None, size);
        assert!(g.iter().all(|(_, n)| *n > 0), "{scene}: {g:?}");
    }
    // The far view's groom covers a small part of the screen, and so does
    // its rectangle.
    let far = grooms("scenes/distances/far.ron", None, size);
    let (rect, samples) = far[0];
    assert!(samples > 0);
    assert!(area(&rect) * 10 < size.0 * size.1, "{rect:?}");
    // The showcase's grooms, one after another (Lipp §3.5).
    let showcase = grooms("scenes/showcase.ron", Some("scenes/graphs/lipp.ron"), size);
    assert!(showcase.len() > 1, "{showcase:?}");
    assert!(showcase.iter().all(|(_, n)| *n > 0), "{showcase:?}");
}

#[test]
fn the_hardware_rasterizers_samples_lie_in_the_rectangle_too() {
    for graph in ["scenes/graphs/hw_strands.ron", "scenes/graphs/hw_mesh.ron"] {
        let g = grooms("scenes/distances/mid.ron", Some(graph), (480, 270));
        assert!(g.iter().all(|(_, n)| *n > 0), "{graph}: {g:?}");
    }
}

fn output(p: &Prepared) -> Vec<u32> {
    let frame = CpuBackend {
        alias: true,
        ..CpuBackend::default()
    }
    .execute(&p.plan, &p.instance, &p.upload)
    .unwrap_or_else(|e| panic!("cpu backend failed: {e}"));
    frame.read(&p.plan, "output.final").expect("output.final")
}

#[test]
fn the_rectangle_changes_no_pixel_of_two_grooms_drawn_one_after_the_other() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/grooms.ron");
    let prepared = |overrides: &[String]| {
        prepare_with(&scene, None, Some((240, 135)), overrides).unwrap_or_else(|e| panic!("{e:?}"))
    };
    let on = prepared(&[]);
    let shades = on
        .plan
        .graph
        .passes
        .iter()
        .filter(|p| p.kind == "lipp.shade")
        .count();
    assert!(shades > 1, "two grooms, {shades} lipp.shade passes");
    let off = prepared(&["lod_scan.groom_rect=false".to_string()]);
    let (a, b) = (output(&on), output(&off));
    assert!(
        a.iter().any(|&w| w != a[0]),
        "an image with something in it"
    );
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{differ} words of the output differ");
}

/// The error the CPU backend gives for `lipp.ron` with `declared`
/// replaced by `small`, rendering the far view at 64×36.
fn error_with(declared: &str, small: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("scenes/graphs/lipp.ron")).unwrap();
    let changed = text.replace(declared, small);
    assert_ne!(changed, text, "lipp.ron declares {declared}");
    let dir = std::env::temp_dir().join(format!("lipp_rect_small_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // One file per change: the tests run in parallel.
    let tag: String = small.chars().filter(char::is_ascii_alphanumeric).collect();
    let graph = dir.join(format!("lipp_{tag}.ron"));
    std::fs::write(&graph, changed).unwrap();
    let p = prepare_with(
        &root.join("scenes/distances/far.ron"),
        Some(&graph),
        Some((64, 36)),
        &[],
    )
    .unwrap_or_else(|e| panic!("{e:?}"));
    let e = CpuBackend::default()
        .execute(&p.plan, &p.instance, &p.upload)
        .err()
        .unwrap_or_else(|| panic!("no error with {small}"));
    std::fs::remove_file(&graph).ok();
    e.to_string()
}

/// A graph whose `raster_args` has no room for the dispatch over blocks of
/// runs that `lipp.clear_gbuffer` reads (words 13-15), the last words, is
/// an error naming the pass and the buffer, not a read past its end.
#[test]
fn a_raster_args_too_small_for_the_runs_dispatch_is_an_error() {
    let message = error_with(
        r#"Buffer(name: "raster_args", size: Bytes(64))"#,
        r#"Buffer(name: "raster_args", size: Bytes(52))"#,
    );
    assert!(
        message.contains("clear_gbuffer")
            && message.contains("`raster_args`")
            && message.contains("64 bytes"),
        "{message}"
    );
}

/// A graph whose `filter_args` has no room for the shaded rectangle that
/// `lipp.shade` writes and `lipp.filter` reads (words 4-5) is an error
/// naming the pass and the buffer: the filter would otherwise take the
/// whole screen as shaded and read stale records outside the rectangle.
#[test]
fn a_filter_args_without_room_for_the_rectangle_is_an_error() {
    let message = error_with(
        r#"Buffer(name: "filter_args", size: Bytes(24))"#,
        r#"Buffer(name: "filter_args", size: Bytes(16))"#,
    );
    assert!(
        message.contains("`shade`")
            && message.contains("`filter_args`")
            && message.contains("24 bytes"),
        "{message}"
    );
}
