//! The solver's promises, on the CPU kernel, for Kulikov's strands and for
//! Lipp's bundle chains: inextensible under a fast head turn, never inside
//! the head (deeper than at rest), still at rest, and a sag without the
//! gravity preload.

use super::chains;
use super::grid::{self, GRID_WORDS, SPLAT, SPLAT_CHAINS};
use super::pbd::{PBD, PBD_CHAINS, PbdParams};
use super::sdf::{FIELD_WORDS, sample};
use super::upload::{MODELS, REST, SDF, pack, repose};
use super::{SimModel, SimVertex};
use crate::kernel::harness::Harness;
use crate::layout::{FrameData, words_of};
use crate::upload::{Upload, upload};
use glam::{Mat4, Vec3};
use strandgraph_assets::Scene;

const FPS: f32 = 60.0;

/// A head with 400 strands of long simulated hair; `animation` is the
/// scene's RON field.
fn scene(animation: &str) -> Scene {
    scene_with(animation, 400)
}

/// A still head with `strands` strands of long simulated hair (and the
/// hair mesh fitted to them).
pub(super) fn long_hair_scene(strands: u32) -> Scene {
    scene_with("", strands)
}

fn scene_with(animation: &str, strands: u32) -> Scene {
    let text = format!(
        r#"Scene(
    resolution: (64, 64),
    camera: LookAt(position: (0.0, 1.6, 1.2), target: (0.0, 1.5, 0.0), fov_deg: 30.0),
    meshes: [(name: "head", source: Head(resolution: 96), transform: (translation: (0.0, 1.6, 0.0)))],
    grooms: [(
        name: "hair",
        source: Procedural(style: Long, strands: {strands}, points: 16, seed: 3),
        parent: "head",
        simulate: true,
    )],
    graph: "graphs/kulikov.ron",
    {animation}
)"#
    );
    let dir = std::env::temp_dir().join(format!("strandgraph-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!(
        "{:x}-{strands}.ron",
        text.len() ^ animation.as_ptr() as usize
    ));
    std::fs::write(&path, text).unwrap();
    Scene::load(&path).unwrap()
}

/// What the solver runs on: Kulikov's strands, or Lipp's bundle chains.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Strands,
    Chains,
}

impl Kind {
    /// The solver's binding and the resource bound to it.
    fn buffers(self) -> [(&'static str, &'static str); 4] {
        match self {
            Kind::Strands => [
                ("groom.vertices", "groom.vertices"),
                ("groom.strands", "groom.strands"),
                (REST, REST),
                (MODELS, MODELS),
            ],
            Kind::Chains => [
                ("groom.vertices", chains::POINTS),
                ("groom.strands", chains::CHAINS),
                (REST, chains::REST),
                (MODELS, chains::CHAIN_MODELS),
            ],
        }
    }
    fn source(self, binding: &str) -> &'static str {
        self.buffers()
            .iter()
            .find(|(b, _)| *b == binding)
            .expect("a solver binding")
            .1
    }
}

/// Runs the scene's animation frame by frame at 60 fps through the CPU
/// kernel.
struct Run {
    scene: Scene,
    up: Upload,
    harness: Harness,
    params: PbdParams,
    kind: Kind,
}

impl Run {
    fn new(scene: Scene, params: PbdParams, kind: Kind) -> Self {
        let mut up = upload(&scene, 64, 64);
        pack(&scene, &mut up);
        chains::pack(&scene, &mut up);
        let mut harness = Harness::new(up.quantities);
        harness.buffer("models", up.resources["models"].clone());
        harness.buffer(SDF, up.resources[SDF].clone());
        for (binding, source) in kind.buffers() {
            harness.buffer(binding, up.resources[source].clone());
        }
        let points = up.resources[kind.source(REST)].len() / 4;
        harness.buffer("sim.state", vec![0; points * 8]);
        harness.buffer("sim.grid", vec![0; GRID_WORDS * scene.grooms.len()]);
        Run {
            scene,
            up,
            harness,
            params,
            kind,
        }
    }

