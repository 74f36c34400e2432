//! The simulation across backends and pipelines, on `scenes/animated.ron`:
//!
//! - the CPU simulator, wgpu and ash agree on the simulated positions after
//!   a short horizon of a fast head turn (the bound is below, with why), for
//!   Kulikov's strands and for Lipp's bundle chains;
//! - Lipp's hair-mesh layers follow the simulated chains;
//! - the scene renders as a sequence (`render --frames`) on every pipeline.

mod common;

use common::{out_dir, root};
use std::process::Command;
use strandgraph::frame::prepare_with;
use strandgraph::runner::{self, Backend, OpenOptions};
use strandgraph::sequence::frame_upload;
use strandgraph_passes::sim::SimVertex;

/// Frames of the horizon, at 30 fps: the head turns 35° in them.
const FRAMES: u32 = 8;
const FPS: f32 = 30.0;

/// What a pipeline simulates: its graph, the overrides that skip what
/// does not matter here, and the solver's state.
struct Simulated {
    graph: &'static str,
    overrides: &'static [&'static str],
    state: &'static str,
}

const KULIKOV: Simulated = Simulated {
    graph: "scenes/graphs/kulikov.ron",
    // Shading does not matter here: no self-shadowing bake.
    overrides: &["shade.self_shadow=\"None\""],
    state: "sim.state",
};

const LIPP: Simulated = Simulated {
    graph: "scenes/graphs/lipp.ron",
    overrides: &[],
    state: "sim.chain_state",
};

/// `resource` after `FRAMES` frames of `sim` on `backend`, with `extra`
/// overrides.
fn after_frames(sim: &Simulated, backend: Backend, extra: &[&str], resource: &str) -> Vec<u32> {
    let scene = root().join("scenes/animated.ron");
    let overrides: Vec<String> = sim
        .overrides
        .iter()
        .chain(extra)
        .map(|s| s.to_string())
        .collect();
    let graph = root().join(sim.graph);
    let mut p = prepare_with(&scene, Some(&graph), Some((160, 90)), &overrides).unwrap();
    let options = OpenOptions {
        alias: false,
        ..OpenOptions::default()
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
    session
        .read(resource)
        .unwrap()
        .unwrap_or_else(|| panic!("{resource} is kept"))
}

/// Simulated world positions after `FRAMES` frames of `sim` on `backend`.
fn positions(sim: &Simulated, backend: Backend) -> Vec<[f32; 3]> {
    let words = after_frames(sim, backend, &[], sim.state);
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
    agree(&KULIKOV);
}

#[test]
fn gpu_backends_agree_with_the_cpu_on_lipps_bundles() {
    agree(&LIPP);
}

fn agree(sim: &Simulated) {
    let cpu = positions(sim, Backend::Cpu);
    let moved = cpu.iter().any(|p| p.iter().any(|v| *v != 0.0));
    assert!(moved, "{}: the CPU simulated nothing", sim.graph);
    let mut failures = Vec::new();
    for backend in [Backend::Wgpu, Backend::Ash] {
        let gpu = positions(sim, backend);
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
            "{} {}: {:.3}% identical, {:.3}% within {CLOSE_M} m, 99.9th percentile {p999:e} m, worst {worst:e} m",
            sim.graph,
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

/// Lipp's layers after the head turn, simulated and carried rigidly: the
/// simulated bundles lag by centimetres, and (the follow pass turning
/// nothing at rest) the rigid ones are where the upload puts them.
#[test]
fn lipps_layers_follow_the_simulated_bundles() {
    let layers = |models: &str| -> Vec<f32> {
        let words = after_frames(
            &LIPP,
            Backend::Cpu,
            &[&format!("simulate.models=\"{models}\"")],
            "hairmesh.layers",
        );
        words.iter().map(|w| f32::from_bits(*w)).collect()
    };
    let (simulated, rigid) = (layers("Flagged"), layers("None"));
    // The upload of the last frame: every layer carried by the head joint.
    let scene = root().join("scenes/animated.ron");
    let graph = root().join(LIPP.graph);
    let mut p = prepare_with(&scene, Some(&graph), Some((160, 90)), &[]).unwrap();
    let up = frame_upload(&mut p, FRAMES - 1, FPS).unwrap();
    let carried: Vec<f32> = up.resources["hairmesh.layers"]
        .iter()
        .map(|w| f32::from_bits(*w))
        .collect();
    // Words 0-2 of each 8-word corner are its position, 4-6 its tangent.
    let largest = |a: &[f32], b: &[f32], first: usize| {
        a.chunks(8)
            .zip(b.chunks(8))
            .map(|(x, y)| {
                (first..first + 3)
                    .map(|k| (x[k] - y[k]).abs())
                    .fold(0.0, f32::max)
            })
            .fold(0.0, f32::max)
    };
    let (rigid_moved, rigid_turned) = (largest(&rigid, &carried, 0), largest(&rigid, &carried, 4));
    let lag = largest(&simulated, &carried, 0);
    eprintln!(
        "rigid: {rigid_moved:e} m, tangents {rigid_turned:e}; simulated lag {:.1} mm",
        lag * 1e3
    );
    assert!(
        rigid_moved < 1e-5 && rigid_turned < 1e-4,
        "a rigid layer moved: {rigid_moved} m, {rigid_turned}"
    );
    assert!(lag > 0.01, "the simulated bundles lag only {lag} m");
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
