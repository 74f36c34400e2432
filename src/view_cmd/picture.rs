//! The picture: graph A alone, B alone, or A left of a draggable divider
//! and B right of it, scaled to fit with the render's aspect, labelled with
//! each graph's name and GPU time; and what the mouse does to the camera.

use super::app::Viewer;
use super::panel::Compare;
use super::slot::Slot;
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};

impl Viewer {
    /// The picture: slot A, slot B, or A left of the divider and B right.
    pub(super) fn picture(&mut self, ui: &mut egui::Ui) {
        let area = ui.available_rect_before_wrap();
        let aspect = self.size.0 as f32 / self.size.1 as f32;
        let fit = if area.width() / area.height() > aspect {
            Vec2::new(area.height() * aspect, area.height())
        } else {
            Vec2::new(area.width(), area.width() / aspect)
        };
        let rect = Rect::from_center_size(area.center(), fit);
        let response = ui.allocate_rect(area, Sense::click_and_drag());
        let painter = ui.painter_at(area);
        painter.rect_filled(area, 0.0, Color32::from_gray(16));
        let full = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        let (a, b) = (self.a.as_ref(), self.b.as_ref());
        let shown = match (self.compare, a, b) {
            (Compare::FlipB, _, Some(b)) => Some(b),
            (_, a, _) => a,
        };
        if let Some(s) = shown {
            painter.image(s.texture, rect, full, Color32::WHITE);
        }
        let mut divider = None;
        if let (Compare::Split, Some(b)) = (self.compare, b) {
            let x = rect.left() + rect.width() * self.split;
            let right = Rect::from_min_max(Pos2::new(x, rect.top()), rect.max);
            let uv = Rect::from_min_max(Pos2::new(self.split, 0.0), Pos2::new(1.0, 1.0));
            painter.image(b.texture, right, uv, Color32::WHITE);
            painter.line_segment(
                [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
                Stroke::new(2.0, Color32::from_gray(230)),
            );
            divider = Some(x);
        }
        // Hiding the panel shows the picture alone (clean captures).
        if self.panel {
            self.labels(&painter, rect);
        }
        self.steer(ui, &response, rect, divider);
    }

    /// Names and frame times in the picture's corners.
    fn labels(&self, painter: &egui::Painter, rect: Rect) {
        let font = egui::FontId::proportional(14.0);
        let label = |i: usize, s: &Slot| {
            let ms = self.history[i].back().copied().unwrap_or(0.0);
            format!("{}  {ms:.2} ms", s.graph.name)
        };
        let put = |text: String, pos: Pos2, align: egui::Align2| {
            painter.text(
                pos + Vec2::new(1.0, 1.0),
                align,
                &text,
                font.clone(),
                Color32::BLACK,
            );
            painter.text(pos, align, text, font.clone(), Color32::WHITE);
        };
        let inset = 8.0;
        match (self.compare, &self.a, &self.b) {
            (Compare::Split, Some(a), Some(b)) => {
                put(
                    label(0, a),
                    rect.left_top() + Vec2::splat(inset),
                    egui::Align2::LEFT_TOP,
                );
                put(
                    label(1, b),
                    rect.right_top() + Vec2::new(-inset, inset),
                    egui::Align2::RIGHT_TOP,
                );
            }
            (Compare::FlipB, _, Some(b)) => put(
                label(1, b),
                rect.left_top() + Vec2::splat(inset),
                egui::Align2::LEFT_TOP,
            ),
            (_, Some(a), _) => put(
                label(0, a),
                rect.left_top() + Vec2::splat(inset),
                egui::Align2::LEFT_TOP,
            ),
            _ => {}
        }
    }

    /// Mouse input: the divider, orbit, pan and zoom.
    fn steer(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: Rect,
        divider: Option<f32>,
    ) {
        let (shift, scroll) = ui.input(|i| (i.modifiers.shift, i.smooth_scroll_delta.y));
        let near_divider = |p: Pos2| divider.is_some_and(|x| (p.x - x).abs() < 6.0);
        let grabbed = response
            .interact_pointer_pos()
            .or(response.hover_pos())
            .is_some_and(near_divider);
        if grabbed {
            ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
        }
        let id = response.id.with("divider");
        if response.drag_started() {
            let on = response.interact_pointer_pos().is_some_and(near_divider);
            ui.ctx().data_mut(|d| d.insert_temp(id, on));
        }
        let dragging_divider = ui.ctx().data(|d| d.get_temp::<bool>(id)).unwrap_or(false);
        let d = response.drag_delta();
        if response.dragged() && dragging_divider {
            if let Some(p) = response.interact_pointer_pos() {
                self.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
            }
        } else if response.dragged_by(egui::PointerButton::Middle)
            || (response.dragged_by(egui::PointerButton::Primary) && shift)
        {
            self.camera.pan(d.x, d.y, rect.height());
        } else if response.dragged_by(egui::PointerButton::Primary) {
            self.camera.orbit(d.x * 0.008, d.y * 0.008);
        }
        if response.hovered() && scroll != 0.0 {
            self.camera.zoom(scroll / 50.0);
        }
    }
}
