//! The integration tests of illume-core, one binary: regressions of its image readers.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod exr_fuzz;
