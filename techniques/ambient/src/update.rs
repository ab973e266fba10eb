//! SceneChange → invalidation: the ambient term keeps no state that a change could make
//! stale (it reads each frame's G-buffer, where moved objects, edited materials and the
//! camera already are), so every change is followed at once and nothing is rebuilt.

use illume_scene::SceneChange;
use illume_transport::ChangeResponse;

/// What `changes` do to the ambient term: nothing to invalidate.
pub fn respond(changes: &[SceneChange]) -> ChangeResponse {
    let _ = changes;
    ChangeResponse::Updated
}
