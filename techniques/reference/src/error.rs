//! Why the reference could not run.

/// Errors of the reference path tracer.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// A setting is out of range.
    #[error("reference.{field}: {reason}")]
    InvalidSetting {
        /// The field.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
}
