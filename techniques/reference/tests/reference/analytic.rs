//! The reference path tracer against analytic answers.

use illume_core::{Rgb, Vec2, Vec3};
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_scene::{LightKind, Trs};
use illume_transport::{GBuffer, World};

/// Furnace: a closed sphere with albedo ρ and uniform emission Le has radiance
/// Le/(1 − ρ) everywhere inside (Neumann series Le·Σρᵏ).
#[test]
fn furnace_converges_to_le_over_one_minus_rho() {
    for (rho, le) in [(0.5f32, 1.0f32), (0.8, 0.25)] {
        let world = World::new(illume_scene::builtin::furnace(rho, Rgb::splat(le)));
        let mut r = ReferenceRenderer::new(ReferenceSettings::default(), 16, 16);
        r.add_samples(&world, 256);
        let expected = le / (1.0 - rho);
        let mean = r.images().full.mean();
        for c in 0..3 {
            let rel = (mean[c] - expected).abs() / expected;
            assert!(
                rel < 0.01,
                "ρ={rho}: channel {c} mean {} vs {expected} (rel {rel})",
                mean[c]
            );
        }
        // Split: emitted Le, once-reflected ρLe, the rest ρ²Le/(1−ρ).
        let imgs = r.images();
        let direct = imgs.direct.mean().x;
        let indirect = imgs.indirect.mean().x;
        assert!(
            (direct - le * (1.0 + rho)).abs() / (le * (1.0 + rho)) < 0.01,
            "direct {direct}"
        );
        let ind_expected = rho * rho * le / (1.0 - rho);
        assert!(
            (indirect - ind_expected).abs() / ind_expected < 0.02,
            "indirect {indirect} vs {ind_expected}"
        );
    }
}

/// A diffuse plane (albedo `rho`, faces +y, 10 m square) seen from 3 m above, lit by one
/// light of `kind` placed at `light_at`; optionally a 0.4 m square occluder 0.5 m up.
fn plane_scene(kind: LightKind, light_at: Trs, rho: f32, occluder: bool) -> World {
    World::new(illume_scene::builtin::lit_plane(
        kind, light_at, rho, occluder,
    ))
}

/// A point light over a diffuse plane: reflected radiance ρ/π · I·cosθ/r².
#[test]
fn point_light_over_plane_matches_inverse_square_law() {
    let intensity = Rgb::new(2.0, 1.0, 0.5);
    let light = Vec3::new(0.3, 1.0, -0.2);
    let rho = 0.6;
    let world = plane_scene(
        LightKind::Point { intensity },
        Trs::from_translation(light),
        rho,
        false,
    );
    // Renderer's direct light at pixel centres: exact up to float rounding.
    let g = GBuffer::render(&world, 32, 24, Vec2::splat(0.5));
    let direct = illume_render::direct_light(&world, &g, 1, 0);
    let mut checked = 0;
    for (i, px) in g.pixels.iter().enumerate() {
        let Some(px) = px else { continue };
        let d = light - px.hit.position;
        let r2 = d.length_squared();
        let cos = d.normalize().y;
        let expected = intensity * (rho / std::f32::consts::PI) * cos / r2;
        let got = direct.pixels()[i];
        assert!(
            ((got - expected).abs() / expected).max_element() < 1e-3,
            "pixel {i}: {got} vs {expected}"
        );
        checked += 1;
    }
    assert_eq!(checked, 32 * 24, "every pixel sees the plane");
    // The path tracer (box filter) agrees on the image mean within 1 %, and finds no
    // indirect light (a single plane cannot light itself).
    let mut r = ReferenceRenderer::new(ReferenceSettings::default(), 32, 24);
    r.add_samples(&world, 64);
    let imgs = r.images();
    let (a, b) = (imgs.full.mean(), direct.mean());
    for c in 0..3 {
        assert!(
            (a[c] - b[c]).abs() / b[c] < 0.01,
            "channel {c}: reference {} vs renderer {}",
            a[c],
            b[c]
        );
    }
    assert_eq!(imgs.indirect.mean(), Rgb::ZERO);
}

#[test]
fn same_seed_same_image_different_seed_different_image() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let render = |seed| {
        let mut r = ReferenceRenderer::new(
            ReferenceSettings {
                seed,
                ..Default::default()
            },
            24,
            16,
        );
        r.add_samples(&world, 2);
        r.images().full
    };
    assert_eq!(render(3), render(3));
    assert_ne!(render(3), render(4));
    // Progressive accumulation in two steps equals one step.
    let mut a = ReferenceRenderer::new(ReferenceSettings::default(), 24, 16);
    a.add_samples(&world, 1);
    a.add_samples(&world, 1);
    let mut b = ReferenceRenderer::new(ReferenceSettings::default(), 24, 16);
    b.add_samples(&world, 2);
    assert_eq!(a.images().full, b.images().full);
}

