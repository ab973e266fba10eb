//! Scene changes → invalidation: the reference keeps no state tied to the scene but its
//! running average, so every change that alters the image restarts it. A new G-buffer
//! (camera move) restarts it too, detected in [`crate::state`] from the G-buffer itself.

use illume_scene::SceneChange;

/// True when `changes` alter the light reaching any point (every change, including
/// objects added and removed; a camera move alone changes the G-buffer, which the
/// technique detects by itself, and is counted here too for simplicity).
pub fn restarts_accumulation(changes: &[SceneChange]) -> bool {
    !changes.is_empty()
}
