//! Scene changes → invalidation (§4.2–§4.3, and surprises beyond the paper).
//!
//! * **Changes on the timeline** (the frame about to be rendered is the timeline's, in
//!   time and in everything records depend on): expire nothing. They are what τ and the
//!   lifespans are for.
//! * **Surprises** (changes not on the timeline: edits, frames off it): the plan of
//!   `interpolated` is dropped and the loop goes on online (as `extrapolated`). With
//!   `expire_on_surprise`, a moved, added or removed instance expires the records on it
//!   and the records whose rays hit it; a light, sky or material change expires every
//!   record (at the next frame's expiry, [`crate::expiry`]).
//! * **Camera moves** expire nothing (records are world-space).
//! * In real time, a world change after rest restarts the age clock and spreads the
//!   remaining lives of the records that stopped ageing.
//!
//! The technique never asks for a rebuild: records are made where the G-buffer asks,
//! whatever instances exist.

use crate::state::RadianceCache;
use illume_core::sampling::mix64;
use illume_scene::{Scene, SceneChange};
use illume_transport::{ChangeResponse, World};

/// True when the parts of `a` that records depend on (instances, lights, materials,
/// sky) equal `b`'s: the camera and the time may differ.
pub(crate) fn same_lighting(a: &Scene, b: &Scene) -> bool {
    a.instances == b.instances
        && a.lights == b.lights
        && a.materials == b.materials
        && a.sky == b.sky
}

impl RadianceCache {
    /// The world changes after resting: records that stopped ageing resume with their
    /// remaining lives spread over 1 to their lifespan (by their key), as records made
    /// frame after frame have them, so that they expire over the next δt_max frames
    /// instead of all at once.
    pub(crate) fn stagger_ages(&mut self) {
        let clock = self.age_clock;
        for slot in self.slots.iter_mut().flatten() {
            let lifespan = slot.record.lifespan_frames.max(1);
            let age = (mix64(slot.key) % u64::from(lifespan)) as u32;
            slot.made_clock = slot.made_clock.min(clock.saturating_sub(age));
        }
    }

    /// What `changes` do to the cache (see the module docs); never a rebuild.
    pub(crate) fn on_changes(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        self.changed_since_frame = true;
        let world_changed = changes
            .iter()
            .any(|c| !matches!(c, SceneChange::CameraMoved { .. }));
        if world_changed {
            if self.settings.paced_real_time && !self.age_clock_running() {
                self.stagger_ages();
            }
            self.last_world_change = Some(self.frame);
        }
        // On the timeline: the frame about to be rendered is the timeline's, in time and
        // in everything records depend on. τ and the lifespans handle such changes.
        let on_timeline = self.temporal()
            && self
                .timeline
                .times()
                .get(self.frame as usize)
                .is_some_and(|&t| {
                    t == world.scene.time
                        && same_lighting(&self.timeline.scene_at_time(t), &world.scene)
                });
        if on_timeline {
            return ChangeResponse::Updated;
        }
        if world_changed {
            // Pass 2's plan assumed the timeline: online from here.
            self.plan = None;
            self.next_world = None;
        }
        if !self.settings.expire_on_surprise {
            return ChangeResponse::Updated;
        }
        for c in changes {
            match c {
                SceneChange::CameraMoved { .. } => {}
                SceneChange::InstanceMoved { instance, .. }
                | SceneChange::InstanceAdded { instance }
                | SceneChange::InstanceRemoved { instance, .. } => {
                    self.expire_instances.push(*instance)
                }
                _ => self.expire_all = true,
            }
        }
        ChangeResponse::Updated
    }
}
