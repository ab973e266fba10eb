//! Why the ambient term could not start.

/// Errors of the ambient term.
#[derive(Debug, thiserror::Error)]
pub enum AmbientError {
    /// A setting is out of range.
    #[error("ambient.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}
