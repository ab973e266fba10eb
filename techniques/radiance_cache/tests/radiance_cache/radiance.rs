//! Radiance records for glossy surfaces: projection of a gather, the translation
//! gradient against records traced again a step away, the specular shading against
//! direct integration, and a glossy scene against the reference path tracer.

use illume_core::progress::Silent;
use illume_core::{Rgb, Vec3};
use illume_radiance_cache::HemisphereGather;
use illume_radiance_cache::hsh::Quadrature;
use illume_radiance_cache::radiance::{GlossyShading, specular_part};
use illume_radiance_cache::record::{Incoming, RecordSettings};
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_reference::{ReferenceSettings, ReferenceTechnique};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{LightKind, Material, Timeline, Trs};
use illume_transport::metal_rough::MetalRough;
use illume_transport::{GBuffer, Technique, World};

fn settings(strata: u32, jitter: bool) -> RecordSettings {
    RecordSettings {
        theta_strata: strata,
        phi_strata: strata,
        jitter,
        incoming: Incoming::All,
        ..RecordSettings::default()
    }
}

#[test]
fn uniform_radiance_projects_onto_the_constant_function_alone() {
    let glossy = GlossyShading::new(8).unwrap();
    let g =
        HemisphereGather::from_fn(Vec3::Y, &settings(64, false), 1, |_| (Rgb::ONE, 2.0)).unwrap();
    let data = glossy.project(&g, 1e-3);
    // H_0 = 1/√(2π): c_0 = ∫ H_0 dω = √(2π).
    let c0 = (2.0 * std::f32::consts::PI).sqrt();
    assert!(
        (data.coefficients[0].x / c0 - 1.0).abs() < 1e-4,
        "{}",
        data.coefficients[0]
    );
    for (i, c) in data.coefficients.iter().enumerate().skip(1) {
        assert!(c.abs().max_element() < 2e-3 * c0, "c_{i} = {c}");
    }
    for (i, g) in data.translation_gradient.iter().enumerate() {
        assert_eq!(g.max_length(), 0.0, "∇c_{i}");
    }
}

#[test]
fn specular_shading_of_uniform_light_is_the_lobes_albedo() {
    // Under uniform incoming radiance 1, Σ b_i c_i = ∫ f_s cos θ dω, f_s's directional
    // albedo, here integrated directly on a fine quadrature. Roughness 0.5 and above
    // (the default's radiance-record range), views up to 60°.
    let glossy = GlossyShading::new(8).unwrap();
    let g =
        HemisphereGather::from_fn(Vec3::Z, &settings(64, true), 1, |_| (Rgb::ONE, 2.0)).unwrap();
    let c = glossy.project(&g, 1e-3).coefficients;
    let fine = Quadrature::new(400, 800);
    for (metallic, roughness) in [(1.0, 0.5), (1.0, 0.8), (0.0, 0.5), (0.5, 0.7)] {
        let brdf = MetalRough {
            base_color: Rgb::new(0.9, 0.6, 0.3),
            metallic,
            roughness,
        };
        for theta in [0.0f32, 30.0, 60.0] {
            let t = theta.to_radians();
            let wo = Vec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
            let b = glossy.specular_coefficients(&brdf, wo);
            let shaded = illume_radiance_cache::hsh::shade(&b, &c);
            let mut direct = [0.0f64; 3];
            for (d, w) in fine.directions.iter().zip(&fine.weights) {
                let v = specular_part(&brdf, wo, *d) * d.z;
                for k in 0..3 {
                    direct[k] += w * v[k] as f64;
                }
            }
            for k in 0..3 {
                assert!(
                    (shaded[k] as f64 - direct[k]).abs() < 0.01 * direct[k].abs().max(0.05),
                    "m {metallic} r {roughness} θ {theta}: {shaded} vs {direct:?}"
                );
            }
        }
    }
}

/// A 40 m white ceiling 1 m above the origin, facing down, lit by a point light 0.5 m
/// below it: the radiance it sends down varies smoothly.
fn ceiling() -> World {
    let mut b = SceneBuilder::new();
    let white = b.material(Material {
        name: "white".into(),
        base_color: Rgb::splat(0.8),
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::Z * 20.0, Vec3::X * 20.0, white));
    b.placed("ceiling", mesh, Trs::from_translation(Vec3::Y), false);
    let node = b.node(
        "light",
        None,
        Trs::from_translation(Vec3::new(0.3, 0.5, 0.1)),
    );
    b.light(
        "point",
        LightKind::Point {
            intensity: Rgb::splat(4.0),
        },
        node,
    );
    World::new(b.finish("test:ceiling"))
}

