//! The integration tests of illume-engine, one binary: the frame recipe end to end: image
//! identity, scene changes, the precomputed day, the settings' declared ranges, a
//! still's progress.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod image_identity;
mod precomputed;
mod scene_changes;
mod setting_ranges;
mod still_progress;
mod technique_folders;
mod test_harnesses;
