//! Why selective photon tracing could not start.

/// Why selective photon tracing could not start.
#[derive(Debug, thiserror::Error)]
pub enum SelectiveError {
    /// A setting is out of range.
    #[error("selective.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The scene has no triangle with area to bucket photons in.
    #[error("{scene}: no surface with area to hold mesh elements")]
    NoSurfaces {
        /// The scene's source (file or builtin name).
        scene: String,
    },
    /// The streaming thread could not be started.
    #[error("selective: cannot start the streaming thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The shared world's lock was poisoned by a panic elsewhere.
    #[error("the shared world's lock is poisoned")]
    PoisonedWorld,
}
