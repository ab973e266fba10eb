//! The keys (listed in `docs/viewer.md`).

use super::{Actions, App};
use crate::renderer::{AnimationCommand, Command};
use egui::Key;
use glam::{Quat, Vec3};
use illume_engine::TechniqueKind;

impl App {
    /// The keys pressed since the last redraw, and fly mode's WASD while held.
    pub(super) fn keys(&mut self, ctx: &egui::Context, actions: &mut Actions) {
        let Some(shown) = self.shown.clone() else {
            return;
        };
        let (pressed, shift, dt): (Vec<Key>, bool, f32) = ctx.input(|i| {
            (
                i.events
                    .iter()
                    .filter_map(|e| match e {
                        egui::Event::Key {
                            key, pressed: true, ..
                        } => Some(*key),
                        _ => None,
                    })
                    .collect(),
                i.modifiers.shift,
                i.stable_dt.min(0.1),
            )
        });
        for key in pressed {
            let mut handled = true;
            match key {
                Key::T => {
                    // The next technique that can run on this scene (a technique that
                    // failed to build is skipped; its reason is in the panel).
                    let all = TechniqueKind::ALL;
                    let i = all.iter().position(|k| *k == shown.technique).unwrap_or(0);
                    let n = all.len();
                    let next = (1..n)
                        .map(|d| all[if shift { (i + n - d) % n } else { (i + d) % n }])
                        .find(|k| !shown.unavailable.iter().any(|(u, _)| u == k));
                    if let Some(next) = next {
                        actions.commands.push(Command::Technique(next));
                    }
                }
                Key::R => {
                    let on = !(shown.reference_spp.is_some() && shown.split.is_none());
                    actions.commands.push(Command::Reference(on));
                }
                Key::V => actions
                    .commands
                    .push(Command::Split(shown.split.is_none().then_some(0.5))),
                Key::Space => actions
                    .commands
                    .push(Command::Animation(AnimationCommand::Play(!shown.playing))),
                Key::Home | Key::C => actions.reset_camera = true,
                Key::F => self.fly = !self.fly,
                Key::O => self.overlay = !self.overlay,
                Key::P => actions.screenshot = true,
                Key::K => actions.record = true,
                Key::Num1 => actions.commands.push(Command::Scale(1)),
                Key::Num2 => actions.commands.push(Command::Scale(2)),
                Key::Num4 => actions.commands.push(Command::Scale(4)),
                Key::Plus | Key::Equals => self.exposure_ev += 0.5,
                Key::Minus => self.exposure_ev -= 0.5,
                Key::Escape => actions.commands.push(Command::Select(None)),
                Key::ArrowLeft
                | Key::ArrowRight
                | Key::ArrowUp
                | Key::ArrowDown
                | Key::PageUp
                | Key::PageDown => {
                    self.move_key(key, shift, actions);
                }
                _ => handled = !self.fly || !matches!(key, Key::W | Key::A | Key::S | Key::D),
            }
            if handled {
                self.log(&format!("key {key:?}"));
            }
        }
        // Fly mode: WASD (Q/E down/up) while held.
        if self.fly
            && let Some(mut orbit) = self.orbit
        {
            let speed = orbit.distance.max(0.1) * dt;
            let (f, r, u) = ctx.input(|i| {
                let axis = |a: Key, b: Key| (i.key_down(a) as i32 - i.key_down(b) as i32) as f32;
                (
                    axis(Key::W, Key::S),
                    axis(Key::D, Key::A),
                    axis(Key::E, Key::Q),
                )
            });
            if f != 0.0 || r != 0.0 || u != 0.0 {
                orbit.fly(f * speed, r * speed, u * speed);
                // Keys held: keep moving at every refresh.
                ctx.request_repaint();
                self.set_camera(orbit);
            }
        }
    }

    /// Arrow keys move the selection across the floor relative to the view; PgUp/PgDn
    /// up and down; Shift+←/→ turn it.
    fn move_key(&self, key: Key, shift: bool, actions: &mut Actions) {
        let Some(orbit) = self.orbit else { return };
        let m = orbit.world_from_camera();
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize_or_zero();
        let right = flat(m.transform_vector3(Vec3::X));
        let forward = flat(m.transform_vector3(-Vec3::Z));
        let step = 0.05 * orbit.distance;
        let (translate, turn_rad) = match (key, shift) {
            (Key::ArrowLeft, true) => (Vec3::ZERO, 15f32.to_radians()),
            (Key::ArrowRight, true) => (Vec3::ZERO, -15f32.to_radians()),
            (Key::ArrowLeft, false) => (-right * step, 0.0),
            (Key::ArrowRight, false) => (right * step, 0.0),
            (Key::ArrowUp, _) => (forward * step, 0.0),
            (Key::ArrowDown, _) => (-forward * step, 0.0),
            (Key::PageUp, _) => (Vec3::Y * step, 0.0),
            (Key::PageDown, _) => (-Vec3::Y * step, 0.0),
            _ => return,
        };
        actions.commands.push(Command::MoveSelected {
            translate,
            rotate: Quat::from_rotation_y(turn_rad),
        });
    }
}
