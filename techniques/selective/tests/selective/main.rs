//! The integration tests of illume-selective, one binary: one module per mechanism of
//! selective photon tracing.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod agreement;
mod common;
mod detection;
mod elements;
mod emission;
mod energy;
mod gather;
mod glossy;
mod masking;
mod presets;
mod qmc;
mod recovery;
mod stream;
mod temporal;
