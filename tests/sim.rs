//! The simulation across backends and pipelines, on `scenes/animated.ron`:
//!
//! - the CPU simulator, wgpu and ash agree on the simulated positions after
//!   a short horizon of a fast head turn (the bound is below, with why);
//! - the scene renders as a sequence (`render --frames`) on every pipeline.

mod common;

use common::{out_dir, root};
use std::process::Command;
use strandgraph::frame::prepare_with;
use strandgraph::runner::{self, Backend, CpuOptions};
use strandgraph::sequence::frame_upload;
use strandgraph_passes::sim::SimVertex;

/// Frames of the horizon, at 30 fps: the head turns 35° in them.
const FRAMES: u32 = 8;
const FPS: f32 = 30.0;

/// Simulated world positions after `FRAMES` frames on `backend`.
fn positions(backend: Backend) -> Vec<[f32; 3]> {
    let scene = root().join("scenes/animated.ron");
    // Shading does not matter here: no self-shadowing bake.
    let overrides = ["shade.self_shadow=\"None\"".to_string()];
    let mut p = prepare_with(&scene, None, Some((160, 90)), &overrides).unwrap();
    let options = CpuOptions {
        alias: false,
        ..CpuOptions::default()
    };
    let mut session = runner::open(backend, &p.plan, &p.instance, options).unwrap_or_else(|e| {
        panic!(
            "{} backend: {e:?} (no device? run scripts/test.sh)",
            backend.name()
        )
    });
    for k in 0..FRAMES {
        let up = frame_upload(&mut p, k, FPS).unwrap();
        session.run(&up).unwrap();
    }
    let words = session
        .read("sim.state")
        .unwrap()
        .expect("sim.state is kept");
    let state: Vec<SimVertex> = bytemuck::pod_collect_to_vec(&words);
    state
        .iter()
        .map(|v| [v.position[0], v.position[1], v.position[2]])
        .collect()
}

/// A GPU may round `sqrt` and division differently from the CPU (Vulkan
/// allows 2.5 ULP for `OpFDiv`, and `sqrt` as `1 / inversesqrt`; wgpu's
/// SPIR-V also lets the driver fuse multiply-adds), and follow-the-leader
/// carries a vertex's rounding down its strand, frame after frame. Where a
/// vertex grazes the head, a rounding can also decide a contact the other
/// way, and the push moves the rest of the strand by up to millimetres. So
/// the bound has two parts: nearly every vertex within 0.05 mm (a
/// thousandth of a 5 cm segment, under a pixel at any view: at 1080p a pixel
/// at 30 cm is 0.3 mm), and every vertex within 1 cm.
const CLOSE_M: f32 = 5e-5;
const CLOSE_SHARE: f64 = 0.999;
const WORST_M: f32 = 1e-2;

#[test]
fn gpu_backends_agree_with_the_cpu_after_a_head_turn() {
    let cpu = positions(Backend::Cpu);
    let moved = cpu.iter().any(|p| p.iter().any(|v| *v != 0.0));
    assert!(moved, "the CPU simulated nothing");
    let mut failures = Vec::new();
    for backend in [Backend::Wgpu, Backend::Ash] {
        let gpu = positions(backend);
        assert_eq!(gpu.len(), cpu.len());
        let mut d: Vec<f32> = cpu
            .iter()
            .zip(&gpu)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max))
            .collect();
        let exact = d.iter().filter(|&&x| x == 0.0).count() as f64 / d.len() as f64;
        let close = d.iter().filter(|&&x| x <= CLOSE_M).count() as f64 / d.len() as f64;
        d.sort_by(f32::total_cmp);
        let worst = d[d.len() - 1];
        let p999 = d[(d.len() as f64 * 0.999) as usize];
        eprintln!(
            "{}: {:.3}% identical, {:.3}% within {CLOSE_M} m, 99.9th percentile {p999:e} m, worst {worst:e} m",
            backend.name(),
            100.0 * exact,
            100.0 * close
        );
        if close < CLOSE_SHARE || worst > WORST_M {
            failures.push(backend.name());
        }
    }
    assert!(failures.is_empty(), "outside the bound: {failures:?}");
}

#[test]
fn the_animated_scene_renders_as_a_sequence_on_every_pipeline() {
    // wgpu on lavapipe, but the hardware strands on the CPU simulator: their
    // segment buffer (5 KiB a strand) is past lavapipe's 128 MiB binding.
    let graphs = [
        ("kulikov", "wgpu"),
        ("lipp", "wgpu"),
        ("scheuermann", "wgpu"),
        ("hw_strands", "cpu"),
        ("kulikov_reference", "wgpu"),
    ];
    for (graph, backend) in graphs {
        let dir = out_dir("sim_sequence").join(graph);
        let _ = std::fs::remove_dir_all(&dir);
        let out = Command::new(env!("CARGO_BIN_EXE_strandgraph"))
            .current_dir(root())
            .args([
                "render",
                "scenes/animated.ron",
                "--backend",
                backend,
                "--size",
                "160x90",
            ])
            .args(["--frames", "3", "--fps", "10", "--graph"])
            .arg(format!("scenes/graphs/{graph}.ron"))
            .arg("-o")
            .arg(&dir)
            .output()
            .unwrap();
        let log = String::from_utf8_lossy(&out.stdout).to_string()
            + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{graph}: {log}");
        let frames: Vec<_> = (0..3)
            .map(|k| image::open(dir.join(format!("frame_{k:04}.png"))))
            .collect();
        let frames: Vec<_> = frames
            .into_iter()
            .map(|f| {
                f.unwrap_or_else(|e| panic!("{graph}: {e}\n{log}"))
                    .to_rgb8()
            })
            .collect();
        // The head turns between frames: every pipeline's picture changes.
        for k in 1..3 {
            let changed = frames[k]
                .pixels()
                .zip(frames[k - 1].pixels())
                .filter(|(a, b)| a != b)
                .count();
            assert!(
                changed > 200,
                "{graph}: frame {k} differs from frame {} in {changed} pixels",
                k - 1
            );
        }
    }
}
