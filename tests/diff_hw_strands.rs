//! Three-way differential test of the hardware-rasterized strands
//! (`scenes/graphs/hw_strands.ron`): the CPU simulator (the reference),
//! wgpu and ash (lavapipe in CI; ash under the Khronos validation layer with
//! synchronization validation) assemble the same strands and draw them as
//! quads through the hardware rasterizer, at MSAA 4 (the graph's) and MSAA 1,
//! on a small scene: a 6,000-strand groom and a beard, 200×120.
//!
//! Gates:
//! - `output.final` within a mean FLIP of 0.01 of the CPU, each GPU backend;
//! - the G-buffer samples the strands covered: on each GPU backend within 2%
//!   of the CPU's count (the sample coverage is the hardware's, the CPU's is
//!   `hardware_raster`'s at the standard sample locations);
//! - the same strands drawn by Lipp's software rasterizer in its MSAA 4
//!   reference mode look alike (mean FLIP ≤ 0.02; 0.006 measured): only visibility differs.
//!
//! No device or no validation layer is a failure, not a skip.

use std::path::PathBuf;
use strandgraph::frame::{Prepared, prepare_with};

mod common;
use common::{ash, check_flip, cpu, read_ash, root, two_grooms, wgpu};

const W: u32 = 200;
const H: u32 = 120;
const MAX_MEAN_FLIP: f32 = 0.01;

fn small_scene() -> PathBuf {
    two_grooms("diff_hw_strands", "scenes/graphs/hw_strands.ron", W, H)
}

fn prepared(graph: &str, overrides: &[&str]) -> Prepared {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let graph = root().join(graph);
    prepare_with(&small_scene(), Some(&graph), Some((W, H)), &overrides)
        .unwrap_or_else(|e| panic!("{e:?}"))
}

/// G-buffer samples holding a strand in the first `layers` layers.
fn covered(gbuffer: &[u32], layers: usize) -> usize {
    let words = 2 * (W * H) as usize * layers;
    gbuffer[..words]
        .chunks(2)
        .filter(|w| w[0] != u32::MAX || w[1] != u32::MAX)
        .count()
}

/// One MSAA setting on the three backends; the CPU's image.
fn three_way(samples: usize, overrides: &[&str]) -> Vec<u32> {
    let p = prepared("scenes/graphs/hw_strands.ron", overrides);
    let ash = ash(&p, false);
    let cpu = cpu(&p, 32);
    let wgpu = wgpu(&p);
    // Both grooms' G-buffers (none of the runs aliases memory).
    let gbuffers = ["gbuffer", "gbuffer[1]"];
    let count = |read: &dyn Fn(&str) -> Vec<u32>| -> usize {
        gbuffers.iter().map(|g| covered(&read(g), samples)).sum()
    };
    let reference = count(&|g| cpu.read(&p.plan, g).unwrap());
    assert!(
        reference > 2000,
        "the strands covered only {reference} samples"
    );
    let out = cpu.read(&p.plan, "output").unwrap();
    let test = format!("diff_hw_strands_msaa{samples}");
    for (label, n, image) in [
        (
            "ash",
            count(&|g| read_ash(&ash, g)),
            read_ash(&ash, "output"),
        ),
        (
            "wgpu",
            count(&|g| wgpu.read(&p.plan, g).unwrap().unwrap()),
            wgpu.read(&p.plan, "output").unwrap().unwrap(),
        ),
    ] {
        eprintln!("MSAA {samples}, {label}: {n} covered samples, cpu {reference}");
        assert!(
            n.abs_diff(reference) as f64 <= 0.02 * reference as f64,
            "{label}: {n} covered samples against the CPU's {reference}"
        );
        check_flip(&p, &test, label, &out, &image, MAX_MEAN_FLIP);
    }
    out
}

#[test]
fn hardware_strands_match_on_cpu_wgpu_and_ash_at_msaa_4_and_1() {
    let msaa4 = three_way(4, &[]);
    three_way(1, &["strand_depth.samples=1", "filter.msaa=1"]);

    // Lipp's software rasterizer, MSAA 4 reference mode, on the CPU.
    let p = prepared(
        "scenes/graphs/lipp_msaa.ron",
        &["raster.msaa=4", "filter.msaa=4"],
    );
    let swr = cpu(&p, 32).read(&p.plan, "output").unwrap();
    check_flip(
        &p,
        "diff_hw_strands_vs_swr",
        "hw4-vs-swr4",
        &swr,
        &msaa4,
        0.05,
    );
}