#[test]
fn the_translation_gradient_predicts_the_coefficients_a_step_away() {
    let world = ceiling();
    let glossy = GlossyShading::new(8).unwrap();
    let s = RecordSettings {
        incoming: Incoming::Reflected,
        ..settings(64, false)
    };
    let gather = |p: Vec3| HemisphereGather::trace(&world, p, Vec3::Y, 1, &s).unwrap();
    let here = glossy.project(&gather(Vec3::ZERO), 1e-3);
    assert!(here.coefficients[0].x > 0.0, "the ceiling is lit");
    for step in [
        Vec3::X * 0.02,
        Vec3::Z * 0.02,
        Vec3::new(-0.015, 0.0, 0.015),
    ] {
        let there = glossy.project(&gather(step), 1e-3);
        let (mut err, mut change) = (0.0f64, 0.0f64);
        for ((a, b), g) in here
            .coefficients
            .iter()
            .zip(&there.coefficients)
            .zip(&here.translation_gradient)
        {
            let actual = *b - *a;
            let predicted = g.dot(step);
            err += (actual - predicted).length_squared() as f64;
            change += actual.length_squared() as f64;
        }
        let relative = (err / change).sqrt();
        assert!(relative < 0.1, "step {step}: relative error {relative}");
    }
}

#[test]
fn a_glossy_scene_agrees_with_the_reference() {
    // CornellBox-Glossy: the sphere and the short box are glossy (Ns 40: roughness
    // 0.47, metallic 0.6–0.65 by the Phong mapping). Default settings trace their lobes per pixel (below traced_roughness_max =
    // 0.5); with traced_roughness_max = 0.4 radiance records serve them.
    let path = illume_scene::shared_scenes_dir().join("cornell_box/CornellBox-Glossy.obj");
    // The file's light has no material definition: lit by the spot light from above.
    let scene = illume_scene::builtin::spot_from_above(illume_scene::load_scene(&path).unwrap());
    let world = World::new(scene);
    let (w, h) = (64, 48);
    let g = GBuffer::rasterize(&world, w, h);
    let mut reference = ReferenceTechnique::new(ReferenceSettings {
        spp_per_frame: 256,
        seed: 9,
        ..ReferenceSettings::default()
    })
    .unwrap();
    reference.advance(&world, &Default::default());
    let r = reference.indirect(&world, &g);
    let glossy_pixels = g
        .pixels
        .iter()
        .flatten()
        .filter(|p| !p.hit.brdf().is_lambertian())
        .count();
    assert!(glossy_pixels > 200, "{glossy_pixels} glossy pixels");
    for (label, traced_roughness_max) in [("traced", 0.5), ("radiance records", 0.4)] {
        let s = RadianceCacheSettings {
            theta_strata: 32,
            phi_strata: 32,
            temporal: TemporalMode::PerFrame,
            traced_roughness_max,
            ..RadianceCacheSettings::default()
        };
        let timeline = Timeline::single(world.scene.clone(), 0.0, w, h);
        let mut rc = RadianceCache::new(&world, &timeline, s).unwrap();
        rc.precompute(&world, &mut Silent).unwrap();
        let img = rc.indirect(&world, &g);
        // Only the glossy pixels: the Lambertian ones are the other tests' business.
        let (mut a, mut b) = (Rgb::ZERO, Rgb::ZERO);
        for ((p, x), y) in g.pixels.iter().zip(img.pixels()).zip(r.pixels()) {
            if p.is_some_and(|p| !p.hit.brdf().is_lambertian()) {
                a += *x;
                b += *y;
            }
        }
        let energy = a.element_sum() / b.element_sum() - 1.0;
        let block = illume_metrics::block_error(&r, &img, 8).unwrap();
        eprintln!("{label}: glossy pixels' energy {energy:+.4}, block error {block:.4}");
        assert!(energy.abs() < 0.03, "{label}: energy {energy}");
        assert!(block < 0.06, "{label}: block error {block}");
    }
}
