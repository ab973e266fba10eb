//! An emitter with an emissive texture: what rays see, next-event estimation and photon
//! emission all use the radiance at the point (factor × texel), and stay unbiased; the
//! rasterized G-buffer shows the same emission as rays (it hands such triangles to a BVH
//! ray per pixel).

use illume_core::sampling::Pcg32;
use illume_core::{Ray, Rgb, Vec2, Vec3};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Mesh, Texture, Trs, WrapMode};
use illume_transport::{GBuffer, TextureFilter, World};

const LE: f32 = 3.0;

/// A 1 m² light facing down at y = 1 whose texture is bright on its u < ½ half (1.0)
/// and dim on the other (0.1), over a floor.
fn world() -> World {
    world_with(false)
}

/// [`world`], with the dim half cut away by an alpha mask when `cut`.
fn world_with(cut: bool) -> World {
    let mut b = SceneBuilder::new();
    let tex = b.texture(Texture {
        name: "halves".into(),
        width: 2,
        height: 1,
        texels: vec![Rgb::splat(1.0), Rgb::splat(0.1)],
        wrap_u: WrapMode::Clamp,
        wrap_v: WrapMode::Clamp,
        alpha: if cut { vec![255, 0] } else { vec![] },
    });
    let light = b.material(Material {
        base_color: Rgb::ZERO,
        emission: Rgb::splat(LE),
        emissive_texture: Some(tex),
        alpha_texture: cut.then_some(tex),
        alpha_cutoff: cut.then_some(0.5),
        double_sided: false,
        ..Default::default()
    });
    let floor = b.material(Material::default());
    // Faces −y (x × z = −y); its u runs along +x.
    let lamp = b.mesh(quad(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::X * 0.5,
        Vec3::Z * 0.5,
        light,
    ));
    b.placed("lamp", lamp, Trs::IDENTITY, false);
    let ground = b.mesh(quad(Vec3::ZERO, Vec3::Z * 3.0, Vec3::X * 3.0, floor));
    b.placed("floor", ground, Trs::IDENTITY, false);
    let cam = b.node(
        "camera",
        None,
        Trs::from_translation(Vec3::new(0.0, 0.5, 3.0)),
    );
    b.camera("camera", 60f32.to_radians(), cam);
    let scene = b.finish("test:emissive-texture");
    scene.validate().unwrap();
    World::new(scene)
}

/// Radiance of the lamp at world point (x, 1, z) by the quad's UV layout (0 where a ray
/// passes through it).
fn le_at(world: &World, x: f32, z: f32) -> f32 {
    world
        .trace(
            &Ray::new(Vec3::new(x, 0.5, z), Vec3::Y),
            illume_scene::MASK_DEFAULT,
        )
        .map_or(0.0, |hit| hit.emission.x)
}

#[test]
fn rays_see_the_textured_radiance() {
    let w = world();
    // The two halves of the lamp along x (u runs with x here).
    let (a, b) = (le_at(&w, -0.3, 0.0), le_at(&w, 0.3, 0.0));
    assert!(((a - LE) / LE).abs() < 1e-4, "bright half {a}");
    assert!(((b - 0.1 * LE) / LE).abs() < 1e-4, "dim half {b}");
}

#[test]
fn nee_and_photons_are_unbiased_with_a_texture() {
    nee_and_photons_match_quadrature(&world());
}

/// An alpha-masked emitter emits nothing from its holes: NEE and photons agree with
/// what rays see (the lamp's bright half only).
#[test]
fn nee_and_photons_skip_the_holes_of_a_cut_out_emitter() {
    let w = world_with(true);
    assert_eq!(le_at(&w, 0.3, 0.0), 0.0, "rays pass through the cut half");
    assert!(le_at(&w, -0.3, 0.0) > 0.0);
    nee_and_photons_match_quadrature(&w);
}

