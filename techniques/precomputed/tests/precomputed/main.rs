//! The integration tests of illume-precomputed, one binary: one module per mechanism of
//! precomputed indirect light.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod clean_keys;
mod common;
mod domains;
mod file;
mod pca_paper_size;
mod presets;
mod shards;
mod sky_from;
mod split;
mod sun_room;
