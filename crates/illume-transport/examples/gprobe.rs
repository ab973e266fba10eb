//! Scratch probe (not committed): moving-camera trilinear G-buffers of Sponza.
#![allow(missing_docs)]
use illume_core::Affine3A;
use illume_scene::Edit;
use illume_transport::{GBuffer, TextureFilter, World};
use std::time::Instant;

#[inline(never)]
fn frames_begin() -> u32 {
    std::hint::black_box(17u32).wrapping_mul(3)
}
#[inline(never)]
fn frames_end() -> u64 {
    std::hint::black_box(5u64).wrapping_add(9)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u32 = args.get(1).map_or(10, |a| a.parse().unwrap());
    let (w, h) = (800, 600);
    let sponza = &illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    let mut scene = illume_scene::load_scene(sponza).unwrap();
    let (eye, target) = illume_scene::builtin::SPONZA_ATRIUM_VIEW;
    illume_scene::builtin::look_from(&mut scene, eye, target).unwrap();
    let mut world = World::new(scene);
    let home = world.scene.camera.world_from_camera;
    let mut g = GBuffer::rasterize_with(&world, w, h, TextureFilter::Trilinear);
    let mut times = Vec::new();
    let b = frames_begin();
    for frame in 0..n {
        let yaw = if frame % 2 == 0 { 8.7e-4 } else { -8.7e-4 };
        world
            .apply_edit(&Edit::SetCameraTransform {
                world_from_camera: home * Affine3A::from_rotation_y(yaw),
            })
            .unwrap();
        let t0 = Instant::now();
        g.rasterize_into_with(&world, w, h, TextureFilter::Trilinear);
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        assert_eq!(g.reused_pixels, 0);
    }
    let e = frames_end();
    std::hint::black_box((b, e));
    times.sort_by(f64::total_cmp);
    println!(
        "median {:.2} ms over {n} frames (min {:.2})",
        times[times.len() / 2],
        times[0]
    );
}
