//! The integration tests of illume-bench, one binary: scenarios, replays, shards and whole
//! benchmark runs.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod common;
mod end_to_end;
mod reference_noise;
mod replay;
mod scenario;
mod shards;
