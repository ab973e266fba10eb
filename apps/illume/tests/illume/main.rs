//! The integration tests of illume (the CLI), one binary: the `illume` binary run as a user
//! runs it (`env!("CARGO_BIN_EXE_illume")`); the window's tests are the `view` target,
//! which needs a display and runs alone.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod cli;
mod common;
mod corpus;
mod exposure;
mod reproductions;
mod robust;
mod shards;
