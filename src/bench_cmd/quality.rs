//! The bench's quality axis: each row's image against its pipeline's
//! ground-truth reference (docs/reference.md), as mean FLIP and coverage
//! error (src/compare.rs) next to the time.
//!
//! The reference of a scene is rendered once per backend, on that backend,
//! and the row's last timed frame is compared with it. An animated scene's
//! reference runs the same frames (its graph simulates as the row's does,
//! with the row's `simulate.*` and `splat.*` overrides), and every timed frame is
//! compared: FLIP per frame, and the flicker of the sequence against the
//! reference's ([`strandgraph::compare::Temporal`]). Both go through the
//! display transform `render` uses by default (ACES, 0 EV), since FLIP
//! judges what a viewer sees. A backend that cannot render the reference
//! (lavapipe stops long shader loops) falls back to the CPU simulator, which
//! agrees with the GPUs (tests/agree.rs), and the table says so.

use super::{FPS, Variant, prepare_graph};
use miette::Result;
use std::collections::BTreeMap;
use std::path::Path;
use strandgraph::compare::{ImageDiff, Temporal, coverage_error, flip, temporal};
use strandgraph::frame::override_param;
use strandgraph::images::{Display, Picture, main_picture};
use strandgraph::runner::{self, Backend, OpenOptions};
use strandgraph::sequence;

/// The ground truth a pipeline's rows are measured against, if it has one.
pub fn reference_graph(pipeline: &str) -> Option<&'static str> {
    match pipeline {
        "Kulikov" => Some("scenes/graphs/kulikov_reference.ron"),
        // The hardware-raster baselines shade with lipp.shade.
        "Lipp" | "HW strands" | "HW mesh" => Some("scenes/graphs/lipp_reference.ron"),
        "Scheuermann" => Some("scenes/graphs/scheuermann_reference.ron"),
        _ => None,
    }
}

/// How the bench's pictures are made from the linear images.
pub const DISPLAY: Display = Display {
    tonemap: strandgraph::images::Tonemap::Aces,
    exposure: 0.0,
};

/// The passes every graph that simulates names `simulate` and `splat`
/// (its velocity grid): overrides of them change what the hair does, not
/// how it is drawn, so a row's carry over to its reference.
const SIMULATION: [&str; 2] = ["simulate.", "splat."];

/// The overrides of `v` and `extra` (`--param`) its reference takes.
pub fn simulation_overrides(v: &Variant, extra: &[String]) -> Vec<String> {
    v.overrides
        .iter()
        .copied()
        .chain(extra.iter().map(String::as_str))
        .filter(|spec| SIMULATION.iter().any(|p| spec.starts_with(p)))
        .map(str::to_string)
        .collect()
}

/// A reference's key: backend, scene, graph, and the simulation overrides.
type Key = (Backend, usize, &'static str, Vec<String>);

/// References rendered so far: the pictures of the frames a row is judged
/// on (the last, or an animated scene's timed frames).
#[derive(Default)]
pub struct References {
    images: BTreeMap<Key, Result<Vec<Picture>, String>>,
    /// Lines for the report: where a reference came from another backend.
    pub notes: Vec<String>,
}

/// Where a reference is rendered: the scene and the bench's settings.
pub struct Setup<'a> {
    pub scene: &'a Path,
    pub size: Option<(u32, u32)>,
    pub quick: bool,
    pub cpu: OpenOptions,
    /// The row's untimed and timed frames (an animated scene's reference
    /// runs as many).
    pub warmup: usize,
    pub frames: usize,
}

/// A row's pictures against its pipeline's reference. The last frame's
/// reference (kept for `bench --pictures`), FLIP difference (its error map
/// is the report's heat map) and coverage error; every judged frame's mean
/// FLIP (their mean is the table's FLIP); and for a sequence, its flicker.
pub struct Judged {
    pub reference: Picture,
    pub diff: ImageDiff,
    pub coverage_error: Option<f32>,
    pub flip_frames: Vec<f32>,
    pub temporal: Option<Temporal>,
}

impl Judged {
    /// The mean of the judged frames' mean FLIP.
    pub fn flip(&self) -> f32 {
        self.flip_frames.iter().sum::<f32>() / self.flip_frames.len().max(1) as f32
    }
}