    fn frame(&mut self, k: u32) {
        let t = k as f32 / FPS;
        self.scene.pose_at(t);
        let posed = upload(&self.scene, 64, 64);
        self.up
            .resources
            .insert("models".into(), posed.resources["models"].clone());
        repose(&self.scene, &mut self.up);
        let mut frame: FrameData = posed.frame.unwrap();
        frame.time = t;
        frame.delta_time = if k == 0 { 0.0 } else { 1.0 / FPS };
        frame.sim_reset = u32::from(k == 0);
        let models = self.up.resources[self.kind.source(MODELS)].clone();
        self.harness
            .buffer("frame", words_of(&[frame]))
            .buffer("models", self.up.resources["models"].clone())
            .buffer(MODELS, models);
        let (splat, pass, lanes) = match self.kind {
            Kind::Strands => (&SPLAT, &PBD, self.up.quantities.strands),
            Kind::Chains => (&SPLAT_CHAINS, &PBD_CHAINS, 4 * self.up.quantities.bundles),
        };
        let groups = (lanes as u32).div_ceil(64);
        let grid_words = GRID_WORDS * self.scene.grooms.len();
        self.harness.buffer("sim.grid", vec![0; grid_words]);
        let splat = (splat.kernel)(&grid::SplatParams {
            enabled: self.params.hair_friction > 0.0,
            models: self.params.models,
        });
        self.harness.run(splat.as_ref(), groups, 64);
        let kernel = (pass.kernel)(&self.params);
        self.harness.run(kernel.as_ref(), groups, 64);
    }

    fn state(&self) -> Vec<SimVertex> {
        bytemuck::pod_collect_to_vec(&self.harness.read("sim.state"))
    }

    /// Each vertex's world position at rest in the current pose.
    fn rest(&self) -> Vec<Vec3> {
        let g = &self.scene.grooms[0];
        let verts: Vec<[f32; 4]> =
            bytemuck::pod_collect_to_vec(&self.up.resources[self.kind.source(REST)]);
        verts
            .iter()
            .map(|v| g.world.transform_point3(Vec3::new(v[0], v[1], v[2])))
            .collect()
    }

    fn strands(&self) -> Vec<[u32; 2]> {
        bytemuck::pod_collect_to_vec(&self.up.resources[self.kind.source("groom.strands")])
    }

    /// The mean distance of each vertex's velocity from its grid cell's
    /// average (the grid splatted from the current state), m/s.
    fn spread(&self) -> f32 {
        let state = self.state();
        let sims: Vec<SimModel> = bytemuck::pod_collect_to_vec(&self.up.resources[MODELS]);
        let inv_world = Mat4::from_cols_array(&sims[0].inv_world);
        let cell = |s: &SimVertex| {
            grid::cell(
                sims[0].grid_min,
                inv_world.transform_point3(Vec3::from_slice(&s.position)),
            )
        };
        let mut cells = vec![(Vec3::ZERO, 0.0f32); GRID_WORDS / 4];
        for s in &state {
            if let Some(c) = cell(s) {
                cells[c].0 += Vec3::from_slice(&s.velocity);
                cells[c].1 += 1.0;
            }
        }
        let (mut sum, mut n) = (0.0, 0.0);
        for s in &state {
            if let Some(c) = cell(s) {
                let mean = cells[c].0 / cells[c].1;
                sum += Vec3::from_slice(&s.velocity).distance(mean);
                n += 1.0;
            }
        }
        sum / n
    }

    /// The field's distance at world point `p` (metres); `None` off the grid.
    fn distance(&self, p: Vec3) -> Option<f32> {
        let sims: Vec<SimModel> = bytemuck::pod_collect_to_vec(&self.up.resources[MODELS]);
        let field = &self.up.resources[SDF][..FIELD_WORDS];
        let q = Mat4::from_cols_array(&sims[0].inv_world).transform_point3(p);
        sample(|i| f32::from_bits(field[i]), sims[0].sdf_min, q.to_array())
            .map(|(d, _)| d * sims[0].scale)
    }
}

const TURN: &str = "animation: (joints: [(mesh: \"head\", pivot: (0.0, 1.5, 0.0), keys: [
    (time: 0.0), (time: 0.25, rotation_deg: (0.0, 90.0, 0.0)), (time: 0.5, rotation_deg: (-20.0, -60.0, 0.0)), (time: 0.75)])]),";

#[test]
fn a_fast_head_turn_keeps_lengths_and_stays_out_of_the_head() {
    for kind in [Kind::Strands, Kind::Chains] {
        fast_head_turn(kind);
    }
}

