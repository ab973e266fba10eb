//! Scene changes → invalidation (§0.5, §0.9.1).
//!
//! Nothing in photon streaming is tied to world positions: VSLs live in object space
//! and move with their object, the tracer's instance level is refitted by the world,
//! and every new photon batch reads the updated world. So an instance move, a light
//! move or emission change, or a material change takes effect at once for new photons,
//! and old photons age out of the FIFO pool within one pool turnover (latency = pool
//! size / impact rate). With [`ChangePolicy::Flush`] the pool is emptied instead.
//! Camera moves change nothing (the paper: photon streaming may even pause then).

use crate::settings::ChangePolicy;
use crate::stream::SharedPool;
use illume_scene::SceneChange;

/// True when `change` alters light transport (everything but a camera move).
pub fn affects_lighting(change: &SceneChange) -> bool {
    !matches!(change, SceneChange::CameraMoved { .. })
}

/// Applies `policy` to the pool for `changes`; returns whether lighting changed.
pub fn on_changes(shared: &SharedPool, policy: ChangePolicy, changes: &[SceneChange]) -> bool {
    if !changes.iter().any(affects_lighting) {
        return false;
    }
    match policy {
        ChangePolicy::AgeOut => {
            let mut s = shared.lock();
            s.photons_at_change = s.pool.photons_pushed();
        }
        ChangePolicy::Flush => {
            shared.flush();
            let mut s = shared.lock();
            s.photons_at_change = s.pool.photons_pushed();
        }
    }
    true
}
