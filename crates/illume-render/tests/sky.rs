//! A uniform sky over a Lambertian plane facing up, with nothing else: the plane's
//! radiance is ρ·L_sky exactly (renderer and path kernel), pixels that see nothing see
//! L_sky, and sky photons bring the plane its irradiance π·L_sky.

use illume_core::sampling::Pcg32;
use illume_core::{Quat, Rgb, Vec3};
use illume_render::{Shadows, direct_light_with};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Scene, Sky, Trs};
use illume_transport::path::{PathSettings, radiance};
use illume_transport::{CameraRays, GBuffer, World};

const RHO: f32 = 0.6;
const SKY: Rgb = Rgb::new(0.5, 1.0, 2.0);

/// A 4 m square plane (faces +y, one-sided) under a uniform sky, seen obliquely so that
/// the horizon (empty pixels) is in view.
fn sky_plane() -> Scene {
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        base_color: Rgb::splat(RHO),
        double_sided: false,
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::Z * 2.0, Vec3::X * 2.0, m));
    b.placed("plane", mesh, Trs::IDENTITY, false);
    let cam = b.node(
        "camera",
        None,
        Trs {
            rotation: Quat::from_rotation_x(-0.5),
            ..Trs::from_translation(Vec3::new(0.0, 1.5, 3.0))
        },
    );
    b.camera("camera", 60f32.to_radians(), cam);
    let mut scene = b.finish("test:sky-plane");
    scene.sky = Some(Sky::Uniform { radiance: SKY });
    scene.validate().unwrap();
    scene
}

#[test]
fn uniform_sky_over_a_plane_is_rho_times_sky() {
    let world = World::new(sky_plane());
    let (w, h) = (40, 30);
    let g = GBuffer::rasterize(&world, w, h);
    let direct = direct_light_with(&world, &g, Shadows::Rays, 4, 0);
    let rays = CameraRays::new(&world.scene.camera, w, h);
    let (mut plane, mut sky) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let got = *direct.get(x, y);
            let path = radiance(
                &world,
                &rays.ray(x, y, illume_core::Vec2::splat(0.5)),
                &mut Pcg32::new(3, (y * w + x) as u64),
                &PathSettings::default(),
            );
            let expected = match g.pixels[(y * w + x) as usize] {
                Some(_) => {
                    plane += 1;
                    SKY * RHO
                }
                None => {
                    sky += 1;
                    SKY
                }
            };
            for (what, v) in [("renderer", got), ("path kernel", path.total())] {
                assert!(
                    (v - expected).abs().max_element() <= 1e-5 * expected.max_element(),
                    "pixel ({x}, {y}), {what}: {v} vs {expected}"
                );
            }
            assert_eq!(path.indirect, Rgb::ZERO, "nothing to bounce off twice");
        }
    }
    assert!(plane > 300 && sky > 100, "{plane} plane pixels, {sky} sky pixels");
}

/// Sky photons: the mean flux reaching the plane's front face is its irradiance π·L
/// times its area (4 m × 4 m), within Monte Carlo error.
#[test]
fn sky_photons_bring_the_plane_its_irradiance() {
    let world = World::new(sky_plane());
    let n = 400_000;
    let mut rng = Pcg32::new(5, 0);
    let mut flux = Rgb::ZERO;
    for _ in 0..n {
        let e = world.lights.sample_emission(&mut rng).expect("the sky emits");
        if let Some(hit) = world.trace(&e.ray, illume_scene::MASK_DEFAULT)
            && hit.front_face
        {
            flux += e.flux;
        }
    }
    let mean = flux / n as f32;
    let expected = SKY * (std::f32::consts::PI * 16.0);
    assert!(
        ((mean - expected) / expected).abs().max_element() < 0.03,
        "{mean} vs {expected}"
    );
    assert!(!world.lights.is_empty());
}
