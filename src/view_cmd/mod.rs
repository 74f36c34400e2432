//! `strandgraph view`: an interactive window on a scene. Any graph of
//! `scenes/graphs/` runs live on wgpu, alone or split-screen against a
//! second one at the same camera, with every pass parameter as a widget
//! and per-pass GPU times from timestamp queries.
//!
//! - [`camera`]: the orbit camera;
//! - [`slot`]: one graph running on the window's device;
//! - [`display`] (+ `display.wgsl`): the tone mapper that shows a slot;
//! - [`app`]: the window's frame loop, keys, screenshots and dropped files;
//! - [`picture`]: the picture (one graph, or a split) and mouse steering;
//! - [`panel`] and [`params`]: the side panel and its parameter widgets;
//! - [`dropped`]: scenes and grooms dropped on the window.

mod app;
mod camera;
mod display;
mod dropped;
mod panel;
mod params;
mod picture;
mod slot;

use miette::{IntoDiagnostic, Result};
use std::path::PathBuf;
use strandgraph::demo::Demo;
use strandgraph::frame::parse_size;
use strandgraph::images::Display;
use strandgraph::tonemap::Tonemap;

#[derive(clap::Args)]
#[command(after_help = "Examples:
  strandgraph view scenes/showcase.ron
  strandgraph view --demo                                  # no checkout needed
  strandgraph view scenes/showcase.ron --compare scenes/graphs/lipp.ron
  strandgraph view --demo --frames 30 --screenshot shot.png # render, save, quit

Mouse: drag to orbit, Shift+drag or middle-drag to pan, wheel to zoom; drag
the divider to move the split. Keys: Space flips between the two graphs,
T turntable, H home view, P screenshot (PNG in the current directory),
Tab hides the panel. Drop a .ron scene or graph, or a .hair or .tfx groom,
on the window to load it.")]
pub struct Args {
    /// The scene (RON), e.g. scenes/showcase.ron.
    #[arg(required_unless_present = "demo")]
    pub scene: Option<PathBuf>,
    /// View the built-in showcase (scene and every shipped graph are in the binary).
    #[arg(long, conflicts_with = "scene")]
    pub demo: bool,
    /// Run this graph instead of the scene's.
    #[arg(long)]
    pub graph: Option<PathBuf>,
    /// A second graph, shown split-screen against the first at the same camera.
    #[arg(long)]
    pub compare: Option<PathBuf>,
    /// The resolution the graphs render at, as WxH; the window scales it to fit.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Override a pass parameter of the first graph, as PASS.PARAM=VALUE (repeatable).
    #[arg(long = "param", value_name = "PASS.PARAM=VALUE")]
    pub params: Vec<String>,
    /// Start turning the camera about the target, in degrees a second.
    #[arg(long, value_name = "DEG_PER_S")]
    pub turntable: Option<f32>,
    #[arg(long, value_enum, default_value = "aces")]
    pub tonemap: Tonemap,
    /// Exposure in stops, applied before the tone mapper.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Start with the side panel hidden (Tab shows it).
    #[arg(long)]
    pub no_panel: bool,
    /// Render this many frames, then quit (with --screenshot: save the last
    /// one's window first). For tests and scripted captures.
    #[arg(long)]
    pub frames: Option<u32>,
    /// With --frames: where to save the window as PNG before quitting.
    #[arg(long, value_name = "FILE.png", requires = "frames")]
    pub screenshot: Option<PathBuf>,
}

/// How the viewer starts, from the arguments.
pub struct Start {
    pub scene: PathBuf,
    pub graph: Option<PathBuf>,
    pub compare: Option<PathBuf>,
    pub size: (u32, u32),
    pub params: Vec<String>,
    pub turntable: Option<f32>,
    pub look: Display,
    pub panel: bool,
    pub frames: Option<u32>,
    pub screenshot: Option<PathBuf>,
}

/// Width of the side panel in points, added to the window.
const PANEL_WIDTH: f32 = 360.0;

pub fn run(args: Args) -> Result<()> {
    // Written out for the loader; removed when the viewer closes.
    let demo = args.demo.then(Demo::write).transpose()?;
    let scene = match (&demo, &args.scene) {
        (Some(d), _) => d.scene.clone(),
        (None, Some(s)) => s.clone(),
        (None, None) => unreachable!("clap requires a scene without --demo"),
    };
    let size = parse_size(&args.size)?;
    let start = Start {
        scene,
        graph: args.graph,
        compare: args.compare,
        size,
        params: args.params,
        turntable: args.turntable,
        look: Display {
            tonemap: args.tonemap,
            exposure: args.exposure,
        },
        panel: !args.no_panel,
        frames: args.frames,
        screenshot: args.screenshot,
    };
    let gpu = strandgraph_wgpu::WgpuBackend::default()
        .gpu()
        .into_diagnostic()?;
    tracing::info!("viewer on {}", gpu.name);
    let panel = if start.panel { PANEL_WIDTH } else { 0.0 };
    let viewport = egui::ViewportBuilder::default()
        .with_title("strandgraph")
        .with_inner_size([size.0 as f32 + panel, size.1 as f32])
        .with_drag_and_drop(true);
    let options = eframe::NativeOptions {
        viewport,
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: egui_wgpu::WgpuConfiguration {
            wgpu_setup: egui_wgpu::WgpuSetup::Existing(egui_wgpu::WgpuSetupExisting {
                instance: gpu.instance.clone(),
                adapter: gpu.adapter.clone(),
                device: gpu.device.clone(),
                queue: gpu.queue.clone(),
            }),
            ..Default::default()
        },
        ..Default::default()
    };
    let outcome: std::sync::Arc<std::sync::Mutex<Result<()>>> =
        std::sync::Arc::new(std::sync::Mutex::new(Ok(())));
    let result = outcome.clone();
    eframe::run_native(
        "strandgraph",
        options,
        Box::new(move |cc| {
            let viewer = app::Viewer::new(cc, gpu, start, result).map_err(|e| format!("{e:?}"))?;
            Ok(Box::new(viewer))
        }),
    )
    .map_err(|e| miette::miette!("viewer: {e}"))?;
    drop(demo);
    let mut outcome = outcome.lock().unwrap_or_else(|e| e.into_inner());
    std::mem::replace(&mut *outcome, Ok(()))
}
