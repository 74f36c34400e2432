//! The viewer's frame loop: input to the camera, the two slots rendered at
//! the same camera, the picture (one graph, a split, or a flip between the
//! two), screenshots, dropped files, and the scripted `--frames` run.

use super::Start;
use super::camera::Orbit;
use super::dropped::{self, Scratch};
use super::panel::{self, Compare};
use super::slot::{GraphFile, Slot, graphs_beside};
use miette::Result;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use strandgraph::images::Display;
use strandgraph_assets::Scene;
use strandgraph_wgpu::Gpu;

/// Frames of history in the frame-time plot.
pub const HISTORY: usize = 240;

pub struct Viewer {
    pub gpu: Gpu,
    renderer: Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>,
    pub scene: Scene,
    pub graphs: Vec<GraphFile>,
    pub size: (u32, u32),
    pub camera: Orbit,
    home: Orbit,
    /// The graph on the left (or alone), and the one it is compared with.
    pub a: Option<Slot>,
    pub b: Option<Slot>,
    pub compare: Compare,
    /// Where the split falls, as a fraction of the picture's width.
    pub split: f32,
    pub look: Display,
    /// Degrees a second, while turning.
    pub turntable: Option<f32>,
    pub panel: bool,
    /// GPU milliseconds per frame of each slot, newest last.
    pub history: [VecDeque<f32>; 2],
    /// What went wrong last (a graph that did not compile, a file that did
    /// not load), shown in the panel.
    pub status: Option<String>,
    /// A graph to (re)open in slot 0 or 1 before the next frame, with overrides.
    pub pending: Vec<(usize, GraphFile, Vec<String>)>,
    frames: u32,
    script: Option<(u32, Option<PathBuf>)>,
    shots: (
        mpsc::Sender<Arc<egui::ColorImage>>,
        mpsc::Receiver<Arc<egui::ColorImage>>,
    ),
    shot_path: Option<PathBuf>,
    outcome: Arc<Mutex<Result<()>>>,
    /// Where scenes around dropped grooms are written.
    scratch: Scratch,
}

impl Viewer {
    pub fn new(
        cc: &eframe::CreationContext<'_>,
        gpu: Gpu,
        start: Start,
        outcome: Arc<Mutex<Result<()>>>,
    ) -> Result<Viewer> {
        let state = cc
            .wgpu_render_state
            .as_ref()
            .ok_or_else(|| miette::miette!("eframe started without its wgpu renderer"))?;
        let scene = Scene::load(&start.scene).map_err(|e| miette::miette!("{e}"))?;
        let (eye, target, fov) = scene.desc.camera.eye_target_fov();
        let camera = Orbit::look_at(eye.into(), target.into(), fov);
        let graph = GraphFile::new(start.graph.as_deref().unwrap_or(&scene.graph));
        let graphs = graphs_beside(&graph.path);
        let mut pending = vec![(0, graph, start.params)];
        if let Some(b) = &start.compare {
            pending.push((1, GraphFile::new(b), Vec::new()));
        }
        let mut viewer = Viewer {
            gpu,
            renderer: state.renderer.clone(),
            scene,
            graphs,
            size: start.size,
            camera,
            home: camera,
            a: None,
            b: None,
            compare: if start.compare.is_some() {
                Compare::Split
            } else {
                Compare::Off
            },
            split: 0.5,
            look: start.look,
            turntable: start.turntable,
            panel: start.panel,
            history: Default::default(),
            status: None,
            pending,
            frames: 0,
            script: start.frames.map(|n| (n, start.screenshot)),
            shots: mpsc::channel(),
            shot_path: None,
            outcome,
            scratch: Scratch::new(),
        };
        // A scripted run fails on the first error rather than showing it.
        viewer.open_pending()?;
        Ok(viewer)
    }

    pub fn renderer(&self) -> Arc<egui::mutex::RwLock<egui_wgpu::Renderer>> {
        self.renderer.clone()
    }

    /// Opens the pending graphs; on failure keeps what ran before.
    fn open_pending(&mut self) -> Result<()> {
        for (i, graph, overrides) in std::mem::take(&mut self.pending) {
            let mut renderer = self.renderer.write();
            let opened = Slot::open(
                &self.gpu,
                &mut renderer,
                &self.scene,
                graph.clone(),
                overrides,
                self.size,
            );
            let slot = match opened {
                Ok(slot) => slot,
                Err(e) if self.script.is_none() => {
                    self.status = Some(format!("{}: {}", graph.name, message(&e)));
                    continue;
                }
                Err(e) => return Err(e),
            };
            let old = if i == 0 { &mut self.a } else { &mut self.b };
            if let Some(old) = old.replace(slot) {
                old.free(&mut renderer);
            }
            self.history[i].clear();
            self.status = None;
        }
        Ok(())
    }

    /// Renders both slots at the camera and records their GPU times.
    fn render(&mut self) -> Result<()> {
        let b_shown = self.compare != Compare::Off;
        for (i, slot) in [self.a.as_mut(), self.b.as_mut().filter(|_| b_shown)]
            .into_iter()
            .enumerate()
        {
            let Some(slot) = slot else { continue };
            slot.render(&self.gpu, &mut self.scene, &self.camera, self.look)?;
            let total: f64 = slot.timings.iter().map(|t| t.millis).sum();
            let h = &mut self.history[i];
            if h.len() == HISTORY {
                h.pop_front();
            }
            h.push_back(total as f32);
        }
        Ok(())
    }

