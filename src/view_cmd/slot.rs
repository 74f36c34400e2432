//! One graph running in the viewer: its compiled plan and wgpu session on
//! the window's device, and the display texture egui draws. Opening a slot
//! compiles the graph for the scene (with the panel's parameter overrides);
//! each [`Slot::render`] uploads the camera, runs every pass with GPU
//! timestamps, then tone-maps the graph's main image into the texture.

use super::camera::Orbit;
use super::display::DisplayTarget;
use miette::{IntoDiagnostic, Result};
use std::path::{Path, PathBuf};
use strandgraph::images::{Display, picture_format};
use strandgraph_assets::Scene;
use strandgraph_assets::scene::Camera;
use strandgraph_graph::Plan;
use strandgraph_graph::schema::ImageFormat;
use strandgraph_passes::Registry;
use strandgraph_passes::layout::words_of;
use strandgraph_passes::upload::{Upload, frame};
use strandgraph_wgpu::{Gpu, PassTiming, Session, WgpuBackend};

/// A graph file the viewer can run, by the name the panel shows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GraphFile {
    pub name: String,
    pub path: PathBuf,
}

impl GraphFile {
    pub fn new(path: &Path) -> GraphFile {
        let name = path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into_owned(),
        );
        GraphFile {
            name,
            path: path.to_path_buf(),
        }
    }
}

pub struct Slot {
    pub graph: GraphFile,
    /// `--param` overrides applied to the graph file's parameters.
    pub overrides: Vec<String>,
    pub plan: Plan,
    session: Session,
    /// The inputs for the first frame (every imported resource); later
    /// frames upload only the camera.
    first: Option<Upload>,
    /// The image output shown, and the transform that shows it.
    output: String,
    display: DisplayTarget,
    /// Hair models in the scene (`frame.model_count`).
    models: u32,
    pub texture: egui::TextureId,
    /// The last frame's GPU time per pass.
    pub timings: Vec<PassTiming>,
}

impl Slot {
    /// Compiles `graph` for `scene` at `size`, applies `overrides` and opens
    /// the plan on `gpu`.
    pub fn open(
        gpu: &Gpu,
        renderer: &mut egui_wgpu::Renderer,
        scene: &Scene,
        graph: GraphFile,
        overrides: Vec<String>,
        size: (u32, u32),
    ) -> Result<Slot> {
        let p = strandgraph::frame::plan_for(scene, &graph.path, size, &overrides)?;
        let (output, format) = main_image(&p.plan).ok_or_else(|| {
            miette::miette!(
                "{}: the graph has no Rgba16Float or Rgba8Unorm image output to show",
                graph.path.display()
            )
        })?;
        let session = WgpuBackend::default()
            .open_on(gpu, &Registry, &p.plan, &p.instance)
            .into_diagnostic()?;
        let display = DisplayTarget::new(gpu, renderer, size, format);
        Ok(Slot {
            graph,
            overrides,
            plan: p.plan,
            session,
            models: p.upload.quantities.models as u32,
            first: Some(p.upload),
            output,
            texture: display.texture,
            display,
            timings: Vec::new(),
        })
    }

    /// Runs one frame from `camera` and tone-maps it into [`Slot::texture`].
    pub fn render(
        &mut self,
        gpu: &Gpu,
        scene: &mut Scene,
        camera: &Orbit,
        look: Display,
    ) -> Result<()> {
        let eye = camera.eye();
        scene.desc.camera = Camera::LookAt {
            position: eye.to_array(),
            target: camera.target.to_array(),
            fov_deg: camera.fov,
        };
        let (w, h) = self.display.size;
        let mut inputs = self.first.take().unwrap_or_default();
        inputs.set("frame", words_of(&[frame(scene, w, h, self.models)]));
        self.timings = self.session.run(&inputs).into_diagnostic()?.to_vec();
        let image = self
            .session
            .texture(&self.output)
            .ok_or_else(|| miette::miette!("no texture for `{}`", self.output))?;
        self.display.draw(gpu, image, look);
        gpu.check("showing the frame").into_diagnostic()
    }

    /// Frees the display texture egui holds.
    pub fn free(self, renderer: &mut egui_wgpu::Renderer) {
        renderer.free_texture(&self.texture);
    }
}

/// The first image output that makes a picture (as `render` picks its main
/// image, [`strandgraph::images::main_picture`]), and its format.
fn main_image(plan: &Plan) -> Option<(String, ImageFormat)> {
    plan.graph.outputs.iter().find_map(|&(r, _)| {
        picture_format(plan, r).map(|f| (plan.graph.resources[r].name.clone(), f))
    })
}

/// Every graph file beside the scene's own graph (`scenes/graphs/*.ron` in
/// a checkout; the built-in demo writes them all out), sorted by name.
pub fn graphs_beside(graph: &Path) -> Vec<GraphFile> {
    let mut files: Vec<GraphFile> = graph
        .parent()
        .and_then(|dir| std::fs::read_dir(dir).ok())
        .into_iter()
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|p| GraphFile::new(&p))
        .collect();
    if !files.iter().any(|f| f.path == graph) {
        files.push(GraphFile::new(graph));
    }
    files.sort_by(|a, b| a.name.cmp(&b.name));
    files
}
