//! The side panel: technique, display, camera, animation, selection, stats.

use super::{Actions, App};
use crate::renderer::{AnimationCommand, Command, Selection};
use glam::Vec3;
use illume_core::image::ToneCurve;
use illume_engine::TechniqueKind;
use illume_scene::{Edit, LightKind};

impl App {
    /// The side panel's sections, top to bottom.
    pub(super) fn panel(&mut self, ui: &mut egui::Ui, actions: &mut Actions) {
        let Some(shown) = self.shown.clone() else {
            ui.label("rendering the first frame…");
            return;
        };
        ui.heading("Technique");
        let mut kind = shown.technique;
        egui::ComboBox::from_id_salt("technique")
            .selected_text(kind.name())
            .show_ui(ui, |ui| {
                for &k in TechniqueKind::ALL {
                    match shown.unavailable.iter().find(|(u, _)| *u == k) {
                        Some((_, why)) => {
                            ui.add_enabled_ui(false, |ui| {
                                ui.selectable_value(&mut kind, k, k.name())
                                    .on_disabled_hover_text(format!("cannot run here: {why}"));
                            });
                        }
                        None => {
                            ui.selectable_value(&mut kind, k, k.name());
                        }
                    }
                }
            })
            .response
            .on_hover_text("T / Shift+T: next / previous technique");
        if kind != shown.technique {
            actions.commands.push(Command::Technique(kind));
        }
        let mut reference = shown.reference_spp.is_some() && shown.split.is_none();
        if ui
            .checkbox(&mut reference, "Reference (R)")
            .on_hover_text("progressive path tracing while nothing moves; restarts on any change")
            .changed()
        {
            actions.commands.push(Command::Reference(reference));
        }
        let mut split = shown.split.is_some();
        if ui.checkbox(&mut split, "Split view (V)").changed() {
            actions.commands.push(Command::Split(split.then_some(0.5)));
        }
        if let Some(spp) = shown.reference_spp {
            ui.label(format!("reference: {spp} / {} spp", shown.reference_target));
        }
        if let Some((flip, spp)) = shown.flip {
            ui.label(format!(
                "FLIP technique vs reference: {flip:.4} (at {spp} spp)"
            ));
        }
        ui.horizontal(|ui| {
            ui.label("Resolution");
            for n in [1u32, 2, 4] {
                if ui
                    .selectable_label(shown.scale == n, format!("1/{n}"))
                    .clicked()
                {
                    actions.commands.push(Command::Scale(n));
                }
            }
        });
        ui.separator();
        ui.heading("Display");
        ui.add(egui::Slider::new(&mut self.exposure_ev, -10.0..=10.0).text("exposure EV"))
            .on_hover_text("stops added to the automatic exposure (render's rule); + / - keys");
        ui.checkbox(&mut self.auto_exposure, "automatic exposure");
        ui.checkbox(&mut self.overlay, "Stats on the image (O)")
            .on_hover_text("frame time by stage, the technique's counters, resolution scale");
        egui::ComboBox::from_id_salt("curve")
            .selected_text(format!("{:?}", self.curve))
            .show_ui(ui, |ui| {
                for c in [ToneCurve::Aces, ToneCurve::Reinhard, ToneCurve::Clamp] {
                    ui.selectable_value(&mut self.curve, c, format!("{c:?}"));
                }
            });
        ui.horizontal(|ui| {
            if ui.button("Screenshot (P)").clicked() {
                actions.screenshot = true;
            }
            let label = if self.recorder.is_some() {
                "Stop clip (K)"
            } else {
                "Record clip (K)"
            };
            if ui.button(label).clicked() {
                actions.record = true;
            }
        });
        ui.separator();
        ui.heading("Camera");
        ui.horizontal(|ui| {
            if ui.button("Reset (Home)").clicked() {
                actions.reset_camera = true;
            }
            ui.checkbox(&mut self.fly, "Fly (F)");
        });
        let mut fov = shown.camera.1.to_degrees();
        if ui
            .add(egui::Slider::new(&mut fov, 5.0..=120.0).text("field of view °"))
            .on_hover_text("vertical field of view [degrees]")
            .changed()
        {
            actions.commands.push(Command::Edit(Edit::SetCameraFov {
                yfov_rad: fov.to_radians(),
            }));
        }
        ui.separator();
        ui.heading("Animation");
        ui.horizontal(|ui| {
            let label = if shown.playing { "Pause" } else { "Play" };
            if ui.button(format!("{label} (Space)")).clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::Play(!shown.playing)));
            }
        });
        let mut t = shown.time_s;
        if ui
            .add(egui::Slider::new(&mut t, 0.0..=shown.duration_s.max(0.001)).text("time s"))
            .changed()
        {
            actions
                .commands
                .push(Command::Animation(AnimationCommand::Seek(t)));
        }
        ui.horizontal(|ui| {
            for s in [0.25, 0.5, 1.0, 2.0] {
                if ui.button(format!("{s}×")).clicked() {
                    actions
                        .commands
                        .push(Command::Animation(AnimationCommand::Speed(s)));
                }
            }
        });
        ui.horizontal(|ui| {
            if ui.button("loop").clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::PingPong(false)));
            }
            if ui.button("ping-pong").clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::PingPong(true)));
            }
        });
        ui.separator();
        ui.heading("Selection");
        ui.horizontal_wrapped(|ui| {
            ui.label("lights:");
            for (i, (name, _)) in shown.lights.iter().enumerate() {
                if ui.small_button(name.as_str()).clicked() {
                    actions
                        .commands
                        .push(Command::Select(Some(Selection::Light(i as u32))));
                }
            }
        });
        match &shown.selection {
            None => {
                ui.label("click an object (or near a light)");
            }
            Some((sel, name)) => {
                ui.label(format!("{sel:?}: {name}"));
                ui.label("arrows/PgUp/PgDn move, Shift+←/→ turn");
                if let Selection::Light(i) = sel
                    && let Some((_, kind)) = shown.lights.get(*i as usize)
                    && let Some(new) = light_editor(ui, *kind)
                {
                    actions.commands.push(Command::Edit(Edit::SetLightKind {
                        light: illume_scene::LightId(*i),
                        kind: new,
                    }));
                }
            }
        }
        if !shown.materials.is_empty() {
            ui.horizontal(|ui| {
                ui.label("material");
                let i = self.selected_material.min(shown.materials.len() - 1);
                egui::ComboBox::from_id_salt("material")
                    .selected_text(shown.materials[i].0.as_str())
                    .show_ui(ui, |ui| {
                        for (j, (name, _)) in shown.materials.iter().enumerate() {
                            ui.selectable_value(&mut self.selected_material, j, name.as_str());
                        }
                    });
            });
            let i = self.selected_material.min(shown.materials.len() - 1);
            let c = shown.materials[i].1;
            let mut rgb = [c.x, c.y, c.z];
            if ui.color_edit_button_rgb(&mut rgb).changed() {
                actions.material = Some((i, Vec3::from(rgb)));
            }
        }
        ui.separator();
        egui::CollapsingHeader::new(format!("Settings: {}", shown.technique))
            .default_open(false)
            .show(ui, |ui| self.settings(ui, &shown, actions));
        egui::CollapsingHeader::new("Stats")
            .default_open(true)
            .show(ui, |ui| {
                let t = shown.times;
                ui.label(self.rate_text());
                ui.label(format!(
                    "update {:.1} · advance {:.1} ms",
                    t.update_ms, t.advance_ms
                ));
                ui.label(format!(
                    "G-buffer {:.1} · direct {:.1} · indirect {:.1} ms",
                    t.gbuffer_ms, t.direct_ms, t.indirect_ms
                ));
                ui.label(format!(
                    "reference {:.1} · frame {:.1} · present {:.2} ms",
                    t.reference_ms, t.total_ms, self.present_ms
                ));
                ui.label(format!(
                    "resolution 1/{} ({}×{})",
                    shown.scale,
                    shown.image.width(),
                    shown.image.height()
                ));
                for (k, v) in &shown.stats {
                    ui.label(format!("{k} {v:.4}"));
                }
            });
        let mut all: Vec<String> = shown.messages.clone();
        all.extend(self.messages.all());
        for m in all.iter().rev().take(6) {
            ui.colored_label(egui::Color32::YELLOW, m);
        }
    }
}

