//! The frame's area: camera by mouse, picking, the gizmo, the split divider and the
//! stats overlay.

use super::{Actions, App};
use crate::gizmo::{Gizmo, Handle, View};
use crate::renderer::{Command, Shown};
use egui::Sense;
use glam::{Quat, Vec2, Vec3};

impl App {
    /// The frame's area: mouse for camera, picking and the split divider.
    pub(super) fn viewport(&mut self, ui: &mut egui::Ui, actions: &mut Actions) {
        let avail = ui.available_rect_before_wrap();
        let ppp = ui.ctx().pixels_per_point();
        let (w, h) = (
            self.options.config.render.width as f32,
            self.options.config.render.height as f32,
        );
        let fit = ((avail.width() * ppp) / w).min((avail.height() * ppp) / h);
        let scale = if fit >= 1.0 {
            fit.floor()
        } else {
            fit.max(0.01)
        };
        let size_px = egui::vec2(w * scale, h * scale);
        let rect = egui::Rect::from_min_size(avail.min, size_px / ppp);
        actions.image_rect_px = [rect.min.x * ppp, rect.min.y * ppp, size_px.x, size_px.y];
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let Some(shown) = self.shown.clone() else {
            return;
        };
        let to_uv = |p: egui::Pos2| {
            Vec2::new(
                (p.x - rect.min.x) / rect.width(),
                (p.y - rect.min.y) / rect.height(),
            )
        };
        let view = View {
            world_from_camera: shown.camera.0,
            yfov_rad: shown.camera.1,
            origin: Vec2::new(rect.min.x, rect.min.y),
            size: Vec2::new(rect.width(), rect.height()),
        };
        let gizmo = shown
            .selection_pivot
            .filter(|_| !self.fly)
            .and_then(|p| Gizmo::new(view, p));
        let painter = ui.painter_at(rect);
        if self.overlay {
            self.draw_overlay(&painter, rect, &shown);
        }
        let pointer = |p: egui::Pos2| Vec2::new(p.x, p.y);
        if let Some(g) = &gizmo {
            let hovered = self
                .gizmo_drag
                .or_else(|| response.hover_pos().and_then(|p| g.hit(pointer(p))));
            draw_gizmo(&painter, g, hovered);
            self.log_gizmo(g, ppp);
            if response.drag_started()
                && let Some(origin) = ui.input(|i| i.pointer.press_origin())
            {
                self.gizmo_drag = g.hit(pointer(origin));
            }
            if let Some(handle) = self.gizmo_drag
                && response.dragged()
                && let Some(p) = response.interact_pointer_pos()
            {
                let to = pointer(p);
                let d = response.drag_delta();
                let (translate, rotate) = g.drag(handle, to - Vec2::new(d.x, d.y), to);
                if translate != Vec3::ZERO || rotate != Quat::IDENTITY {
                    self.log(&format!("gizmo {handle:?}"));
                    actions
                        .commands
                        .push(Command::MoveSelected { translate, rotate });
                }
            }
        }
        if response.drag_stopped() || gizmo.is_none() {
            self.gizmo_drag = None;
        }
        if self.gizmo_drag.is_some() {
            return;
        }
        // Split divider: drawn, and dragged when grabbed near it.
        if let Some(split) = shown.split {
            let x = rect.min.x + split * rect.width();
            ui.painter().line_segment(
                [egui::pos2(x, rect.min.y), egui::pos2(x, rect.max.y)],
                egui::Stroke::new(2.0, egui::Color32::WHITE),
            );
            ui.painter().text(
                egui::pos2(x + 4.0, rect.min.y + 4.0),
                egui::Align2::LEFT_TOP,
                format!("reference {} spp", shown.reference_spp.unwrap_or(0)),
                egui::FontId::proportional(12.0),
                egui::Color32::WHITE,
            );
            if response.drag_started()
                && let Some(p) = response.interact_pointer_pos()
            {
                self.split_drag = (p.x - x).abs() < 8.0;
            }
            if self.split_drag
                && response.dragged()
                && let Some(p) = response.interact_pointer_pos()
            {
                actions.commands.push(Command::Split(Some(to_uv(p).x)));
                return;
            }
        }
        if response.drag_stopped() {
            self.split_drag = false;
        }
        if response.double_clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            self.log("double-click");
            let id = self.next_pick;
            self.next_pick += 1;
            self.focus_pick = Some(id);
            actions.commands.push(Command::Pick {
                uv: to_uv(p),
                id,
                select: true,
            });
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
            && gizmo.as_ref().is_none_or(|g| g.hit(pointer(p)).is_none())
        {
            self.log("click");
            let id = self.next_pick;
            self.next_pick += 1;
            actions.commands.push(Command::Pick {
                uv: to_uv(p),
                id,
                select: true,
            });
        }
        let Some(mut orbit) = self.orbit else { return };
        let mut moved = false;
        if response.dragged() && !self.split_drag {
            let d = response.drag_delta();
            let (dx, dy) = (d.x / rect.width().max(1.0), d.y / rect.height().max(1.0));
            let pan = response.dragged_by(egui::PointerButton::Secondary)
                || response.dragged_by(egui::PointerButton::Middle)
                || ui.input(|i| i.modifiers.shift);
            if pan {
                orbit.pan(-dx, dy);
            } else if self.fly {
                orbit.look(dx * 3.0, dy * 3.0);
            } else {
                orbit.orbit(dx * 4.0, dy * 4.0);
            }
            moved = true;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                orbit.dolly((-scroll * 0.002).exp());
                moved = true;
                self.log("wheel");
            }
        }
        if moved {
            self.set_camera(orbit);
        }
    }

    /// `--log-input`: the gizmo's place on the window \[physical pixels\] when it moved.
    fn log_gizmo(&mut self, g: &Gizmo, ppp: f32) {
        let Some(x_end) = g.axes[0] else { return };
        let now = [g.centre.x, g.centre.y, x_end.x, x_end.y].map(|v| v * ppp);
        if !self.options.log_input || self.gizmo_logged == Some(now) {
            return;
        }
        self.gizmo_logged = Some(now);
        let ends: Vec<String> = g
            .axes
            .iter()
            .map(|e| {
                e.map_or("none".into(), |e| {
                    format!("{:.1},{:.1}", e.x * ppp, e.y * ppp)
                })
            })
            .collect();
        eprintln!(
            "illume view: gizmo centre_px={:.1},{:.1} axes_px={} length_m={:.5}",
            now[0],
            now[1],
            ends.join(";"),
            g.length_m
        );
    }

    /// The stats overlay in the image's top-left corner: frame time by stage, the
    /// technique's counters, resolution scale.
    fn draw_overlay(&self, painter: &egui::Painter, rect: egui::Rect, shown: &Shown) {
        let t = shown.times;
        let mut text = format!(
            "{}{} · {} · 1/{} ({}×{})\n",
            shown.technique,
            match shown.reference_spp {
                Some(s) if shown.split.is_none() =>
                    format!(" (reference {s}/{} spp)", shown.reference_target),
                Some(s) => format!(" | reference {s}/{} spp", shown.reference_target),
                None => String::new(),
            },
            self.rate_text(),
            shown.scale,
            shown.image.width(),
            shown.image.height()
        );
        text += &format!(
            "G-buffer {:.1} · direct {:.1} · indirect {:.1} · present {:.2} ms\n",
            t.gbuffer_ms, t.direct_ms, t.indirect_ms, self.present_ms
        );
        text += &format!(
            "frame {:.1} ms: update {:.1} · advance {:.1} · reference {:.1}",
            t.total_ms, t.update_ms, t.advance_ms, t.reference_ms
        );
        let prefix = format!("{}.", shown.technique);
        for (k, v) in &shown.stats {
            text += &format!(
                "\n{} {}",
                k.strip_prefix(&prefix).unwrap_or(k),
                short_number(*v)
            );
        }
        if let Some((_, notice)) = &self.rebuilding {
            text += &format!("\n{notice}");
        }
        let galley = painter.layout_no_wrap(
            text,
            egui::FontId::monospace(11.0),
            egui::Color32::from_gray(235),
        );
        let at = rect.min + egui::vec2(6.0, 6.0);
        painter.rect_filled(
            egui::Rect::from_min_size(at, galley.size() + egui::vec2(8.0, 6.0)),
            3.0,
            egui::Color32::from_black_alpha(170),
        );
        painter.galley(at + egui::vec2(4.0, 3.0), galley, egui::Color32::WHITE);
    }
}