    /// Loads a dropped scene, graph or groom.
    fn load_dropped(&mut self, path: &Path) {
        match dropped::classify(path) {
            Ok(dropped::Dropped::Graph) => {
                self.pending.push((0, GraphFile::new(path), Vec::new()));
            }
            Ok(dropped::Dropped::Scene) | Ok(dropped::Dropped::Groom) => {
                let graph = self.a.as_ref().map(|s| s.graph.path.clone());
                match dropped::load(path, graph.as_deref(), &self.scratch) {
                    Ok((scene, note)) => self.set_scene(scene, note),
                    Err(e) => self.status = Some(message(&e)),
                }
            }
            Err(e) => self.status = Some(message(&e)),
        }
    }

    fn set_scene(&mut self, scene: Scene, note: Option<String>) {
        let (eye, target, fov) = scene.desc.camera.eye_target_fov();
        self.camera = Orbit::look_at(eye.into(), target.into(), fov);
        self.home = self.camera;
        self.scene = scene;
        for (i, slot) in [&self.a, &self.b].into_iter().enumerate() {
            if let Some(s) = slot {
                self.pending.push((i, s.graph.clone(), s.overrides.clone()));
            }
        }
        self.status = note;
    }

    fn keys(&mut self, ctx: &egui::Context) {
        use egui::Key;
        let typing = ctx.egui_wants_keyboard_input();
        let (flip, turn, home, shot, tab) = ctx.input(|i| {
            (
                i.key_pressed(Key::Space),
                i.key_pressed(Key::T),
                i.key_pressed(Key::H),
                i.key_pressed(Key::P),
                i.key_pressed(Key::Tab),
            )
        });
        if typing {
            return;
        }
        if flip && self.b.is_some() {
            self.compare = match self.compare {
                Compare::FlipB => Compare::FlipA,
                _ => Compare::FlipB,
            };
        }
        if turn {
            self.turntable = match self.turntable {
                Some(_) => None,
                None => Some(30.0),
            };
        }
        if home {
            self.camera = self.home;
        }
        if tab {
            self.panel = !self.panel;
        }
        if shot {
            let name = format!(
                "strandgraph-{}.png",
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs())
            );
            self.screenshot(ctx, PathBuf::from(name));
        }
    }

    fn screenshot(&mut self, ctx: &egui::Context, path: PathBuf) {
        let tx = self.shots.0.clone();
        ctx.request_screenshot(move |image| {
            let _ = tx.send(image);
        });
        self.shot_path = Some(path);
    }

    /// Writes a screenshot that arrived; ends a scripted run after it.
    fn save_screenshots(&mut self, ctx: &egui::Context) {
        while let Ok(image) = self.shots.1.try_recv() {
            let Some(path) = self.shot_path.take() else {
                continue;
            };
            let saved = save_png(&image, &path);
            match (&saved, self.script.is_some()) {
                (Ok(()), _) => self.status = Some(format!("saved {}", path.display())),
                (Err(e), false) => self.status = Some(message(e)),
                (Err(_), true) => {}
            }
            if self.script.is_some() {
                self.finish(ctx, saved);
            }
        }
    }

    /// Ends a scripted run with `result`.
    fn finish(&mut self, ctx: &egui::Context, result: Result<()>) {
        *self.outcome.lock().unwrap_or_else(|e| e.into_inner()) = result;
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.save_screenshots(&ctx);
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        for path in dropped {
            self.load_dropped(&path);
        }
        self.keys(&ctx);
        if let Some(deg) = self.turntable {
            let dt = ctx.input(|i| i.stable_dt).min(0.1);
            self.camera.orbit((deg * dt).to_radians(), 0.0);
        }
        if let Err(e) = self.open_pending() {
            return self.finish(&ctx, Err(e));
        }
        if let Err(e) = self.render() {
            if self.script.is_some() {
                return self.finish(&ctx, Err(e));
            }
            self.status = Some(message(&e));
        }
        // After the frame, so the panel shows this frame's times; its edits
        // take effect on the next one.
        if self.panel {
            egui::Panel::right("panel")
                .default_size(super::PANEL_WIDTH)
                .show(ui, |ui| panel::show(self, ui));
        }
        egui::CentralPanel::no_frame().show(ui, |ui| self.picture(ui));
        self.frames += 1;
        if let Some((n, shot)) = &self.script
            && self.frames == *n
        {
            match shot.clone() {
                Some(path) => self.screenshot(&ctx, path),
                None => self.finish(&ctx, Ok(())),
            }
        }
        ctx.request_repaint();
    }
}

/// An error as one line for the panel: the chain of causes, without the
/// terminal report's colours and line wrapping.
fn message(e: &miette::Report) -> String {
    e.chain()
        .map(|c| c.to_string())
        .collect::<Vec<_>>()
        .join(": ")
}

/// Writes an egui screenshot (sRGB RGBA) as PNG.
fn save_png(image: &egui::ColorImage, path: &Path) -> Result<()> {
    let [w, h] = image.size;
    let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
    let png = image::RgbaImage::from_raw(w as u32, h as u32, bytes)
        .ok_or_else(|| miette::miette!("screenshot: {w}x{h} does not match its pixels"))?;
    png.save(path)
        .map_err(|e| miette::miette!("writing the screenshot {}: {e}", path.display()))
}
