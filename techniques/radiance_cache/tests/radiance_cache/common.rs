//! Fixtures shared by the modules of this test binary.

use illume_core::Vec2;
use illume_transport::{GBuffer, World};

/// The image width of the tests on `builtin:cornell-spot` [pixels].
pub const W: u32 = 64;
/// The image height of the tests on `builtin:cornell-spot` [pixels].
pub const H: u32 = 48;

/// `builtin:cornell-spot` and its [`W`] × [`H`] G-buffer (pixel centres).
pub fn cornell() -> (World, GBuffer) {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let g = GBuffer::render(&world, W, H, Vec2::splat(0.5));
    (world, g)
}

/// `f`'s result on a rayon pool of `threads` threads.
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}
