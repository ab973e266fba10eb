//! Scene changes → invalidation (§0.5, §0.9.1).
//!
//! Nothing in photon streaming is tied to world positions: VSLs live in object space
//! and move with their object, the tracer's instance level is refitted by the world,
//! and every new photon batch reads the updated world. So an instance move, a light
//! move or emission change, or a material change takes effect at once for new photons,
//! and old photons age out of the FIFO pool within one pool turnover (latency = pool
//! size / impact rate). With [`ChangePolicy::Flush`] the pool is emptied instead.
//! Camera moves change nothing (the paper: photon streaming may even pause then). The
//! streaming thread rests once the pool has turned over after a change
//! ([`PhotonStreamSettings::rest_when_settled`](crate::PhotonStreamSettings::rest_when_settled));
//! a change that affects lighting wakes it.
//!
//! A removed object is an ordinary lighting change: rays no longer see it, so its VSLs
//! receive no new photons and their power ages out with the pool. An added object asks
//! for a rebuild: VSLs are placed once, per object, before streaming starts (§0.4.2,
//! Algorithm 1), and a new object has none to receive or emit its photons' power.

use crate::settings::ChangePolicy;
use crate::stream::SharedPool;
use illume_scene::SceneChange;
use illume_transport::ChangeResponse;

/// True when `change` alters light transport (everything but a camera move).
pub fn affects_lighting(change: &SceneChange) -> bool {
    !matches!(change, SceneChange::CameraMoved { .. })
}

/// Applies `policy` to the pool for `changes`.
pub fn on_changes(
    shared: &SharedPool,
    policy: ChangePolicy,
    changes: &[SceneChange],
) -> ChangeResponse {
    if changes
        .iter()
        .any(|c| matches!(c, SceneChange::InstanceAdded { .. }))
    {
        return ChangeResponse::Rebuild {
            reason: "an added object has no VSLs (they are placed once, §0.4.2)",
        };
    }
    if !changes.iter().any(affects_lighting) {
        return ChangeResponse::Updated;
    }
    if policy == ChangePolicy::Flush {
        shared.flush();
    }
    shared.lighting_changed();
    ChangeResponse::Updated
}
