//! Shadow maps against exact shadow rays, as [`ShadowMapSettings::ray_below_cos`] varies:
//! `cargo run --release -p illume-render --example shadow_map_error [NAME…]` (only the
//! scenes whose names contain one of the NAMEs, e.g. `9:37` or `sibenik`).
//!
//! Per scene, on one 800×600 G-buffer: direct light with a shadow ray per pixel (the
//! truth the maps stand in for), then with maps: first as before that setting existed
//! (maps everywhere, a one-footprint normal offset), then at `ray_below_cos` 0 (maps
//! everywhere), 0.1, 0.2 (the default) and 0.3 without a normal offset (the default).
//! Printed per row: HDR-FLIP and per-channel mean differences against the rays' image,
//! the share of the light's lit pixels that took a ray because the light grazes them and
//! the map did not find them fully shadowed, and the direct pass's time (the fastest of 3, the maps already rendered: lookups and
//! the grazing rays). Scenes: `cornell-spot`; Dabrovic Sponza under the `[sun]` defaults
//! (Koldinghus, 21 June) at the five clock times of `scenarios/day_sponza.toml`, seen
//! from its camera; Sponza and Sibenik under the photon-streaming benches' spot from
//! above (Sibenik's under the vault, as `scenarios/selective_sibenik.toml`); the Cornell
//! dragon under a point light (a cube map). Scenes missing from `ILLUME_SCENES` are
//! reported and left out.

use illume_core::Vec2;
use illume_core::image::RgbImage;
use illume_metrics::{FlipSettings, hdr_flip};
use illume_render::{ShadowMapSettings, ShadowMaps, Shadows, direct_light, direct_light_with};
use illume_scene::{Scene, builtin, sun::SunSettings};
use illume_transport::{GBuffer, World};
use std::time::Instant;

const SIZE: (u32, u32) = (800, 600);

/// The rows per scene: a label, `ray_below_cos` and `normal_offset_texels` (the other
/// settings at their defaults). The first row is the settings before grazing light took
/// rays (a one-footprint normal offset, maps everywhere).
const VARIANTS: [(&str, f32, f32); 5] = [
    ("0, offset 1", 0.0, 1.0),
    ("0", 0.0, 0.0),
    ("0.1", 0.1, 0.0),
    ("0.2", 0.2, 0.0),
    ("0.3", 0.3, 0.0),
];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let only = |name: &str| args.is_empty() || args.iter().any(|a| name.contains(a.as_str()));
    println!(
        "{:<18} {:>13} {:>9} {:>24} {:>8} {:>9}",
        "scene", "ray_below_cos", "hdr-flip", "mean diff (R G B) %", "rays %", "direct ms"
    );
    for (name, scene) in scenes() {
        if !only(&name) {
            continue;
        }
        let world = World::new(scene);
        let g = GBuffer::rasterize(&world, SIZE.0, SIZE.1);
        let rays = direct_light(&world, &g, 1, 0);
        for (label, ray_below_cos, normal_offset_texels) in VARIANTS {
            let settings = ShadowMapSettings {
                ray_below_cos,
                normal_offset_texels,
                ..Default::default()
            };
            let maps = ShadowMaps::build(&world, &settings).expect("valid settings");
            let mut best = f64::INFINITY;
            let mut image: Option<RgbImage> = None;
            for _ in 0..3 {
                let start = Instant::now();
                image = Some(direct_light_with(&world, &g, Shadows::Maps(&maps), 1, 0));
                best = best.min(start.elapsed().as_secs_f64() * 1e3);
            }
            let image = image.expect("three runs");
            let flip = hdr_flip(&rays, &image, &FlipSettings::default())
                .map(|f| f.map.mean())
                .unwrap_or(f64::NAN);
            let (mr, mm) = (rays.mean(), image.mean());
            let diff = |c: usize| 100.0 * (mm[c] - mr[c]) / mr[c].max(1e-12);
            println!(
                "{name:<18} {label:>13} {flip:>9.4} {:>+8.2}{:>+8.2}{:>+8.2} {:>8.1} {best:>9.1}",
                diff(0),
                diff(1),
                diff(2),
                100.0 * grazing_share(&world, &g, &maps),
            );
        }
    }
}

/// Share of the pixels analytic light 0 lights (facing it, in range) whose lookup the
/// maps decline (grazing light): those take a ray.
fn grazing_share(world: &World, g: &GBuffer, maps: &ShadowMaps) -> f64 {
    let (mut lit, mut rays) = (0u64, 0u64);
    for px in g.pixels.iter().flatten() {
        let hit = &px.hit;
        let Some((s, _)) = world.lights.incident_from(0, hit.position, Vec2::ZERO) else {
            continue;
        };
        if hit.facing_normal().dot(s.wi) <= 0.0 || hit.facing_geometric_normal().dot(s.wi) <= 0.0 {
            continue;
        }
        lit += 1;
        rays += u64::from(maps.visibility(0, hit, &s).is_none());
    }
    rays as f64 / lit.max(1) as f64
}

/// The scenes, by name; those whose files are missing are reported and skipped.
fn scenes() -> Vec<(String, Scene)> {
    let mut out = vec![(
        "cornell-spot".to_string(),
        builtin::load("cornell-spot").expect("builtin"),
    )];
    let dir = illume_scene::shared_scenes_dir();
    let load = |path: &str| match illume_scene::load_scene(&dir.join(path)) {
        Ok(s) => Some(s),
        Err(e) => {
            println!("{path} skipped: {e}");
            None
        }
    };
    if let Some(sponza) = load("dabrovic_sponza/sponza.obj") {
        // scenarios/day_sponza.toml's camera and clock times.
        for (label, t) in [
            ("7:22", 26_520.0),
            ("9:37", 34_620.0),
            ("12:14", 44_040.0),
            ("15:52", 57_120.0),
            ("18:25", 66_300.0),
        ] {
            let mut s = sponza.clone();
            builtin::look_from(&mut s, [-14.0, 2.0, 0.0].into(), [0.0, 5.0, 0.0].into())
                .expect("a valid view");
            s.attach_sun(SunSettings::default()).expect("default sun");
            s.set_time(t);
            out.push((format!("sponza sun {label}"), s));
        }
        let mut s = builtin::spot_from_above(sponza);
        let (eye, target) = builtin::SPONZA_ATRIUM_VIEW;
        builtin::look_from(&mut s, eye, target).expect("a valid view");
        out.push(("sponza spot".to_string(), s));
    }
    if let Some(sibenik) = load("sibenik/sibenik.obj") {
        let mut s = builtin::spot_from_above(sibenik);
        builtin::move_spot_from_above(&mut s, [0.0, 2.5, 0.0].into());
        builtin::look_from(&mut s, [-17.0, -11.0, 0.0].into(), [10.0, -9.0, 0.0].into())
            .expect("a valid view");
        out.push(("sibenik spot".to_string(), s));
    }
    if let Some(dragon) = load("cornell_dragon/cornell_dragon.obj") {
        let mut s = builtin::spot_from_above(dragon);
        if let illume_scene::LightKind::Spot { intensity, .. } = s.lights[0].kind {
            s.lights[0].kind = illume_scene::LightKind::Point { intensity };
        }
        out.push(("dragon point".to_string(), s));
    }
    out
}
