//! The integration tests of illume-reference, one binary: the reference path tracer against
//! analytic answers and an independent renderer.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod agreement;
mod analytic;
mod denoised;
mod independent_renderer;