/// A counter's value, short.
fn short_number(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.3e}")
    } else if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

/// The gizmo's handles: X red, Y green, Z blue, each ring in a paler tint of its axis's
/// colour (the vertical turn's ring yellow); the handle under the pointer (or dragged)
/// drawn thicker.
fn draw_gizmo(painter: &egui::Painter, g: &Gizmo, active: Option<Handle>) {
    let pos = |v: Vec2| egui::pos2(v.x, v.y);
    let width = |h: Handle| if active == Some(h) { 4.0 } else { 2.0 };
    let ring_colours = [
        egui::Color32::from_rgb(240, 140, 140),
        egui::Color32::from_rgb(240, 200, 40),
        egui::Color32::from_rgb(140, 170, 255),
    ];
    for (k, ring) in g.rings.iter().enumerate() {
        let points: Vec<egui::Pos2> = ring.iter().map(|&p| pos(p)).collect();
        painter.add(egui::Shape::line(
            points,
            egui::Stroke::new(width(Handle::Turn(k)), ring_colours[k]),
        ));
    }
    let colours = [
        egui::Color32::from_rgb(235, 60, 60),
        egui::Color32::from_rgb(60, 210, 60),
        egui::Color32::from_rgb(70, 120, 255),
    ];
    for (i, end) in g.axes.iter().enumerate() {
        if let Some(end) = end {
            let h = Handle::Axis(i);
            painter.line_segment(
                [pos(g.centre), pos(*end)],
                egui::Stroke::new(width(h), colours[i]),
            );
            painter.circle_filled(pos(*end), width(h) + 2.0, colours[i]);
        }
    }
}
