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
    assert!(
        plane > 300 && sky > 100,
        "{plane} plane pixels, {sky} sky pixels"
    );
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
        // A photon that could not be emitted counts as a photon carrying nothing.
        let Some(e) = world.lights.sample_emission(&mut rng) else {
            continue;
        };
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

/// An environment map of `w × h` texels, `base` everywhere and `bright` at texel (i, j).
fn env(w: u32, h: u32, base: Rgb, bright: Option<(u32, u32, Rgb)>, rotation_deg: f32) -> Sky {
    let mut texels = vec![base; (w * h) as usize];
    if let Some((i, j, c)) = bright {
        texels[(j * w + i) as usize] = c;
    }
    Sky::Equirect(std::sync::Arc::new(illume_scene::EnvMap {
        name: "test".into(),
        width: w,
        height: h,
        texels: texels.into(),
        scale: 1.0,
        rotation_deg,
        sampling: Default::default(),
    }))
}

/// The README's mapping: u = 0.5 looks along −Z, 0.75 along +X, 0.25 along −X, the edges
/// along +Z, v = 0 up; a positive rotation turns +X toward −Z.
#[test]
fn environment_mapping_is_the_documented_one() {
    let Sky::Equirect(map) = env(16, 8, Rgb::ZERO, None, 0.0) else {
        unreachable!()
    };
    let uv = |d: Vec3| map.uv(d.normalize());
    assert!((uv(-Vec3::Z) - illume_core::Vec2::new(0.5, 0.5)).length() < 1e-6);
    assert!((uv(Vec3::X).x - 0.75).abs() < 1e-6);
    assert!((uv(-Vec3::X).x - 0.25).abs() < 1e-6);
    assert!(uv(Vec3::Z).x.min(1.0 - uv(Vec3::Z).x) < 1e-6);
    assert!(uv(Vec3::Y).y < 1e-6 && (uv(-Vec3::Y).y - 1.0).abs() < 1e-6);
    for d in [Vec3::new(0.3, 0.5, -0.8), Vec3::new(-0.9, -0.2, 0.1)] {
        let d = d.normalize();
        assert!((map.direction(map.uv(d)) - d).length() < 1e-5);
    }
    let Sky::Equirect(turned) = env(16, 8, Rgb::ZERO, None, 90.0) else {
        unreachable!()
    };
    // What was seen along +X is seen along −Z after turning by +90°.
    assert!((turned.uv(-Vec3::Z).x - map.uv(Vec3::X).x).abs() < 1e-6);
}

/// A vertical plane facing +X, seen from +X, under an environment that is black but for
/// one bright texel.
fn lit_by_one_texel(i: u32, j: u32, rotation_deg: f32) -> World {
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        base_color: Rgb::splat(RHO),
        double_sided: false,
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::Y, Vec3::Z, m)); // faces +X
    b.placed("wall", mesh, Trs::IDENTITY, false);
    let cam = b.node(
        "camera",
        None,
        Trs {
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            ..Trs::from_translation(Vec3::new(3.0, 0.0, 0.0))
        },
    );
    b.camera("camera", 40f32.to_radians(), cam);
    let mut scene = b.finish("test:one-texel");
    scene.sky = Some(env(
        16,
        8,
        Rgb::ZERO,
        Some((i, j, Rgb::splat(50.0))),
        rotation_deg,
    ));
    scene.validate().unwrap();
    World::new(scene)
}

#[test]
fn one_bright_texel_lights_the_plane_from_the_stated_direction() {
    // Texel (12, 3): u ≈ 0.78, just above the horizon: from +X.
    // Mean over the wall's pixels (the background shows the sky itself).
    let mean = |world: &World| {
        let g = GBuffer::rasterize(world, 24, 18);
        let direct = direct_light_with(world, &g, Shadows::Rays, 64, 1);
        let wall: Vec<Rgb> = (0..g.pixels.len())
            .filter(|&i| g.pixels[i].is_some())
            .map(|i| *direct.get(i as u32 % 24, i as u32 / 24))
            .collect();
        assert!(wall.len() > 100, "{} wall pixels", wall.len());
        wall.iter().copied().sum::<Rgb>() / wall.len() as f32
    };
    let lit = mean(&lit_by_one_texel(12, 3, 0.0));
    assert!(lit.x > 0.01, "lit from +X: {lit}");
    // Texel (4, 3) is at −X, behind the one-sided wall: nothing.
    assert_eq!(mean(&lit_by_one_texel(4, 3, 0.0)), Rgb::ZERO);
    // Turning the sky by 180° brings texel (4, 3) round to +X.
    let turned = mean(&lit_by_one_texel(4, 3, 180.0));
    assert!(
        ((turned - lit) / lit).abs().max_element() < 0.2,
        "{turned} vs {lit}"
    );
}

/// Importance sampling of an environment with a small bright region is unbiased: the
/// plane facing up gets ρ/π ∫ L cosθ dω (quadrature of the bilinear map) from the renderer
/// and from sky photons.
#[test]
fn environment_importance_sampling_is_unbiased() {
    let sky = env(
        32,
        16,
        Rgb::new(0.2, 0.3, 0.4),
        Some((20, 4, Rgb::splat(200.0))),
        30.0,
    );
    let Sky::Equirect(map) = &sky else {
        unreachable!()
    };
    // Quadrature of ∫_{upper hemisphere} L cosθ dω.
    let n = 800;
    let mut irradiance = Rgb::ZERO;
    for a in 0..n {
        for b in 0..2 * n {
            let theta = (a as f32 + 0.5) / n as f32 * std::f32::consts::FRAC_PI_2;
            let phi = (b as f32 + 0.5) / (2 * n) as f32 * 2.0 * std::f32::consts::PI;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            irradiance += map.lookup(map.uv(d)) * (theta.cos() * theta.sin());
        }
    }
    irradiance *=
        std::f32::consts::FRAC_PI_2 / n as f32 * 2.0 * std::f32::consts::PI / (2 * n) as f32;
    let mut scene = sky_plane();
    scene.sky = Some(sky.clone());
    let world = World::new(scene);
    let g = GBuffer::rasterize(&world, 16, 12);
    let direct = direct_light_with(&world, &g, Shadows::Rays, 256, 2);
    let (mut sum, mut count) = (Rgb::ZERO, 0);
    for (i, px) in g.pixels.iter().enumerate() {
        if px.is_some() {
            sum += *direct.get(i as u32 % 16, i as u32 / 16);
            count += 1;
        }
    }
    let mean = sum / count as f32;
    let expected = irradiance * (RHO / std::f32::consts::PI);
    assert!(
        ((mean - expected) / expected).abs().max_element() < 0.03,
        "renderer {mean} vs {expected}"
    );
    // Sky photons onto the 4 m × 4 m plane.
    let mut rng = Pcg32::new(9, 0);
    let photons = 400_000;
    let mut flux = Rgb::ZERO;
    for _ in 0..photons {
        // A photon that could not be emitted counts as a photon carrying nothing.
        let Some(e) = world.lights.sample_emission(&mut rng) else {
            continue;
        };
        if let Some(hit) = world.trace(&e.ray, illume_scene::MASK_DEFAULT)
            && hit.front_face
        {
            flux += e.flux;
        }
    }
    let got = flux / photons as f32;
    let want = irradiance * 16.0;
    assert!(
        ((got - want) / want).abs().max_element() < 0.03,
        "photons {got} vs {want}"
    );
}