fn fast_head_turn(kind: Kind) {
    let mut run = Run::new(scene(TURN), PbdParams::default(), kind);
    let rest = run.rest();
    let strands = run.strands();
    // How deep each vertex may go: its rest depth, if inside at rest (a
    // bundle's corner by the scalp).
    run.scene.pose_at(0.0);
    let allowed: Vec<f32> = rest
        .iter()
        .map(|p| run.distance(*p).unwrap_or(0.0).min(0.0))
        .collect();
    let (mut worst_length, mut deepest, mut moved) = (0.0f32, 0.0f32, 0.0f32);
    for k in 0..60 {
        run.frame(k);
        let state = run.state();
        let now = run.rest();
        for &[first, count] in &strands {
            for v in first as usize + 1..(first + count) as usize {
                let p = |i: usize| Vec3::from_slice(&state[i].position);
                let want = rest[v].distance(rest[v - 1]);
                worst_length = worst_length.max((p(v).distance(p(v - 1)) - want).abs() / want);
                let depth = run.distance(p(v)).unwrap_or(0.0) - allowed[v];
                deepest = deepest.min(depth);
                moved = moved.max(p(v).distance(now[v]));
            }
        }
    }
    eprintln!(
        "{kind:?}: worst length change {:.4}%, deepest {:.4} mm past rest, largest lag {:.1} mm",
        worst_length * 100.0,
        -deepest * 1e3,
        moved * 1e3
    );
    assert!(
        worst_length < 0.01,
        "{kind:?}: a segment changed length by {:.3}%",
        worst_length * 100.0
    );
    assert!(
        deepest >= -1e-4,
        "{kind:?}: a vertex ended {:.3} mm inside the head",
        -deepest * 1e3
    );
    // The hair lagged behind the head: it is simulated, not carried.
    assert!(
        moved > 0.02,
        "{kind:?}: hair moved at most {moved} m from the carried pose"
    );
}

#[test]
fn a_groom_at_rest_stays_at_rest_for_1000_steps() {
    for kind in [Kind::Strands, Kind::Chains] {
        let params = PbdParams::default();
        let mut run = Run::new(scene(""), params, kind);
        let rest = run.rest();
        let frames = 1000 / params.substeps;
        for k in 0..=frames {
            run.frame(k);
        }
        let state = run.state();
        let drift = state
            .iter()
            .zip(&rest)
            .map(|(s, r)| Vec3::from_slice(&s.position).distance(*r))
            .fold(0.0, f32::max);
        assert!(
            drift < 1e-4,
            "{kind:?}: a vertex drifted {:.4} mm in 1000 steps",
            drift * 1e3
        );
        let speed = state
            .iter()
            .map(|s| Vec3::from_slice(&s.velocity).length())
            .fold(0.0, f32::max);
        assert!(speed < 1e-3, "{kind:?}: still moving at {speed} m/s");
    }
}

#[test]
fn without_the_preload_gravity_pulls_the_style_down() {
    let params = PbdParams {
        gravity_preload: false,
        shape_stiffness: 0.0,
        ..PbdParams::default()
    };
    for kind in [Kind::Strands, Kind::Chains] {
        let mut run = Run::new(scene(""), params, kind);
        let rest = run.rest();
        for k in 0..30 {
            run.frame(k);
        }
        let state = run.state();
        let tips: Vec<(Vec3, Vec3)> = run
            .strands()
            .iter()
            .map(|&[first, count]| {
                let tip = (first + count - 1) as usize;
                (Vec3::from_slice(&state[tip].position), rest[tip])
            })
            .collect();
        let drop = tips.iter().map(|(p, r)| r.y - p.y).sum::<f32>() / tips.len() as f32;
        assert!(
            drop > 0.01,
            "{kind:?}: tips fell {drop} m on average in half a second"
        );
    }
}

/// Hair-hair friction makes neighbouring vertices move alike: after the
/// head turn, velocities differ less from their cell's average with it.
#[test]
fn hair_friction_pulls_neighbours_together() {
    let spread = |hair_friction: f32| {
        let params = PbdParams {
            hair_friction,
            ..PbdParams::default()
        };
        let mut run = Run::new(scene(TURN), params, Kind::Strands);
        for k in 0..20 {
            run.frame(k);
        }
        run.spread()
    };
    let (without, with) = (spread(0.0), spread(0.5));
    eprintln!("velocity spread in a cell: {without:.4} m/s without, {with:.4} m/s with friction");
    assert!(with < 0.8 * without, "{with} against {without}");
}