/// Spot (glTF falloff) and directional lights over the plane, analytic per pixel; an
/// occluder casts an exact shadow.
#[test]
fn spot_and_directional_direct_light_match_analytic_values() {
    use illume_scene::spot_falloff;
    let rho = 0.5;
    let build = |kind: LightKind, at: Trs, occluder: bool| plane_scene(kind, at, rho, occluder);
    // Spot 1.5 m up, tilted 20° about x, cones 15°/30°.
    let spot_at = Trs {
        rotation: illume_core::Quat::from_rotation_x(
            -std::f32::consts::FRAC_PI_2 + 20f32.to_radians(),
        ),
        ..Trs::from_translation(Vec3::new(0.2, 1.5, 0.0))
    };
    let (ci, co) = (15f32.to_radians(), 30f32.to_radians());
    let intensity = Rgb::new(3.0, 2.0, 1.0);
    let world = build(
        LightKind::Spot {
            intensity,
            inner_cone_rad: ci,
            outer_cone_rad: co,
        },
        spot_at,
        false,
    );
    let axis = world.scene.lights[0].direction();
    let g = GBuffer::render(&world, 40, 30, Vec2::splat(0.5));
    let direct = illume_render::direct_light(&world, &g, 1, 0);
    let (mut lit, mut dark) = (0, 0);
    for (i, px) in g.pixels.iter().enumerate() {
        let p = px.as_ref().unwrap().hit.position;
        let d = Vec3::new(0.2, 1.5, 0.0) - p;
        let wi = d.normalize();
        let expected = intensity
            * (rho / std::f32::consts::PI)
            * spot_falloff(axis.dot(-wi), ci.cos(), co.cos())
            * wi.y
            / d.length_squared();
        let got = direct.pixels()[i];
        assert!(
            (got - expected).abs().max_element() <= 1e-3 * expected.max_element() + 1e-7,
            "spot pixel {i}: {got} vs {expected}"
        );
        if expected.x > 0.0 {
            lit += 1
        } else {
            dark += 1
        }
    }
    assert!(
        lit > 100 && dark > 100,
        "the view must contain the cone's inside and outside ({lit}/{dark})"
    );
    // Directional light from 30° off vertical: L = ρ/π·E·cosθ everywhere; with an
    // occluder, the pixels whose shadow ray hits the square are exactly 0.
    let sun_at = Trs {
        rotation: illume_core::Quat::from_rotation_x(
            -std::f32::consts::FRAC_PI_2 + 30f32.to_radians(),
        ),
        ..Trs::IDENTITY
    };
    let e = Rgb::new(2.0, 2.0, 2.0);
    for occluder in [false, true] {
        let world = build(LightKind::Directional { irradiance: e }, sun_at, occluder);
        let to_sun = -world.scene.lights[0].direction();
        let g = GBuffer::render(&world, 40, 30, Vec2::splat(0.5));
        let direct = illume_render::direct_light(&world, &g, 1, 0);
        let mut shadowed = 0;
        for (i, px) in g.pixels.iter().enumerate() {
            let hit = &px.as_ref().unwrap().hit;
            if hit.instance.0 == 1 {
                continue; // the occluder itself
            }
            // Does the ray towards the sun pass through the occluder square (|x|,|z| ≤ 0.2 at y = 0.5)?
            let s = (0.5 - hit.position.y) / to_sun.y;
            let q = hit.position + to_sun * s;
            let blocked = occluder && q.x.abs() < 0.2 && q.z.abs() < 0.2;
            let expected = if blocked {
                Rgb::ZERO
            } else {
                e * (rho / std::f32::consts::PI) * to_sun.y
            };
            let on_edge =
                occluder && ((q.x.abs() - 0.2).abs() < 0.01 || (q.z.abs() - 0.2).abs() < 0.01);
            if !on_edge {
                assert!(
                    (direct.pixels()[i] - expected).abs().max_element() < 1e-4,
                    "sun pixel {i} (occluder {occluder})"
                );
            }
            shadowed += blocked as u32;
        }
        assert_eq!(
            shadowed > 0,
            occluder,
            "the occluder must cast a visible shadow"
        );
    }
}
