//! Scene changes → invalidation (§3.1's limits: static geometry, Lambertian materials,
//! one sun path).
//!
//! The sun's motion is on the file's timeline: the clock time picks the keys, nothing
//! is invalidated. A moved static instance, a changed material, or a camera that leaves
//! what the domain allows (`screen`: any move; `cube`: a new position; `atlas`: any
//! camera) makes the file stale: a warning and `stale` counted, never a rebuild (a new
//! file is an offline precompute, `illume precompute`). Dynamic objects moving, lights
//! and objects added or removed change nothing: they neither block the precomputed
//! light nor bleed colour (the paper's limit).

use crate::lookup::Lookup;
use crate::state::Precomputed;
use illume_scene::SceneChange;
use illume_transport::{ChangeResponse, World};

impl Precomputed {
    /// What `changes` do to the technique (see the module docs): counts and warns
    /// about the stale ones; never a rebuild.
    pub(crate) fn on_changes(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        for c in changes {
            let stale = match c {
                SceneChange::InstanceMoved { instance, .. } => world
                    .scene
                    .instances
                    .get(instance.index())
                    .is_some_and(|i| !i.dynamic),
                SceneChange::MaterialChanged { .. } => true,
                // A screen file holds its camera's view, a cube file its position's.
                SceneChange::CameraMoved { from, to } => match self.lookup {
                    Lookup::Screen => !self.pending,
                    Lookup::Cube { .. } => from.translation != to.translation,
                    Lookup::Atlas { .. } => false,
                },
                _ => false,
            };
            if stale {
                self.stale += 1;
                log::warn!(
                    "precomputed: {} no longer matches the scene (a static instance moved, a material changed, or the camera left what a {} file allows): indirect light is stale",
                    self.file.display(),
                    match self.lookup {
                        Lookup::Screen => "screen",
                        Lookup::Cube { .. } => "cube",
                        Lookup::Atlas { .. } => "atlas",
                    }
                );
            }
        }
        ChangeResponse::Updated
    }
}
