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

/// A still of builtin scene `name` at `w × h` with radiance caching in `per_frame` mode
/// (`settings` otherwise): its rasterized G-buffer and the indirect image.
pub fn still_indirect(
    name: &str,
    size: (u32, u32),
    settings: illume_radiance_cache::RadianceCacheSettings,
) -> (GBuffer, illume_core::image::RgbImage) {
    let (g, img, _) = still_cache(name, size, settings);
    (g, img)
}

/// [`still_indirect`], also returning the cache the still left (its records).
pub fn still_cache(
    name: &str,
    (w, h): (u32, u32),
    settings: illume_radiance_cache::RadianceCacheSettings,
) -> (
    GBuffer,
    illume_core::image::RgbImage,
    illume_radiance_cache::RadianceCache,
) {
    use illume_transport::Technique;
    let scene = illume_scene::builtin::load(name).unwrap();
    let timeline = illume_scene::Timeline::new(scene.clone(), vec![0.0], w, h).unwrap();
    let world = World::new(scene);
    let settings = illume_radiance_cache::RadianceCacheSettings {
        temporal: illume_radiance_cache::TemporalMode::PerFrame,
        ..settings
    };
    let mut rc = illume_radiance_cache::RadianceCache::new(&world, &timeline, settings).unwrap();
    rc.precompute(&world, &mut illume_core::progress::Silent)
        .unwrap();
    let g = GBuffer::rasterize(&world, w, h);
    let img = rc.indirect(&world, &g);
    (g, img, rc)
}
