//! Direct light per frame, shadow rays against shadow maps:
//! `cargo bench -p illume-render --bench direct`.
//!
//! Per scene at 800×600 on a G-buffer rasterized once: `rays` is [`direct_light`] (one
//! BVH shadow ray per pixel and analytic light), `maps moving light` is a whole frame's
//! worth of shadow maps when the light moves every frame (to a new pose each frame) — the edit, [`ShadowMaps::rebuild`]
//! into last frame's allocations, then [`direct_light_with`] — and `maps build` that
//! rebuild alone; `maps static light` is a frame whose light and objects did not move
//! (the maps are kept, only the lookups cost); `unshadowed` ([`Shadows::Off`]) is the same light with no visibility
//! test, the part of the cost both modes share. `auto static light` and `auto moving
//! light` are the same frames with `shadows = "auto"`'s per-light choice
//! ([`ShadowChooser::choose`], then [`direct_light_with`]): what an interactive technique
//! gets (before the choice it got `maps` every frame). Scenes: `cornell-spot` (its spot
//! light), the same with every material glossy (metallic 0.5, roughness 0.4), and Sponza
//! with a spot light under the roof aimed down (as in the photon-streaming bench), then
//! with a point light and a sun in its place, all at 800×600; and the Cornell dragon
//! (`cornell_dragon/cornell_dragon.obj`, 100 k triangles) at 320×240 with a point light
//! below its ceiling (a cube map). After the timings, a `calibration` table prints what
//! the cost model's constants are fitted to (lit pixels, triangles, texels).
//!
//! `cargo bench -p illume-render --bench direct -- paired` instead measures the
//! before/after pairs (maps against auto, still and moving light) back to back, frame
//! by frame (see [`paired`]).

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{Criterion, criterion_group};
use illume_core::{Affine3A, Quat, Rgb, Vec3};
use illume_render::{ShadowChooser, Shadows, direct_light, direct_light_with};
use illume_render::{ShadowMapSettings, ShadowMaps};
use illume_scene::{Edit, Light, LightId, LightKind, Node, Scene, Trs};
use illume_transport::{GBuffer, World};
use std::time::Duration;

const SIZE: (u32, u32) = (800, 600);

/// The moving-point-light dragon's image size (issue 15).
const DRAGON_SIZE: (u32, u32) = (320, 240);

/// `scene` with its lights replaced by one `kind` light near the top of its bounds,
/// pointing down, and no emissive surfaces (direct light is the analytic light alone).
fn with_light(mut scene: Scene, kind: LightKind) -> Scene {
    for m in &mut scene.materials {
        m.emission = Rgb::ZERO;
    }
    scene.lights.clear();
    let b = scene.bounds();
    let (c, e) = (b.center(), b.extent());
    let node = illume_scene::NodeId(scene.nodes.len() as u32);
    scene.nodes.push(Node {
        name: "bench_light".into(),
        parent: None,
        local: Trs {
            translation: Vec3::new(c.x, b.max.y - 0.05 * e.y, c.z),
            // Down, and 20° off vertical so the sun's shadows are not all hidden.
            rotation: Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2 + 0.35),
            scale: Vec3::ONE,
        },
        world_from_node: Affine3A::IDENTITY,
    });
    scene.lights.push(Light {
        name: "bench_light".into(),
        kind,
        node,
        world_from_light: Affine3A::IDENTITY,
    });
    scene.update_world_transforms();
    scene
}

fn scenes() -> Vec<(String, World, (u32, u32))> {
    let cornell = illume_scene::builtin::load("cornell-spot").expect("builtin");
    // The same box with every material glossy (metallic 0.5, roughness 0.4): the BRDF
    // is evaluated per light instead of once per pixel.
    let mut glossy = cornell.clone();
    for m in &mut glossy.materials {
        m.metallic = 0.5;
        m.roughness = 0.4;
    }
    let mut scenes = vec![
        ("cornell-spot".to_string(), World::new(cornell), SIZE),
        ("cornell-spot glossy".to_string(), World::new(glossy), SIZE),
    ];
    let path = &illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    match illume_scene::load_scene(path) {
        Ok(mut sponza) => {
            let (eye, target) = illume_scene::builtin::SPONZA_ATRIUM_VIEW;
            illume_scene::builtin::look_from(&mut sponza, eye, target).expect("a valid view");
            let e = sponza.bounds().extent();
            let intensity = Rgb::splat(10.0 * (e.y / 2.0).powi(2));
            for (name, kind) in [
                (
                    "spot",
                    LightKind::Spot {
                        intensity,
                        inner_cone_rad: 30f32.to_radians(),
                        outer_cone_rad: 45f32.to_radians(),
                    },
                ),
                ("point", LightKind::Point { intensity }),
                (
                    "sun",
                    LightKind::Directional {
                        irradiance: Rgb::splat(3.0),
                    },
                ),
            ] {
                scenes.push((
                    format!("sponza {name}"),
                    World::new(with_light(sponza.clone(), kind)),
                    SIZE,
                ));
            }
        }
        Err(e) => println!("sponza skipped: {e}"),
    }
    let path = &illume_scene::shared_scenes_dir().join("cornell_dragon/cornell_dragon.obj");
    match illume_scene::load_scene(path) {
        Ok(dragon) => {
            let e = dragon.bounds().extent();
            let intensity = Rgb::splat(10.0 * (e.y / 2.0).powi(2));
            scenes.push((
                "dragon point".to_string(),
                World::new(with_light(dragon, LightKind::Point { intensity })),
                DRAGON_SIZE,
            ));
        }
        Err(e) => println!("dragon skipped: {e}"),
    }
    scenes
}

