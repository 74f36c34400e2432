//! The bench's quality axis: each row's image against its pipeline's
//! ground-truth reference (docs/reference.md), as mean FLIP and coverage
//! error (src/compare.rs) next to the time.
//!
//! The reference of a scene is rendered once per backend, on that backend,
//! and the row's last timed frame is compared with it. Both go through the
//! display transform `render` uses by default (ACES, 0 EV), since FLIP
//! judges what a viewer sees. A backend that cannot render the reference
//! (lavapipe stops long shader loops) falls back to the CPU simulator, which
//! agrees with the GPUs (tests/agree.rs), and the table says so.

use super::{Variant, prepare_graph};
use miette::Result;
use std::collections::BTreeMap;
use std::path::Path;
use strandgraph::compare::{ImageDiff, coverage_error, flip};
use strandgraph::images::{Display, Picture, main_picture};
use strandgraph::runner::{self, Backend, CpuOptions};

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

/// References rendered so far, by backend, scene and graph.
#[derive(Default)]
pub struct References {
    images: BTreeMap<(Backend, usize, &'static str), Result<Picture, String>>,
    /// Lines for the report: where a reference came from another backend.
    pub notes: Vec<String>,
}

/// Where a reference is rendered: the scene and the bench's settings.
pub struct Setup<'a> {
    pub scene: &'a Path,
    pub size: Option<(u32, u32)>,
    pub quick: bool,
    pub cpu: CpuOptions,
}

/// A row's picture against its pipeline's reference: the reference (kept
/// for `bench --pictures`), the FLIP difference (its mean is the table's
/// FLIP, its error map the report's heat map) and the coverage error.
pub struct Judged {
    pub reference: Picture,
    pub diff: ImageDiff,
    pub coverage_error: Option<f32>,
}

impl References {
    /// `image` (row `v`'s, on `backend`, scene `s`) against the reference;
    /// `None` when the pipeline has none.
    pub fn judge(
        &mut self,
        backend: Backend,
        s: usize,
        setup: &Setup<'_>,
        v: &Variant,
        picture: &Picture,
    ) -> Result<Option<Judged>, String> {
        let Some(graph) = reference_graph(v.pipeline) else {
            return Ok(None);
        };
        let reference = self.reference(backend, s, setup, graph)?;
        let diff = flip(&reference.image, &picture.image)
            .ok_or_else(|| format!("{graph}: the reference and the row differ in size"))?;
        let coverage_error = match (&reference.coverage, &picture.coverage) {
            (Some(r), Some(t)) => coverage_error(r, t),
            _ => None,
        };
        Ok(Some(Judged {
            reference,
            diff,
            coverage_error,
        }))
    }

    /// The reference of scene `s` on `backend`, else (once, shared by
    /// every backend that falls back) on the CPU simulator.
    fn reference(
        &mut self,
        backend: Backend,
        s: usize,
        setup: &Setup<'_>,
        graph: &'static str,
    ) -> Result<Picture, String> {
        if let Some(r) = self.images.get(&(backend, s, graph)) {
            return r.clone();
        }
        let mut r = render(backend, setup, graph).map_err(|e| e.to_string());
        if let (Err(e), true) = (&r, backend.is_gpu()) {
            self.notes.push(format!(
                "{}: the reference of {} was rendered on the cpu backend: {e}",
                backend.name(),
                setup.scene.display()
            ));
            r = self.reference(Backend::Cpu, s, setup, graph);
        }
        self.images.insert((backend, s, graph), r.clone());
        r
    }
}

/// One frame of `graph` on `backend`, as a picture.
fn render(backend: Backend, setup: &Setup<'_>, graph: &str) -> Result<Picture> {
    let p = prepare_graph(setup.scene, &super::locate(graph), setup.size, setup.quick)?;
    let mut session = runner::open(backend, &p.plan, &p.instance, setup.cpu)?;
    session.run(&p.upload)?;
    runner::check_frame(&p.plan, &p.instance, session.as_ref())?;
    let q = p.upload.quantities;
    main_picture(&p.plan, q.width, q.height, DISPLAY, |name| {
        session.read(name).ok().flatten()
    })
    .ok_or_else(|| miette::miette!("{graph} has no image output"))
}
