//! The groom's screen rectangle (passes/src/lipp/rect.rs, ours) holds every
//! sample the rasterizer wrote, for every groom of the built-in scenes, on
//! the CPU simulator: `lipp.shade` shades nothing outside it, so a sample
//! outside would be hair cut off.
//!
//! Each groom's `lipp.shade` is checked with the bindings it ran with
//! (the simulator's per-pass capture, as the agreement tests use): the
//! G-buffer the rasterizer left and the rectangle `lipp.lod_scan` put in
//! `raster_args`.

use std::path::Path;
use strandgraph::agree::capture;
use strandgraph::frame::prepare_with;
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
    for c in capture(&p).unwrap_or_else(|e| panic!("{scene}: {e:?}")) {
        if p.plan.graph.passes[c.pass].kind != "lipp.shade" {
            continue;
        }
        let words = |name: &str| &c.bindings.iter().find(|(n, _)| n == name).unwrap().1;
        let (g, args) = (words("gbuffer"), words("raster_args"));
        let rect = Rect::from_args(args[ARGS_RECT_LO], args[ARGS_RECT_HI]);
        let pixels = (w * h) as usize;
        let mut samples = 0;
        for (slot, pair) in g.chunks_exact(2).enumerate() {
            if (pair[0] as u64 | (pair[1] as u64) << 32) == EMPTY {
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
