//! G-buffer cost per frame, ray casting against rasterization:
//! `cargo bench -p illume-transport --bench gbuffer`.
//!
//! `rays` is [`GBuffer::render`] (one BVH ray per pixel), `raster` is
//! [`GBuffer::rasterize`] into a fresh allocation (visibility buffer, then each pixel's
//! surface from its triangle), `raster moving camera` is [`GBuffer::rasterize_into`] last
//! frame's buffer with the camera turned since (every pixel rebuilt, allocation reused),
//! `raster static` the same with nothing changed (the whole buffer kept), and
//! `visibility` is the rasterizer alone ([`VisibilityBuffer::render`]). Group
//! `hit_tables`: the per-world texture tables (`HitTables::new`).

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{Criterion, criterion_group, criterion_main};
use illume_core::{Affine3A, Vec2};
use illume_scene::Edit;
use illume_transport::{GBuffer, TextureFilter, VisibilityBuffer, World};
use std::time::Duration;

const SIZES: [(u32, u32); 3] = [(640, 480), (800, 600), (1280, 1024)];

fn scenes() -> Vec<(&'static str, World)> {
    let mut scenes = vec![(
        "cornell-spot",
        World::new(illume_scene::builtin::load("cornell-spot").expect("builtin")),
    )];
    let sponza = &illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    match illume_scene::load_scene(sponza) {
        Ok(mut scene) => {
            let (eye, target) = illume_scene::builtin::SPONZA_ATRIUM_VIEW;
            illume_scene::builtin::look_from(&mut scene, eye, target).expect("a valid view");
            scenes.push(("sponza", World::new(scene)))
        }
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
            g.bench_function(format!("{name} {w}x{h} raster static"), |b| {
                b.iter(|| reused.rasterize_into(&world, w, h))
            });
            // Turn the camera by ±0.05° every frame: no pixel can be kept. `moving camera`
            // reads textures bilinearly (as rays do); `moving trilinear` mip-maps them,
            // as the renderer's default does.
            let mut moving = World::new(world.scene.clone());
            let home = moving.scene.camera.world_from_camera;
            let mut frame = 0u32;
            for (label, filter) in [
                ("raster moving camera", TextureFilter::Bilinear),
                ("raster moving trilinear", TextureFilter::Trilinear),
            ] {
                g.bench_function(format!("{name} {w}x{h} {label}"), |b| {
                    b.iter(|| {
                        frame += 1;
                        let yaw = if frame.is_multiple_of(2) {
                            8.7e-4
                        } else {
                            -8.7e-4
                        };
                        moving
                            .apply_edit(&Edit::SetCameraTransform {
                                world_from_camera: home * Affine3A::from_rotation_y(yaw),
                            })
                            .expect("edit");
                        reused.rasterize_into_with(&moving, w, h, filter);
                        assert_eq!(reused.reused_pixels, 0);
                    })
                });
            }
            g.bench_function(format!("{name} {w}x{h} visibility"), |b| {
                b.iter(|| VisibilityBuffer::render(&world.scene, w, h))
            });
        }
    }
    g.finish();
}

/// `HitTables::new`: packing a scene's textures to sRGB-8 codes and building the photon
/// copies (once per `World`, so part of every scene load).
fn hit_tables(c: &mut Criterion) {
    let mut g = c.benchmark_group("hit_tables");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(2));
    for (name, world) in scenes() {
        g.bench_function(format!("{name} HitTables::new"), |b| {
            b.iter(|| illume_transport::hit_tables::HitTables::new(&world.scene))
        });
    }
    g.finish();
}

criterion_group!(benches, gbuffer, hit_tables);
criterion_main!(benches);
