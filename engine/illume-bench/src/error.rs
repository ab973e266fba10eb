//! Typed errors of the benchmark harness; every error that concerns a file names it.

use std::path::PathBuf;

/// What can go wrong while reading a scenario, running it or writing its report.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The scenario's TOML is malformed or has an unknown key (the message names the key
    /// and line).
    #[error("{path}: {message}")]
    Parse {
        /// The scenario file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// A scenario field has a value outside its documented range.
    #[error("{path}: {field}: {message}")]
    Invalid {
        /// The scenario file.
        path: PathBuf,
        /// The field, e.g. `times_s` or `technique[1].name`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The scene could not be loaded or its animation selected.
    #[error("{path}: scene: {message}")]
    Scene {
        /// The scenario file.
        path: PathBuf,
        /// The loader's message (names the scene file).
        message: String,
    },
    /// A scripted edit names an item the scene does not have, or the scene refused it.
    #[error("{path}: edit[{index}]: {message}")]
    Edit {
        /// The scenario file.
        path: PathBuf,
        /// 0-based index of the `[[edit]]` entry.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A technique could not be built from its settings.
    #[error("{path}: technique[{index}] ({name}): {message}")]
    Technique {
        /// The scenario file.
        path: PathBuf,
        /// 0-based index of the `[[technique]]` entry.
        index: usize,
        /// The technique's name.
        name: String,
        /// What went wrong.
        message: String,
    },
    /// An image could not be read or written (the inner error names the file).
    #[error(transparent)]
    Image(#[from] illume_core::image::ImageError),
    /// A measurement or the report failed.
    #[error(transparent)]
    Metrics(#[from] illume_metrics::MetricsError),
    /// The output folder holds a file illume did not write where it would write one
    /// (the message names it), or its manifest could not be kept.
    #[error(transparent)]
    Output(#[from] illume_core::outputs::OutputError),
}

impl BenchError {
    /// An I/O error on `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
