//! Why photon streaming could not start.

/// Why photon streaming could not start.
#[derive(Debug, thiserror::Error)]
pub enum PhotonStreamError {
    /// A setting is out of range.
    #[error("photon_stream.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The scene has no surface to place VSLs on.
    #[error("{scene}: no surface with area to place VSLs on")]
    NoSurfaces {
        /// The scene's source (file or builtin name).
        scene: String,
    },
    /// The shared world's lock was poisoned by a panic elsewhere.
    #[error("the shared world's lock is poisoned")]
    PoisonedWorld,
    /// The simulation thread could not be started.
    #[error("cannot start the photon_stream simulation thread: {0}")]
    Thread(std::io::Error),
}
