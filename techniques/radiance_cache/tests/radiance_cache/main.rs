//! The integration tests of illume-radiance-cache, one binary: one module per mechanism of
//! temporal radiance caching.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod agreement;
mod budget;
mod common;
mod glossy_animation;
mod gradients;
mod hsh;
mod modes;
mod octree;
mod radiance;
mod record;
mod record_edges;
mod reproject;
mod screen_floor;
mod settings;
mod settling;
mod silhouettes;
mod technique;
mod temporal;
