//! Typed errors of the measuring library; every error that concerns a file names it.

use illume_core::image::{Image, ImageError};
use std::path::PathBuf;

/// What can go wrong while measuring or reporting.
#[derive(Debug, thiserror::Error)]
pub enum MetricsError {
    /// An image could not be read or written (the inner error names the file).
    #[error(transparent)]
    Image(#[from] ImageError),
    /// Two images that must be compared pixel by pixel differ in size.
    #[error(
        "image sizes differ: reference is {reference_width}×{reference_height}, test is {test_width}×{test_height}"
    )]
    SizeMismatch {
        /// Reference width in pixels.
        reference_width: u32,
        /// Reference height in pixels.
        reference_height: u32,
        /// Test width in pixels.
        test_width: u32,
        /// Test height in pixels.
        test_height: u32,
    },
    /// A measurement failed for a named pair of files.
    #[error("comparing {test} against {reference}: {source}")]
    Pair {
        /// The reference file.
        reference: PathBuf,
        /// The test file.
        test: PathBuf,
        /// What went wrong.
        source: Box<MetricsError>,
    },
    /// The image has no pixels, or is too small for the metric.
    #[error("image is {width}×{height}; {metric} needs at least {min}×{min} pixels")]
    TooSmall {
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
        /// The metric's name.
        metric: &'static str,
        /// Minimum side length in pixels.
        min: u32,
    },
    /// Two sequences (or a sequence and its timestamps) that must pair up differ in length.
    #[error("{what}: lengths differ ({left} vs {right})")]
    LengthMismatch {
        /// Which sequences.
        what: &'static str,
        /// Length of the first.
        left: usize,
        /// Length of the second.
        right: usize,
    },
    /// A temporal metric was given too few frames.
    #[error("{what} needs at least {min} frames, got {got}")]
    TooFewFrames {
        /// The metric.
        what: &'static str,
        /// Minimum frame count.
        min: usize,
        /// Frames given.
        got: usize,
    },
    /// An argument is outside its documented range.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// A metric or tone-mapper name was not recognised.
    #[error("unknown {kind} `{name}` (expected one of: {expected})")]
    UnknownName {
        /// What kind of name (metric, tone mapper).
        kind: &'static str,
        /// The name given.
        name: String,
        /// The accepted names.
        expected: &'static str,
    },
    /// A file or directory could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A CSV file is malformed.
    #[error("{path}:{line}: malformed CSV: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A plot could not be drawn or written.
    #[error("{path}: cannot draw plot: {message}")]
    Plot {
        /// The output file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl MetricsError {
    /// An I/O error on `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

/// `Ok` when both images have the same size, [`MetricsError::SizeMismatch`] otherwise.
pub fn check_same_size<A, B>(reference: &Image<A>, test: &Image<B>) -> Result<(), MetricsError> {
    if (reference.width(), reference.height()) == (test.width(), test.height()) {
        Ok(())
    } else {
        Err(MetricsError::SizeMismatch {
            reference_width: reference.width(),
            reference_height: reference.height(),
            test_width: test.width(),
            test_height: test.height(),
        })
    }
}

/// `Ok` when the image has at least one pixel.
pub(crate) fn check_not_empty<T>(
    image: &Image<T>,
    metric: &'static str,
) -> Result<(), MetricsError> {
    if image.width() == 0 || image.height() == 0 {
        Err(MetricsError::TooSmall {
            width: image.width(),
            height: image.height(),
            metric,
            min: 1,
        })
    } else {
        Ok(())
    }
}