impl References {
    /// `pictures` (row `v`'s, on `backend`, scene `s`: its last frame, or
    /// every timed frame of an animated scene) against the reference;
    /// `None` when the pipeline has none.
    pub fn judge(
        &mut self,
        backend: Backend,
        s: usize,
        setup: &Setup<'_>,
        v: &Variant,
        extra: &[String],
        pictures: &[Picture],
    ) -> Result<Option<Judged>, String> {
        let Some(graph) = reference_graph(v.pipeline) else {
            return Ok(None);
        };
        let key = (backend, s, graph, simulation_overrides(v, extra));
        let references = self.reference(key, setup)?;
        let (Some(last), Some(reference)) = (pictures.last(), references.last()) else {
            return Err(format!("{graph}: no frame to compare"));
        };
        if references.len() != pictures.len() {
            return Err(format!(
                "{graph}: {} reference frames for {} of the row",
                references.len(),
                pictures.len()
            ));
        }
        let size_error = || format!("{graph}: the reference and the row differ in size");
        let mut flip_frames = Vec::with_capacity(pictures.len());
        for (r, p) in references.iter().zip(pictures).take(pictures.len() - 1) {
            flip_frames.push(flip(&r.image, &p.image).ok_or_else(size_error)?.mean);
        }
        let diff = flip(&reference.image, &last.image).ok_or_else(size_error)?;
        flip_frames.push(diff.mean);
        let coverage_error = match (&reference.coverage, &last.coverage) {
            (Some(r), Some(t)) => coverage_error(r, t),
            _ => None,
        };
        Ok(Some(Judged {
            reference: reference.clone(),
            diff,
            coverage_error,
            flip_frames,
            temporal: temporal(&images(pictures), &images(&references)),
        }))
    }

    /// The reference pictures for `key`, rendered on its backend, else
    /// (once, shared by every backend that falls back) on the CPU simulator.
    fn reference(&mut self, key: Key, setup: &Setup<'_>) -> Result<Vec<Picture>, String> {
        if let Some(r) = self.images.get(&key) {
            return r.clone();
        }
        let (backend, _, graph, sim) = &key;
        let mut r = render(*backend, setup, graph, sim).map_err(|e| e.to_string());
        if let (Err(e), true) = (&r, backend.is_gpu()) {
            self.notes.push(format!(
                "{}: the reference of {} was rendered on the cpu backend: {e}",
                backend.name(),
                setup.scene.display()
            ));
            let mut on_cpu = key.clone();
            on_cpu.0 = Backend::Cpu;
            r = self.reference(on_cpu, setup);
        }
        self.images.insert(key, r.clone());
        r
    }
}

/// `graph` on `backend` with the simulation overrides `sim`, as pictures:
/// one frame of a still scene; the row's frames of an animated one, a
/// picture of each timed frame.
fn render(
    backend: Backend,
    setup: &Setup<'_>,
    graph: &str,
    sim: &[String],
) -> Result<Vec<Picture>> {
    let mut p = prepare_graph(setup.scene, &super::locate(graph), setup.size, setup.quick)?;
    for spec in sim {
        override_param(&mut p.plan, spec)?;
    }
    let (inputs, judged_from) =
        match sequence::animation_frames(&mut p, setup.warmup + setup.frames, FPS)? {
            Some(frames) => (frames, setup.warmup),
            None => (vec![p.upload.clone()], 0),
        };
    let mut session = runner::open(backend, &p.plan, &p.instance, setup.cpu)?;
    sequence_pictures(session.as_mut(), &p.plan, &p.instance, &inputs, judged_from)
}

/// Runs `inputs` frame after frame in `session`, and returns the picture of
/// every frame from `judged_from` on.
pub fn sequence_pictures(
    session: &mut dyn runner::Session,
    plan: &strandgraph_graph::Plan,
    instance: &strandgraph_graph::Instance,
    inputs: &[strandgraph_passes::upload::Upload],
    judged_from: usize,
) -> Result<Vec<Picture>> {
    let mut pictures = Vec::new();
    for (k, input) in inputs.iter().enumerate() {
        session.run(input)?;
        if k < judged_from {
            continue;
        }
        runner::check_frame(plan, instance, &*session)?;
        let q = input.quantities;
        let picture = main_picture(plan, q.width, q.height, DISPLAY, |name| {
            session.read(name).ok().flatten()
        })
        .ok_or_else(|| miette::miette!("{} has no image output", plan.graph.name))?;
        pictures.push(picture);
    }
    Ok(pictures)
}

fn images(pictures: &[Picture]) -> Vec<&image::RgbaImage> {
    pictures.iter().map(|p| &p.image).collect()
}
