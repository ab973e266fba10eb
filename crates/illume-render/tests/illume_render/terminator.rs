//! The shadow terminator of a faceted sphere: a sun lights a 16×8 sphere, and along its
//! terminator every pixel's direct light, by shadow rays and by shadow maps, is the
//! unshadowed E·ρ/π·cosθ of its shading normal, as on a smooth sphere. Facets that turn away from
//! the sun while their interpolated normals still face it used to go black, one facet at
//! a time: the lit side ended in steps (`World::shadow_ray`, Hanika 2021).

use illume_core::{Quat, Rgb, Vec3};
use illume_render::{ShadowMapSettings, ShadowMaps, Shadows, direct_light_with};
use illume_scene::builtin::{SceneBuilder, look_from, uv_sphere};
use illume_scene::{LightKind, Material, Trs};
use illume_transport::{GBuffer, World};

const SIZE: u32 = 96;
const IRRADIANCE: f32 = 3.0;
const ALBEDO: f32 = 0.8;
/// The sun's turn about +Y: a quarter turn less a quarter of a 16-slice facet (5.625°).
const SUN_TURN: f32 = std::f32::consts::FRAC_PI_2 - std::f32::consts::PI / 32.0;

/// The direction towards the sun.
fn to_sun() -> Vec3 {
    Quat::from_rotation_y(SUN_TURN) * Vec3::Z
}

/// A white sphere of radius 1 at the origin, `slices`×`stacks` facets, lit by a sun
/// from +X (half a facet round), seen from the side so the terminator crosses the image.
fn sunlit_sphere(slices: u32, stacks: u32) -> World {
    let mut b = SceneBuilder::new();
    let white = b.material(Material {
        base_color: Rgb::splat(ALBEDO),
        ..Default::default()
    });
    let sphere = b.mesh(uv_sphere(1.0, slices, stacks, white, false));
    b.placed("sphere", sphere, Trs::IDENTITY, false);
    // The light shines down its local −Z; turned a quarter about +Y it would shine
    // along −X and put the terminator on a column of vertices (no facet would straddle
    // it); a quarter facet less puts it across a column of facets turned away from the
    // sun whose lit corners still face it.
    let sun = b.node(
        "sun",
        None,
        Trs {
            rotation: Quat::from_rotation_y(SUN_TURN),
            ..Trs::IDENTITY
        },
    );
    b.light(
        "sun",
        LightKind::Directional {
            irradiance: Rgb::splat(IRRADIANCE),
        },
        sun,
    );
    b.camera_looking_down(3.0, 45f32.to_radians());
    let mut scene = b.finish("test:sunlit-sphere");
    look_from(&mut scene, Vec3::new(-2.0, 1.0, 3.2), Vec3::ZERO).unwrap();
    World::new(scene)
}

/// Mean and largest |direct − E·ρ/π·cosθ| over the pixels of a 16×8 sphere whose
/// shading normal faces the sun at a cosine θ in (0, 0.35), in units of E·ρ/π (the
/// sphere is convex and alone: nothing may shadow a point its normal turns to the
/// sun); and how many such pixels lie on facets turned away from the sun.
fn terminator_error(shadows: impl Fn(&World) -> Option<ShadowMaps>) -> (f32, f32, usize) {
    let world = sunlit_sphere(16, 8);
    let g = GBuffer::rasterize(&world, SIZE, SIZE);
    let maps = shadows(&world);
    let mode = maps.as_ref().map_or(Shadows::Rays, Shadows::Maps);
    let direct = direct_light_with(&world, &g, mode, 1, 0);
    let peak = IRRADIANCE * ALBEDO / std::f32::consts::PI;
    let wi = to_sun();
    let (mut sum, mut max, mut count, mut turned) = (0f32, 0f32, 0usize, 0usize);
    for (px, radiance) in g.pixels.iter().zip(direct.pixels()) {
        let Some(px) = px else { continue };
        let cos = px.hit.facing_normal().dot(wi);
        if !(cos > 0.0 && cos < 0.35) {
            continue;
        }
        turned += usize::from(px.hit.facing_geometric_normal().dot(wi) <= 0.0);
        let d = (radiance.y - peak * cos).abs() / peak;
        sum += d;
        max = max.max(d);
        count += 1;
    }
    (sum / count.max(1) as f32, max, turned)
}

fn check(mean: f32, max: f32, turned: usize) {
    // The sun is a quarter facet (5.6°) past a column of vertices, so a turned-away
    // facet that went black lost up to sin 5.6° ≈ 0.098 of the peak: before the fix,
    // mean 0.014 and largest 0.095 here; after it, 0 and 0 (rays and maps alike).
    assert!(
        turned > 100,
        "only {turned} pixels on facets turned away from the sun"
    );
    assert!(
        mean < 1e-3 && max < 0.01,
        "direct light against E·ρ/π·cosθ along the terminator: mean {mean}, largest {max} \
         (of E·ρ/π), {turned} pixels on facets turned away"
    );
}

#[test]
fn a_faceted_spheres_terminator_has_no_steps_with_shadow_rays() {
    let (mean, max, turned) = terminator_error(|_| None);
    check(mean, max, turned);
}

#[test]
fn a_faceted_spheres_terminator_has_no_steps_with_shadow_maps() {
    let (mean, max, turned) = terminator_error(|world| {
        Some(ShadowMaps::build(world, &ShadowMapSettings::default()).unwrap())
    });
    check(mean, max, turned);
}
