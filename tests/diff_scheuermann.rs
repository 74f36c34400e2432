//! Three-way differential test of Scheuermann's graph
//! (`scenes/graphs/scheuermann.ron`): the CPU simulator (the reference),
//! wgpu and ash (lavapipe in CI; ash under the Khronos validation layer with
//! synchronization validation) draw the same hair patches through the same
//! four hardware-raster stages, on a small scene: a 6,000-strand groom and a
//! beard, the showcase's three-quarter view, 200×120.
//!
//! Gates:
//! - `output.final` within a mean FLIP of 0.01 of the CPU, each GPU backend
//!   (the bar; the rasterization rules are the same, filtering and
//!   shading are f32 on every side);
//! - the final depth buffer: pixels where the hair wrote depth on one side
//!   and not the other at most 1% of those written on either;
//! - ash with memory aliasing gives the same image as without.
//!
//! No device or no validation layer is a failure, not a skip.

use std::path::PathBuf;
use strandgraph::frame::prepare;

mod common;
use common::{ash, check_flip, cpu, read_ash, two_grooms, wgpu};

const W: u32 = 200;
const H: u32 = 120;
const MAX_MEAN_FLIP: f32 = 0.01;

fn small_scene() -> PathBuf {
    two_grooms("diff_scheuermann", "scenes/graphs/scheuermann.ron", W, H)
}

/// Pixels whose depth the hair changed (from the head's) on exactly one
/// side, and on either.
fn depth_disagreement(head: &[u32], a: &[u32], b: &[u32]) -> (usize, usize) {
    let (mut one, mut either) = (0, 0);
    for ((&h, &x), &y) in head.iter().zip(a).zip(b) {
        let (wa, wb) = (x != h, y != h);
        either += usize::from(wa || wb);
        one += usize::from(wa != wb);
    }
    (one, either)
}

#[test]
fn scheuermann_graph_matches_on_cpu_wgpu_and_ash() {
    let p = prepare(&small_scene(), None, Some((W, H))).unwrap_or_else(|e| panic!("{e:?}"));
    assert!(
        p.upload.quantities.patches > 100,
        "{:?}",
        p.upload.quantities
    );
    let plain = ash(&p, false);
    let aliased = ash(&p, true);
    let cpu = cpu(&p, 32);
    let wgpu = wgpu(&p);
    let read_cpu = |name: &str| cpu.read(&p.plan, name).unwrap();
    let read_wgpu = |name: &str| wgpu.read(&p.plan, name).unwrap().unwrap();

    let head = read_cpu("scene.depth");
    let depth = read_cpu("depth_buffer");
    let drawn = depth.iter().zip(&head).filter(|(a, b)| a != b).count();
    assert!(drawn > 1000, "the hair wrote depth on only {drawn} pixels");
    for (label, other) in [
        ("ash", read_ash(&plain, "depth_buffer")),
        ("wgpu", read_wgpu("depth_buffer")),
    ] {
        let (one, either) = depth_disagreement(&head, &depth, &other);
        eprintln!("depth_buffer cpu/{label}: written on one side only on {one} of {either}");
        assert!(one as f64 <= 0.01 * either as f64, "{label}: depth");
    }

    let out = read_cpu("output");
    check_flip(
        &p,
        "diff_scheuermann",
        "ash",
        &out,
        &read_ash(&plain, "output"),
        MAX_MEAN_FLIP,
    );
    check_flip(
        &p,
        "diff_scheuermann",
        "wgpu",
        &out,
        &read_wgpu("output"),
        MAX_MEAN_FLIP,
    );
    assert_eq!(
        read_ash(&plain, "output"),
        read_ash(&aliased, "output"),
        "ash: the aliased run's image differs"
    );
}