fn direct(c: &mut Criterion) {
    let mut g = c.benchmark_group("direct");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(500));
    g.measurement_time(Duration::from_secs(3));
    let settings = ShadowMapSettings::default();
    let mut calibration = Vec::new();
    for (name, world, (w, h)) in scenes() {
        let gbuffer = GBuffer::rasterize(&world, w, h);
        g.bench_function(format!("{name} {w}x{h} unshadowed"), |b| {
            b.iter(|| direct_light_with(&world, &gbuffer, Shadows::Off, 1, 0))
        });
        g.bench_function(format!("{name} {w}x{h} rays"), |b| {
            b.iter(|| direct_light(&world, &gbuffer, 1, 0))
        });
        let mut maps = ShadowMaps::build(&world, &settings).expect("valid settings");
        g.bench_function(format!("{name} {w}x{h} maps static light"), |b| {
            b.iter(|| {
                maps.rebuild(&world, &settings).expect("valid settings");
                direct_light_with(&world, &gbuffer, Shadows::Maps(&maps), 1, 0)
            })
        });
        let (mut auto_maps, mut chooser) = (ShadowMaps::default(), ShadowChooser::default());
        g.bench_function(format!("{name} {w}x{h} auto static light"), |b| {
            b.iter(|| {
                chooser
                    .choose(&world, &gbuffer, &mut auto_maps, &settings)
                    .expect("valid settings");
                direct_light_with(&world, &gbuffer, Shadows::Maps(&auto_maps), 1, 0)
            })
        });
        println!("{name}: auto static light chose {:?}", chooser.choices());
        // The light turns by up to ±0.01° and moves by up to ±0.2 mm every frame, to a
        // new pose each time: every map (spot, cube, sun) is re-rendered; the G-buffer
        // (camera and objects unchanged) stays valid.
        let mut world = world;
        let home = world.scene.lights[0].world_from_light;
        let mut frame = 0u32;
        let mut nudge = move |world: &mut World| {
            frame += 1;
            // Never the same pose twice (a revisited pose would find its map current).
            let angle = 1.7e-4 * (frame as f32 * 0.7).sin();
            world
                .apply_edit(&Edit::SetLightTransform {
                    light: LightId(0),
                    world_from_light: home
                        * Affine3A::from_rotation_translation(
                            Quat::from_rotation_x(angle),
                            Vec3::splat(angle),
                        ),
                })
                .expect("edit");
        };
        g.bench_function(format!("{name} {w}x{h} maps moving light"), |b| {
            b.iter(|| {
                nudge(&mut world);
                maps.rebuild(&world, &settings).expect("valid settings");
                assert_eq!(maps.rendered_last_build(), maps.map_count());
                direct_light_with(&world, &gbuffer, Shadows::Maps(&maps), 1, 0)
            })
        });
        let (mut auto_maps, mut chooser) = (ShadowMaps::default(), ShadowChooser::default());
        g.bench_function(format!("{name} {w}x{h} auto moving light"), |b| {
            b.iter(|| {
                nudge(&mut world);
                chooser
                    .choose(&world, &gbuffer, &mut auto_maps, &settings)
                    .expect("valid settings");
                direct_light_with(&world, &gbuffer, Shadows::Maps(&auto_maps), 1, 0)
            })
        });
        println!(
            "{name}: auto moving light chose {:?}, raster scale {:.2}",
            chooser.choices(),
            chooser.raster_scale()
        );
        g.bench_function(format!("{name} {w}x{h} maps build"), |b| {
            b.iter(|| {
                nudge(&mut world);
                maps.rebuild(&world, &settings).expect("valid settings")
            })
        });
        let plan = maps.planned()[0];
        calibration.push(format!(
            "| {name} | {w}×{h} | {} | {} | {} | {} |",
            lit_pixels(&world, &gbuffer),
            world.scene.instanced_triangle_count(),
            plan.faces,
            plan.texels
        ));
    }
    g.finish();
    println!("\n### calibration\n\n| scene | size | lit pixels | triangles | maps | texels |");
    println!("|---|---|---:|---:|---:|---:|");
    for row in calibration {
        println!("{row}");
    }
}

