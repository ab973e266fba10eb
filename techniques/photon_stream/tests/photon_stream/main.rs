//! The integration tests of illume-photon-stream, one binary: one module per mechanism of
//! photon streaming.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod agreement;
mod common;
mod dynamic;
mod emit;
mod grain;
mod placement;
mod pool;
mod presets;
mod reference;
mod shading_stride;
mod snapshot;
mod soak;
