//! The integration tests of illume-render, one binary: one module per mechanism of the CPU
//! renderer.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod glossy;
mod shadow_maps;
mod sky;
mod terminator;
