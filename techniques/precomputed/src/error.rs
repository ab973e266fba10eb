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
    #[error("precomputed: scene {0} has no sun path ([sun] table): nothing to precompute")]
    NoSun(String),
    /// The `.illumepc` file is unusable.
    #[error("precomputed: {0}")]
    File(#[from] crate::file::FileError),
    /// The PCA failed.
    #[error("precomputed: {0}")]
    Pca(#[from] crate::pca::PcaError),
    /// The sun table is invalid.
    #[error("precomputed: {0}")]
    Sun(#[from] illume_scene::sun::SunError),
}