/// Pixels of `gbuffer` that light 0 reaches (in range and cone, facing it): the pixels
/// that pay a shadow ray or a lookup.
fn lit_pixels(world: &World, gbuffer: &GBuffer) -> usize {
    gbuffer
        .pixels
        .iter()
        .flatten()
        .filter(|px| {
            let hit = &px.hit;
            world
                .lights
                .incident_from(0, hit.position, illume_core::Vec2::ZERO)
                .is_some_and(|(s, _)| {
                    hit.facing_normal().dot(s.wi) > 0.0
                        && hit.facing_geometric_normal().dot(s.wi) > 0.0
                })
        })
        .count()
}

/// `-- paired`: the before/after rows measured back to back. Per scene, 41 rounds of
/// one frame each of `maps static light` then `auto static light`, and of `maps moving
/// light` then `auto moving light` (each pair in alternating order, after 5 warm-up
/// rounds), so that the load of other processes, which drifts over seconds on a shared
/// machine, weighs on both alike. Prints medians and the median of the per-round ratios.
fn paired() {
    let settings = ShadowMapSettings::default();
    println!("\n### paired: maps (before) against auto (after), one frame each, back to back\n");
    println!("| scene | light | maps [ms] | auto [ms] | median auto ÷ maps | auto's choice |");
    println!("|---|---|---:|---:|---:|---|");
    for (name, mut world, (w, h)) in scenes() {
        if name.contains("glossy") {
            continue;
        }
        let gbuffer = GBuffer::rasterize(&world, w, h);
        let home = world.scene.lights[0].world_from_light;
        for moving in [false, true] {
            let mut maps = ShadowMaps::build(&world, &settings).expect("valid settings");
            let (mut auto_maps, mut chooser) = (ShadowMaps::default(), ShadowChooser::default());
            let (mut before, mut after, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
            for round in 0..46u32 {
                if moving {
                    let angle = 1.7e-4 * (round as f32 * 0.7).sin();
                    world
                        .apply_edit(&Edit::SetLightTransform {
                            light: LightId(0),
                            world_from_light: home
                                * Affine3A::from_rotation_translation(
                                    Quat::from_rotation_x(angle),
                                    Vec3::splat(angle),
                                ),
                        })
                        .expect("edit");
                }
                let time_maps = |maps: &mut ShadowMaps| {
                    let t = std::time::Instant::now();
                    maps.rebuild(&world, &settings).expect("valid settings");
                    std::hint::black_box(direct_light_with(
                        &world,
                        &gbuffer,
                        Shadows::Maps(maps),
                        1,
                        0,
                    ));
                    t.elapsed().as_secs_f64() * 1e3
                };
                let time_auto = |maps: &mut ShadowMaps, chooser: &mut ShadowChooser| {
                    let t = std::time::Instant::now();
                    chooser
                        .choose(&world, &gbuffer, maps, &settings)
                        .expect("valid settings");
                    std::hint::black_box(direct_light_with(
                        &world,
                        &gbuffer,
                        Shadows::Maps(maps),
                        1,
                        0,
                    ));
                    t.elapsed().as_secs_f64() * 1e3
                };
                let (m, a) = if round % 2 == 0 {
                    let m = time_maps(&mut maps);
                    (m, time_auto(&mut auto_maps, &mut chooser))
                } else {
                    let a = time_auto(&mut auto_maps, &mut chooser);
                    (time_maps(&mut maps), a)
                };
                if round >= 5 {
                    before.push(m);
                    after.push(a);
                    ratios.push(a / m);
                }
            }
            let c = chooser.choices()[0];
            println!(
                "| {name} {w}×{h} | {} | {:.2} | {:.2} | {:.2} | {} |",
                if moving { "moving" } else { "still" },
                median(&mut before),
                median(&mut after),
                median(&mut ratios),
                if c.maps { "maps" } else { "rays" }
            );
            world
                .apply_edit(&Edit::SetLightTransform {
                    light: LightId(0),
                    world_from_light: home,
                })
                .expect("edit");
        }
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

criterion_group!(benches, direct);

fn main() {
    if std::env::args().any(|a| a == "paired") {
        paired();
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
