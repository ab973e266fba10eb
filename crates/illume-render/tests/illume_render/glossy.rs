//! A point light over a glossy plane: every pixel's direct light, from the renderer
//! (shadow rays and shadow maps) and from the reference's path kernel, equals the glTF
//! metallic-roughness BRDF written out here independently, in f64, times the irradiance
//! I·cosθ/d².

use illume_core::sampling::Pcg32;
use illume_core::{Quat, Rgb, Vec3};
use illume_render::{ShadowMapSettings, ShadowMaps};
use illume_render::{Shadows, direct_light_with};
use illume_scene::{LightKind, Trs};
use illume_transport::path::{PathRadiance, PathSettings, continue_path};
use illume_transport::{GBuffer, World};

/// glTF 2.0 Appendix B, straight from the specification's formulas, in f64.
fn gltf_brdf(
    n: Vec3,
    wo: Vec3,
    wi: Vec3,
    base: [f64; 3],
    metallic: f64,
    roughness: f64,
) -> [f64; 3] {
    let d = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (n, v, l) = (d(n), d(wo), d(wi));
    let h = {
        let s = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
        let len = dot(s, s).sqrt();
        [s[0] / len, s[1] / len, s[2] / len]
    };
    let (nl, nv, nh, vh) = (dot(n, l), dot(n, v), dot(n, h), dot(v, h));
    let a = roughness * roughness;
    let a2 = a * a;
    let dd = a2 / (std::f64::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    let spec = vis * dd;
    let schlick = (1.0 - vh.abs()).powi(5);
    let f_diel = 0.04 + 0.96 * schlick;
    let mut out = [0.0; 3];
    for c in 0..3 {
        let diffuse = base[c] / std::f64::consts::PI;
        let dielectric = diffuse * (1.0 - f_diel) + spec * f_diel;
        let metal = spec * (base[c] + (1.0 - base[c]) * schlick);
        out[c] = dielectric * (1.0 - metallic) + metal * metallic;
    }
    out
}

#[test]
fn point_light_over_glossy_plane_matches_the_analytic_brdf() {
    let intensity = 4.0f32;
    let light_at = Vec3::new(0.6, 1.0, 0.3);
    for (metallic, roughness) in [(1.0f32, 0.3f32), (0.0, 0.5), (0.5, 0.7), (1.0, 0.8)] {
        let mut scene = illume_scene::builtin::lit_plane(
            LightKind::Point {
                intensity: Rgb::splat(intensity),
            },
            Trs::from_translation(light_at),
            0.8,
            false,
        );
        // Tilt the camera so that the view direction varies over the plane.
        let cam = scene.camera.node.index();
        scene.nodes[cam].local = Trs {
            rotation: Quat::from_rotation_x(-1.1),
            ..Trs::from_translation(Vec3::new(0.0, 2.0, 2.0))
        };
        scene.update_world_transforms();
        let base = [0.9, 0.6, 0.3];
        scene.materials[0].base_color = Rgb::new(0.9, 0.6, 0.3);
        scene.materials[0].metallic = metallic;
        scene.materials[0].roughness = roughness;
        let world = World::new(scene);
        let g = GBuffer::rasterize(&world, 48, 36);
        let rays = direct_light_with(&world, &g, Shadows::Rays, 1, 0);
        let maps = ShadowMaps::build(&world, &ShadowMapSettings::default()).unwrap();
        let mapped = direct_light_with(&world, &g, Shadows::Maps(&maps), 1, 0);
        let mut checked = 0;
        let mut off_lambert = 0f64;
        for (i, px) in g.pixels.iter().enumerate() {
            let Some(px) = px else { continue };
            let hit = &px.hit;
            let to_light = light_at - hit.position;
            let d2 = to_light.length_squared() as f64;
            let wi = to_light.normalize();
            let cos = hit.facing_normal().dot(wi) as f64;
            let f = gltf_brdf(
                hit.facing_normal(),
                px.to_camera,
                wi,
                base,
                metallic as f64,
                roughness as f64,
            );
            let expected = f.map(|f| f * intensity as f64 * cos / d2);
            let lambert = 0.9 / std::f64::consts::PI * intensity as f64 * cos / d2;
            off_lambert = off_lambert.max((expected[0] / lambert - 1.0).abs());
            let (x, y) = (i as u32 % g.width, i as u32 / g.width);
            let mut kernel = PathRadiance::default();
            continue_path(
                &world,
                *hit,
                px.to_camera,
                &mut Pcg32::new(1, i as u64),
                &PathSettings::default(),
                &mut kernel,
            );
            for (what, got) in [
                ("renderer, rays", *rays.get(x, y)),
                ("renderer, maps", *mapped.get(x, y)),
                ("path kernel", kernel.direct),
            ] {
                for c in 0..3 {
                    let (g, e) = (got[c] as f64, expected[c]);
                    assert!(
                        (g - e).abs() <= 1e-4 * e.abs() + 1e-6,
                        "metallic {metallic} roughness {roughness}, pixel ({x}, {y}), {what}, channel {c}: {g} vs {e}"
                    );
                }
            }
            assert_eq!(kernel.indirect, Rgb::ZERO, "one plane: no second bounce");
            checked += 1;
        }
        assert!(checked > 1000, "{checked} pixels");
        // Not Lambertian: somewhere the value differs from albedo/π · E by > 10 %.
        assert!(
            off_lambert > 0.1,
            "max deviation from Lambert {off_lambert}"
        );
    }
}
