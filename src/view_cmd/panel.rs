//! The side panel: which graphs run and how they are compared, the camera
//! and display transform, per-pass GPU times and the frame-time plot, and
//! every pass parameter ([`super::params`]).

use super::app::Viewer;
use super::slot::{GraphFile, Slot};
use egui::{Color32, Pos2, Rect, Stroke, Vec2};
use strandgraph::tonemap::Tonemap;

/// How the second graph is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    /// Only the first graph runs.
    Off,
    /// The first graph left of the divider, the second right of it.
    Split,
    /// One graph at a time (Space flips), both running.
    FlipA,
    FlipB,
}

/// The two slots' colours in bars and plots.
const COLOURS: [Color32; 2] = [
    Color32::from_rgb(102, 178, 255),
    Color32::from_rgb(255, 170, 80),
];

pub fn show(v: &mut Viewer, ui: &mut egui::Ui) {
    egui::ScrollArea::vertical().show(ui, |ui| {
        ui.heading("strandgraph");
        ui.label(egui::RichText::new(&v.gpu.name).small().weak());
        ui.label(egui::RichText::new(v.scene.path.display().to_string()).small());
        if let Some(status) = &v.status {
            ui.colored_label(Color32::from_rgb(255, 140, 120), status);
        }
        ui.separator();
        pipelines(v, ui);
        ui.separator();
        view(v, ui);
        ui.separator();
        times(v, ui);
        for i in 0..2 {
            let Some(slot) = (if i == 0 { &v.a } else { &v.b }) else {
                continue;
            };
            let title = format!("Parameters: {}", slot.graph.name);
            egui::CollapsingHeader::new(title)
                .id_salt(("params", i))
                .show(ui, |ui| super::params::show(v, i, ui));
        }
    });
}

fn pipelines(v: &mut Viewer, ui: &mut egui::Ui) {
    for i in 0..2 {
        let current = [&v.a, &v.b][i].as_ref().map(|s| s.graph.clone());
        let label = ["A", "B"][i];
        let shown = current
            .as_ref()
            .map_or("none", |g| g.name.as_str())
            .to_string();
        let mut picked: Option<Option<GraphFile>> = None;
        egui::ComboBox::from_label(label)
            .selected_text(shown)
            .show_ui(ui, |ui| {
                if i == 1 && ui.selectable_label(current.is_none(), "none").clicked() {
                    picked = Some(None);
                }
                for g in &v.graphs {
                    let on = current.as_ref() == Some(g);
                    if ui.selectable_label(on, &g.name).clicked() && !on {
                        picked = Some(Some(g.clone()));
                    }
                }
            });
        match picked {
            Some(Some(g)) => {
                v.pending.push((i, g, Vec::new()));
                if i == 1 && v.compare == super::panel::Compare::Off {
                    v.compare = Compare::Split;
                }
            }
            Some(None) => {
                if let Some(b) = v.b.take() {
                    b.free(&mut v.renderer().write());
                }
                v.compare = Compare::Off;
            }
            None => {}
        }
    }
    if v.b.is_some() {
        ui.horizontal(|ui| {
            ui.radio_value(&mut v.compare, Compare::Split, "split");
            let flipped = matches!(v.compare, Compare::FlipA | Compare::FlipB);
            if ui.radio(flipped, "flip (Space)").clicked() && !flipped {
                v.compare = Compare::FlipA;
            }
            ui.radio_value(&mut v.compare, Compare::Off, "A only");
        });
        if v.compare == Compare::Split {
            ui.add(egui::Slider::new(&mut v.split, 0.0..=1.0).text("divider"));
        }
    }
}