/// NEE irradiance at the origin and the photons' mean flux against quadratures of what
/// rays see of the lamp.
fn nee_and_photons_match_quadrature(w: &World) {
    // Quadrature of the irradiance at the origin and of the power, from what rays see.
    let n = 400;
    let (mut e, mut power) = (0f64, 0f64);
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (
                (i as f32 + 0.5) / n as f32 - 0.5,
                (j as f32 + 0.5) / n as f32 - 0.5,
            );
            let le = le_at(w, x, z) as f64;
            let d = Vec3::new(x, 1.0, z);
            let r2 = d.length_squared() as f64;
            let cos = 1.0 / r2.sqrt();
            e += le * cos * cos / r2;
            power += le * std::f64::consts::PI;
        }
    }
    let da = 1.0 / (n * n) as f64;
    let (e, power) = (e * da, power * da);
    // NEE from the origin (the floor's point under the lamp).
    let mut rng = Pcg32::new(4, 0);
    let samples = 200_000;
    let mut est = 0f64;
    for _ in 0..samples {
        if let Some(s) = w.lights.sample_incident(Vec3::ZERO, &mut rng) {
            est += (s.weight.x * s.wi.y.max(0.0)) as f64;
        }
    }
    let est = est / samples as f64;
    assert!((est / e - 1.0).abs() < 0.01, "NEE irradiance {est} vs {e}");
    // Photons: their mean flux is the lamp's power.
    let mut flux = 0f64;
    for _ in 0..samples {
        flux += w
            .lights
            .sample_emission(&mut rng)
            .map_or(0.0, |p| p.flux.x as f64);
    }
    let flux = flux / samples as f64;
    assert!(
        (flux / power - 1.0).abs() < 0.01,
        "photon power {flux} vs {power}"
    );
}

/// A 2 m square facing +y, seen from 3 m above, emitting 4 × a texture that is bright
/// (1) on its left half and dark (0.25) on its right half.
fn glowing_floor() -> World {
    let mut b = SceneBuilder::new();
    let tex = b.texture(Texture::from_fn("halves", 8, 8, |x, _| {
        Rgb::splat(if x < 4 { 1.0 } else { 0.25 })
    }));
    let m = b.material(Material {
        base_color: Rgb::splat(0.5),
        emission: Rgb::splat(4.0),
        emissive_texture: Some(tex),
        ..Default::default()
    });
    let floor = quad(Vec3::ZERO, Vec3::Z, Vec3::X, m);
    let mesh = b.mesh(Mesh {
        name: "floor".into(),
        ..floor
    });
    b.placed("floor", mesh, Trs::IDENTITY, false);
    b.camera_looking_down(3.0, 40f32.to_radians());
    let scene = b.finish("test:glowing-floor");
    scene.validate().unwrap();
    World::new(scene)
}

#[test]
fn rasterized_emission_reads_the_emissive_texture_as_rays_do() {
    let world = glowing_floor();
    let (w, h) = (64, 48);
    let rays = GBuffer::render(&world, w, h, Vec2::splat(0.5));
    for filter in [TextureFilter::Bilinear, TextureFilter::Trilinear] {
        let raster = GBuffer::rasterize_with(&world, w, h, filter);
        let (mut compared, mut bright, mut dark) = (0, 0, 0);
        for (r, t) in raster.pixels.iter().zip(&rays.pixels) {
            let (Some(r), Some(t)) = (r, t) else { continue };
            let (re, te) = (r.hit.emission, t.hit.emission);
            // Bilinear lookups at uv a rounding apart: equal but for the texels'
            // boundary column.
            assert!(
                (re - te).abs().max_element() <= 0.05 * te.max_element() + 1e-3,
                "{filter:?}: raster emission {re}, rays {te}"
            );
            compared += 1;
            bright += usize::from(re.x > 3.9);
            dark += usize::from(re.x < 1.1);
        }
        assert!(compared > 500, "only {compared} pixels see the floor");
        // Both halves show: the texture, not the bare factor 4 everywhere.
        assert!(
            bright > compared / 4 && dark > compared / 4,
            "{filter:?}: {bright} bright and {dark} dark of {compared} pixels"
        );
    }
}
