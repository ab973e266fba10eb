//! The integration tests of illume-scene, one binary: the loaders against hand-made and
//! hostile files.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod loaders;