fn view(v: &mut Viewer, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        let mut turning = v.turntable.is_some();
        if ui.checkbox(&mut turning, "turntable (T)").changed() {
            v.turntable = turning.then_some(30.0);
        }
        if let Some(speed) = &mut v.turntable {
            ui.add(egui::DragValue::new(speed).suffix(" °/s").speed(1.0));
        }
    });
    ui.add(egui::Slider::new(&mut v.camera.fov, 5.0..=90.0).text("field of view °"));
    egui::ComboBox::from_label("tone map")
        .selected_text(format!("{:?}", v.look.tonemap))
        .show_ui(ui, |ui| {
            for t in [Tonemap::Aces, Tonemap::Agx, Tonemap::None] {
                ui.selectable_value(&mut v.look.tonemap, t, format!("{t:?}"));
            }
        });
    ui.add(egui::Slider::new(&mut v.look.exposure, -4.0..=4.0).text("exposure EV"));
    ui.label(
        egui::RichText::new(format!(
            "{}×{} · drag orbit · Shift/middle pan · wheel zoom · H home · P screenshot",
            v.size.0, v.size.1
        ))
        .small()
        .weak(),
    );
}

/// Per-pass GPU times of the last frame as bars, and the frame-time plot.
fn times(v: &Viewer, ui: &mut egui::Ui) {
    let slots: Vec<(usize, &Slot)> = [&v.a, &v.b]
        .into_iter()
        .enumerate()
        .filter_map(|(i, s)| s.as_ref().map(|s| (i, s)))
        .filter(|(i, _)| *i == 0 || v.compare != Compare::Off)
        .collect();
    let longest = slots
        .iter()
        .flat_map(|(_, s)| s.timings.iter().map(|t| t.millis))
        .fold(0.0f64, f64::max)
        .max(1e-3);
    ui.label("GPU time (timestamp queries)");
    for &(i, slot) in &slots {
        let total: f64 = slot.timings.iter().map(|t| t.millis).sum();
        ui.colored_label(
            COLOURS[i],
            format!("{}: {total:.3} ms a frame", slot.graph.name),
        );
    }
    plot(v, ui, &slots);
    for &(i, slot) in &slots {
        egui::CollapsingHeader::new(format!("per pass: {}", slot.graph.name))
            .id_salt(("passes", i))
            .default_open(true)
            .show(ui, |ui| {
                for t in &slot.timings {
                    bar(ui, i, t, longest);
                }
            });
    }
}

/// One pass's time as a bar scaled to the longest pass shown.
fn bar(ui: &mut egui::Ui, i: usize, t: &strandgraph_wgpu::PassTiming, longest: f64) {
    let (rect, _) =
        ui.allocate_exact_size(Vec2::new(ui.available_width(), 13.0), egui::Sense::hover());
    let bar = Rect::from_min_size(
        rect.min,
        Vec2::new(
            rect.width() * 0.45 * (t.millis / longest) as f32,
            rect.height() - 2.0,
        ),
    );
    ui.painter()
        .rect_filled(bar, 1.0, COLOURS[i].gamma_multiply(0.6));
    ui.painter().text(
        Pos2::new(rect.left() + rect.width() * 0.47, rect.center().y),
        egui::Align2::LEFT_CENTER,
        format!("{:.3}  {}", t.millis, t.name),
        egui::FontId::monospace(10.0),
        ui.visuals().text_color(),
    );
}

/// Milliseconds per frame over the last frames, one line per slot.
fn plot(v: &Viewer, ui: &mut egui::Ui, slots: &[(usize, &Slot)]) {
    let (rect, _) =
        ui.allocate_exact_size(Vec2::new(ui.available_width(), 90.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_stroke(
        rect,
        2.0,
        Stroke::new(1.0, Color32::from_gray(80)),
        egui::StrokeKind::Inside,
    );
    let top = slots
        .iter()
        .flat_map(|(i, _)| v.history[*i].iter().copied())
        .fold(0.0f32, f32::max)
        .max(0.1)
        * 1.15;
    for &(i, _) in slots {
        let h = &v.history[i];
        let n = super::app::HISTORY as f32;
        let points: Vec<Pos2> = h
            .iter()
            .enumerate()
            .map(|(k, &ms)| {
                let x = rect.right() - (h.len() - 1 - k) as f32 / n * rect.width();
                Pos2::new(x, rect.bottom() - ms / top * rect.height())
            })
            .collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.5, COLOURS[i])));
    }
    painter.text(
        rect.left_top() + Vec2::new(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("{top:.2} ms"),
        egui::FontId::monospace(10.0),
        ui.visuals().weak_text_color(),
    );
}