/// Colour, intensity and cone of a light; the new kind when changed.
fn light_editor(ui: &mut egui::Ui, kind: LightKind) -> Option<LightKind> {
    let split = |c: Vec3| {
        let m = c.max_element().max(1e-12);
        ((c / m).to_array(), m)
    };
    let mut changed = false;
    let mut edit_power = |ui: &mut egui::Ui, c: Vec3, unit: &str| -> Vec3 {
        let (mut rgb, mut scale) = split(c);
        let speed = scale * 0.01 + 1e-3;
        ui.horizontal(|ui| {
            changed |= ui.color_edit_button_rgb(&mut rgb).changed();
            changed |= ui
                .add(
                    egui::DragValue::new(&mut scale)
                        .speed(speed)
                        .range(0.0..=1e9),
                )
                .on_hover_text(unit)
                .changed();
        });
        Vec3::from(rgb) * scale
    };
    let new = match kind {
        LightKind::Point { intensity } => LightKind::Point {
            intensity: edit_power(ui, intensity, "intensity [W/sr]"),
        },
        LightKind::Directional { irradiance } => LightKind::Directional {
            irradiance: edit_power(ui, irradiance, "irradiance [W/m²]"),
        },
        LightKind::Spot {
            intensity,
            inner_cone_rad,
            outer_cone_rad,
        } => {
            let intensity = edit_power(ui, intensity, "intensity [W/sr]");
            let mut inner = inner_cone_rad.to_degrees();
            let mut outer = outer_cone_rad.to_degrees();
            changed |= ui
                .add(egui::Slider::new(&mut outer, 1.0..=90.0).text("outer cone °"))
                .changed();
            changed |= ui
                .add(egui::Slider::new(&mut inner, 0.0..=outer).text("inner cone °"))
                .changed();
            LightKind::Spot {
                intensity,
                inner_cone_rad: inner.min(outer).to_radians(),
                outer_cone_rad: outer.to_radians(),
            }
        }
    };
    changed.then_some(new)
}
