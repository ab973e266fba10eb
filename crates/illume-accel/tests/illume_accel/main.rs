//! The integration tests of illume-accel, one binary: the two-level BVH against brute
//! force.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod tracer;
