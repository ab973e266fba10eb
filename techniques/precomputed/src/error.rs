//! Errors of `precomputed`, prefixed with its name.

/// What can go wrong building, precomputing or loading `precomputed`.
#[derive(Debug, thiserror::Error)]
pub enum PrecomputedError {
    /// A setting is out of range.
    #[error("precomputed.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// Why.
        reason: String,
    },
    /// The scene has no `[sun]` (nothing to precompute a day of).
    #[error("scene {0} has no sun path ([sun] table): nothing to precompute")]
    NoSun(String),
    /// The `.illumepc` file is unusable (the message names it).
    #[error("{0}")]
    File(#[from] crate::file::FileError),
    /// The PCA failed.
    #[error("PCA: {0}")]
    Pca(#[from] crate::pca::PcaError),
    /// The sun table is invalid.
    #[error("{0}")]
    Sun(#[from] illume_scene::sun::SunError),
}
