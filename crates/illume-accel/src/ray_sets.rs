//! Reproducible ray sets for benchmarks and comparisons with other ray tracers.

use illume_core::sampling::Pcg32;
use illume_core::{Ray, Vec3};
use illume_scene::Scene;

/// `n` rays with origins uniform in the scene's bounds and directions uniform on the
/// sphere ("incoherent" rays, like diffuse bounces and photon paths), from `seed`.
pub fn incoherent_rays(scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::new(seed, 1);
    let b = scene.bounds();
    let mut u = || rng.next_f64() as f32;
    (0..n)
        .map(|_| {
            let o = b.min + b.extent() * Vec3::new(u(), u(), u());
            let z = 1.0 - 2.0 * u();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

/// One unit-length ray through each pixel centre of a square image of about `n` pixels
/// from the scene camera (its `yfov_rad`, aspect 1), row by row from the top.
pub fn primary_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let side = (n as f64).sqrt().round().max(1.0) as usize;
    let cam = &scene.camera;
    let tan = (cam.yfov_rad * 0.5).tan();
    let origin = Vec3::from(cam.world_from_camera.translation);
    let mut rays = Vec::with_capacity(side * side);
    for y in 0..side {
        for x in 0..side {
            let px = (2.0 * (x as f32 + 0.5) / side as f32 - 1.0) * tan;
            let py = (1.0 - 2.0 * (y as f32 + 0.5) / side as f32) * tan;
            let dir = cam
                .world_from_camera
                .transform_vector3(Vec3::new(px, py, -1.0))
                .normalize();
            rays.push(Ray::new(origin, dir));
        }
    }
    rays
}
