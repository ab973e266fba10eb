//! Scene changes → invalidation (§5.2, and light changes beyond the paper).
//!
//! * `InstanceMoved`, `InstanceRemoved`, `MaterialChanged` (the paper's BSDF phantom),
//!   `LightChanged`: a new current snapshot; every group shot in an older one is stale
//!   and will be re-traced (selectively, most important first).
//! * A light change whose changed lights carry at least `restart_fraction` of the
//!   scene's power: re-tracing costs twice a fresh pool, so the solution restarts (all
//!   accumulators cleared, photons traced again in index order).
//! * `CameraMoved`: only the view-frustum factor V is reset (§5.3).
//! * `InstanceAdded`: a rebuild — mesh elements are laid out once for the instances
//!   present at construction.

use crate::groups::Priority;
use crate::retrace::Snapshot;
use crate::state::Selective;
use illume_scene::SceneChange;
use illume_transport::flux::Quanta;
use illume_transport::{ChangeResponse, World};
use std::sync::Arc;

/// What a list of changes asks of the technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Invalidation {
    /// Nothing photons see changed.
    None,
    /// Only the camera moved: reset V.
    Camera,
    /// Photons may have changed: a new snapshot.
    Lighting,
    /// Build anew.
    Rebuild(&'static str),
}

/// Classifies `changes`.
pub fn classify(changes: &[SceneChange]) -> Invalidation {
    if changes
        .iter()
        .any(|c| matches!(c, SceneChange::InstanceAdded { .. }))
    {
        return Invalidation::Rebuild("an added object has no mesh elements (laid out at start)");
    }
    if changes
        .iter()
        .any(|c| !matches!(c, SceneChange::CameraMoved { .. }))
    {
        return Invalidation::Lighting;
    }
    if changes.is_empty() {
        Invalidation::None
    } else {
        Invalidation::Camera
    }
}

/// The fraction of `new`'s light power carried by lights that differ from `old`
/// (added, changed or moved; lights that vanished count with their old power over the
/// larger total). 0 when no light changed.
pub fn changed_light_fraction(old: &Snapshot, new: &Snapshot) -> f64 {
    let total_new: f64 = new.cells.units().iter().map(|u| u.power).sum();
    let total_old: f64 = old.cells.units().iter().map(|u| u.power).sum();
    let mut changed = 0.0;
    for u in new.cells.units() {
        match old.cells.units().iter().find(|o| o.key == u.key) {
            Some(o) if o.signature == u.signature => {}
            _ => changed += u.power,
        }
    }
    for o in old.cells.units() {
        if !new.cells.units().iter().any(|u| u.key == o.key) {
            changed += o.power;
        }
    }
    let total = total_new.max(total_old);
    if total > 0.0 {
        (changed / total).min(1.0)
    } else {
        0.0
    }
}

impl Selective {
    /// What `changes` do to the solution (see the module docs).
    pub(crate) fn on_changes(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        match classify(changes) {
            Invalidation::None => ChangeResponse::Updated,
            Invalidation::Rebuild(reason) => ChangeResponse::Rebuild { reason },
            Invalidation::Camera => {
                self.reset_view();
                ChangeResponse::Updated
            }
            Invalidation::Lighting => {
                // The emission maps stay (crate::emission), unless the solution restarts
                // and a directional light turned since its map was made.
                let mut next = Snapshot::with_maps(
                    world,
                    self.next_snapshot,
                    self.factors.exponent(2),
                    self.current.cells.maps().clone(),
                );
                self.next_snapshot += 1;
                let fraction = changed_light_fraction(&self.current, &next);
                let restart = fraction > self.settings.restart_fraction as f64;
                if restart && self.settings.emission_map && !next.cells.maps().fit(&next.lights) {
                    let maps = crate::emission::build_maps(
                        world,
                        &self.settings.photon_path(),
                        &self.scramble,
                    );
                    next.cells = next.cells.with_maps(maps);
                    self.counters.emission_maps_built += 1;
                }
                self.current = Arc::new(next);
                if restart {
                    self.restart();
                } else {
                    self.stale = self
                        .groups
                        .iter()
                        .filter(|g| g.epoch.id != self.current.id)
                        .count() as u64;
                }
                if changes
                    .iter()
                    .any(|c| matches!(c, SceneChange::CameraMoved { .. }))
                {
                    self.reset_view();
                }
                ChangeResponse::Updated
            }
        }
    }

    /// The camera moved: every group's view-frustum counters (§5.3's V) and the count of
    /// pilots shot since the move start again, whatever else the change list holds.
    pub(crate) fn reset_view(&mut self) {
        for g in &mut self.groups {
            g.priority.pilots_seen = 0;
            g.priority.pilots_visible = 0;
        }
        self.pilots_since_camera = 0;
    }

    /// Restarts the solution: accumulators cleared, every group current and empty.
    pub(crate) fn restart(&mut self) {
        for a in &mut self.accumulators {
            *a = [Quanta::ZERO; 2];
        }
        for c in &mut self.counts {
            *c = [0; 2];
        }
        for g in &mut self.groups {
            g.epoch = Arc::clone(&self.current);
            g.priority = Priority::default();
        }
        self.stale = 0;
        self.filled = 0;
        self.union = None;
        self.counters.restarts += 1;
    }
}
