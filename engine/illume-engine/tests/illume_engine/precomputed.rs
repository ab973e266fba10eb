//! `precomputed` through the engine on `builtin:sun-room`: a day precomputed in memory
//! (tiny), a frame between keys, the full frame against the reference path tracer.

use illume_engine::{Config, Engine, TechniqueKind};
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_transport::World;

const W: u32 = 40;
const H: u32 = 30;

#[test]
fn a_frame_between_keys_matches_the_reference() {
    let scene = illume_scene::builtin::load("sun-room").unwrap();
    let sun = scene.sun.as_ref().unwrap().settings.clone();
    let mut config = Config {
        technique: TechniqueKind::Precomputed,
        ..Default::default()
    };
    config.render.width = W;
    config.render.height = H;
    config.precomputed.schedule = illume_precomputed::settings::ScheduleKind::Uniform;
    config.precomputed.from_h = 11.0;
    // Inclusive: the keys of 11:00 and 12:00.
    config.precomputed.to_h = 12.0;
    config.precomputed.step_min = 60.0;
    config.precomputed.spp = 64;
    let mut engine = Engine::new(scene.clone(), &config).unwrap();
    let t = sun.scene_time(11.5);
    let out = engine.step(t).unwrap();
    assert_eq!(
        out.stats.get("precomputed.keys"),
        Some(2.0),
        "{:?}",
        out.stats
    );
    assert!(out.frame.full.pixels().iter().all(|p| p.is_finite()));

    // The reference: the scene at that time (dynamic box included: the technique's
    // indirect light ignores it, §2), 256 spp.
    let mut scene = scene;
    scene.set_time(t);
    let world = World::new(scene);
    let mut r = ReferenceRenderer::new(
        ReferenceSettings {
            spp: 256,
            ..Default::default()
        },
        W,
        H,
    );
    r.add_samples(&world, 256);
    let reference = r.images().full;
    let flip = illume_metrics::hdr_flip(&reference, &out.frame.full, &Default::default()).unwrap();
    let mean = |img: &illume_core::image::RgbImage| {
        img.pixels()
            .iter()
            .map(|p| p.element_sum() / 3.0)
            .sum::<f32>()
            / img.pixels().len() as f32
    };
    eprintln!(
        "sun-room 11:30, {W}×{H}: HDR-FLIP {:.4}, mean full {:.4} vs reference {:.4}",
        flip.map.mean(),
        mean(&out.frame.full),
        mean(&reference)
    );
    // Direct light is the renderer's (shadow maps, the sky's direct term sampled), the
    // reference's 256 spp noise on 40×30 pixels dominates: a bound that catches a missing
    // or doubled term (sky or indirect), not noise.
    assert!(
        (mean(&out.frame.full) / mean(&reference) - 1.0).abs() < 0.1,
        "energy differs by more than 10 %"
    );
    assert!(flip.map.mean() < 0.35, "HDR-FLIP {}", flip.map.mean());
}

/// A scene without a `[sun]` (as a scene file is) takes the sun of the `.illumepc` file
/// it is rendered with: the frame equals the one of the scene that carried the sun.
#[test]
fn a_scene_without_a_sun_takes_the_files() {
    let scene = illume_scene::builtin::load("sun-room").unwrap();
    let sun = scene.sun.as_ref().unwrap().settings.clone();
    let world = World::new(scene.clone());
    let s = illume_precomputed::PrecomputedSettings {
        schedule: illume_precomputed::settings::ScheduleKind::Uniform,
        from_h: 11.0,
        to_h: 13.0,
        step_min: 60.0,
        spp: 4,
        ..Default::default()
    };
    let file = illume_precomputed::precompute::precompute(
        &world,
        &s,
        (W, H),
        &mut illume_core::progress::Silent,
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("illume-engine-sun-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("day.illumepc");
    file.write(&path).unwrap();
    let mut config = Config {
        technique: TechniqueKind::Precomputed,
        ..Default::default()
    };
    config.render.width = W;
    config.render.height = H;
    config.precomputed = illume_precomputed::PrecomputedSettings {
        data: path.display().to_string(),
        ..s
    };
    // The scene without its sun path (its sky back to scale 1, as a file's would be).
    let mut bare = scene.clone();
    let path_of_sun = bare.sun.take().unwrap();
    bare.sky = path_of_sun.sky_base;
    let t = sun.scene_time(12.25);
    let with_sun = Engine::new(scene, &config).unwrap().step(t).unwrap();
    let mut engine = Engine::new(bare, &config).unwrap();
    let without = engine.step(t).unwrap();
    // The bare scene now has a sun, shining at noon.
    let world = illume_engine::read_world(engine.world());
    let light = &world
        .scene
        .sun
        .as_ref()
        .expect("the file's sun is attached")
        .light;
    match world.scene.lights[light.index()].kind {
        illume_scene::LightKind::Directional { irradiance } => {
            assert!(irradiance.max_element() > 0.0, "{irradiance:?}")
        }
        ref other => panic!("the sun is directional, not {other:?}"),
    }
    drop(world);
    assert_eq!(with_sun.frame.full.pixels(), without.frame.full.pixels());
    // No file: no sun, and the error says so.
    let mut bare = illume_scene::builtin::load("sun-room").unwrap();
    bare.sun = None;
    config.precomputed.data = dir.join("missing.illumepc").display().to_string();
    let e = Engine::new(bare, &config)
        .err()
        .expect("a missing file is an error")
        .to_string();
    assert!(e.contains("missing.illumepc"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
