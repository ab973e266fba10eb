//! The integration tests of illume-metrics, one binary: the image metrics against published
//! values and the reports.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod flip_reference;
mod image_metrics;
mod report;
