//! The integration tests of illume-transport, one binary: one module per mechanism of the
//! shared light transport.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod emissive_texture;
mod mip;
mod mirror;
mod normal_map;
mod raster;
mod second_world;
mod terminator;
