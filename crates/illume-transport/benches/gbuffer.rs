//! G-buffer cost per frame, ray casting against rasterization:
//! `cargo bench -p illume-transport --bench gbuffer`.
//!
//! `rays` is [`GBuffer::render`] (one BVH ray per pixel), `raster` is
//! [`GBuffer::rasterize`] (visibility buffer, then one exact triangle test per pixel),
//! `raster reused` is [`GBuffer::rasterize_into`] into last frame's allocation, and
//! `visibility` is the rasterizer alone ([`VisibilityBuffer::render`]).

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{Criterion, criterion_group, criterion_main};
use illume_core::Vec2;
use illume_transport::{GBuffer, VisibilityBuffer, World};
use std::path::Path;
use std::time::Duration;

const SIZES: [(u32, u32); 3] = [(640, 480), (800, 600), (1280, 1024)];

fn scenes() -> Vec<(&'static str, World)> {
    let mut scenes = vec![(
        "cornell-spot",
        World::new(illume_scene::builtin::load("cornell-spot").expect("builtin")),
    )];
    let sponza = Path::new("/work/shared/scenes/dabrovic_sponza/sponza.obj");
    match illume_scene::load_scene(sponza) {
        Ok(scene) => scenes.push(("sponza", World::new(scene))),
        Err(e) => println!("sponza skipped: {e}"),
    }
    scenes
}

fn gbuffer(c: &mut Criterion) {
    let mut g = c.benchmark_group("gbuffer");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(500));
    g.measurement_time(Duration::from_secs(2));
    for (name, world) in scenes() {
        for (w, h) in SIZES {
            g.bench_function(format!("{name} {w}x{h} rays"), |b| {
                b.iter(|| GBuffer::render(&world, w, h, Vec2::splat(0.5)))
            });
            g.bench_function(format!("{name} {w}x{h} raster"), |b| {
                b.iter(|| GBuffer::rasterize(&world, w, h))
            });
            let mut reused = GBuffer::rasterize(&world, w, h);
            g.bench_function(format!("{name} {w}x{h} raster reused"), |b| {
                b.iter(|| reused.rasterize_into(&world, w, h))
            });
            g.bench_function(format!("{name} {w}x{h} visibility"), |b| {
                b.iter(|| VisibilityBuffer::render(&world.scene, w, h))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, gbuffer);
criterion_main!(benches);
