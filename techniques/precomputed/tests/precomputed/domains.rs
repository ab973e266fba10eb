//! The `cube` and `atlas` domains on `builtin:sun-room`: images from cameras the
//! precompute never used, against the reference path tracer.
//!
//! Tolerances: keys and references are path traced with few samples (the test profile
//! is slow), so pixels are compared in 8×8 blocks (noise averaged) and as image means.
//! The atlas adds its own error: texels of 1/6 m filter the light bilinearly, and texels
//! along contact edges take their neighbours' values; the block tolerance is wider for it.

use crate::common::{SIZE, blocks, reference_with_sky_direct, sky_direct, world};
use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_precomputed::Precomputed;
use illume_precomputed::precompute::precompute;
use illume_precomputed::settings::{Denoise, Domain, PrecomputedSettings, ScheduleKind};
use illume_scene::Scene;
use illume_transport::{GBuffer, Technique, World};

const HOURS: f64 = 11.5;

fn settings(domain: Domain) -> PrecomputedSettings {
    PrecomputedSettings {
        domain,
        schedule: ScheduleKind::Uniform,
        // 10:00, 11:00 and 12:00 (`to_h` is inclusive).
        from_h: 10.0,
        to_h: 12.0,
        step_min: 60.0,
        spp: 48,
        components: 10,
        atlas_density: 6.0,
        probe_spacing: 1.0,
        exposure: 64.0,
        ..Default::default()
    }
}

/// `scene` with its camera turned by `yaw` degrees and moved by `shift`, at `HOURS`.
fn posed(scene: &Scene, yaw_deg: f32, shift: illume_core::Vec3, mask_dynamic: bool) -> Scene {
    let mut scene = scene.clone();
    let node = scene.camera.node.index();
    let local = &mut scene.nodes[node].local;
    local.rotation = illume_core::Quat::from_rotation_y(yaw_deg.to_radians()) * local.rotation;
    local.translation += shift;
    if mask_dynamic {
        for i in scene.instances.iter_mut().filter(|i| i.dynamic) {
            i.mask = 0;
        }
    }
    let sun = scene.sun.as_ref().unwrap().settings.clone();
    scene.set_time(sun.scene_time(HOURS));
    scene
}

/// What the technique's indirect image should be: the reference's light reflected ≥ 2
/// times (sun and sky) plus the sky's direct light (the technique supplies it).
fn reference(world: &World, scene: Scene) -> RgbImage {
    reference_with_sky_direct(world, scene, 192, (7, 8))
}

/// The technique's indirect image of `scene`, and `expected` with the pixels that see
/// nothing (the sky through the window: its radiance is not reflected light) set to 0.
fn technique_image(
    technique: &mut Precomputed,
    world: &World,
    scene: Scene,
    expected: &RgbImage,
) -> (RgbImage, RgbImage) {
    let w = world.with_scene(scene);
    let g = GBuffer::render(&w, SIZE.0, SIZE.1, illume_core::Vec2::splat(0.5));
    let seen = expected
        .pixels()
        .iter()
        .zip(&g.pixels)
        .map(|(e, p)| if p.is_some() { *e } else { Rgb::ZERO })
        .collect();
    // As the renderer does for a split frame: the direct share is asked for.
    technique.want_direct_share(true);
    (
        technique.indirect(&w, &g),
        RgbImage::from_vec(SIZE.0, SIZE.1, seen).unwrap(),
    )
}

/// The direct share of the technique's last image (`--split`'s sky light in `_direct`)
/// against the reference's direct light of the sky alone in `scene`, on the pixels that
/// see something: their means within `tolerance` (relative). Measured (2026-11-28): atlas
/// −1.0 %, cube −1.9 %; both checked at 8 %, the atlas image's mean tolerance above.
fn check_share(
    technique: &mut Precomputed,
    world: &World,
    scene: Scene,
    domain: &str,
    tolerance: f32,
) {
    let ws = world.with_scene(scene.clone());
    let g = GBuffer::render(&ws, SIZE.0, SIZE.1, illume_core::Vec2::splat(0.5));
    let share = technique
        .direct_share()
        .expect("a new file hands over the sky's direct light");
    let expected = sky_direct(world, scene, 192, 9);
    let seen = |img: &RgbImage| -> Vec<Rgb> {
        img.pixels()
            .iter()
            .zip(&g.pixels)
            .filter(|(_, p)| p.is_some())
            .map(|(v, _)| *v)
            .collect()
    };
    let (m_ours, m_ref) = (mean(&seen(&share)), mean(&seen(&expected)));
    eprintln!("{domain}: sky's direct share {m_ours:.5} vs reference {m_ref:.5}");
    assert!(m_ref > 1e-4, "the sky lights the room ({m_ref})");
    assert!(
        (m_ours - m_ref).abs() < tolerance * m_ref,
        "{domain}: direct share {m_ours} vs reference {m_ref} (±{tolerance})"
    );
    assert!(technique.direct_share().is_none(), "taken, not kept");
    // Frames shown whole do not ask for it, and the technique skips its work.
    technique.want_direct_share(false);
    let _ = technique.indirect(&ws, &g);
    assert!(
        technique.direct_share().is_none(),
        "not asked for, not made"
    );
}

fn mean(v: &[Rgb]) -> f32 {
    v.iter().map(|p| (p.x + p.y + p.z) / 3.0).sum::<f32>() / v.len() as f32
}

/// RMS of the 8×8 block means' differences, relative to the reference's mean.
fn block_rms(a: &RgbImage, b: &RgbImage) -> f32 {
    let (ba, bb) = (blocks(a.pixels()), blocks(b.pixels()));
    let rms = (ba
        .iter()
        .zip(&bb)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f32>()
        / ba.len() as f32)
        .sqrt();
    rms / mean(b.pixels())
}

fn load(
    world: &World,
    s: &PrecomputedSettings,
    file: illume_precomputed::file::PcFile,
) -> Result<Precomputed, String> {
    Precomputed::from_file(
        world,
        s.clone(),
        std::path::Path::new("room.illumepc"),
        file,
        SIZE.0,
        SIZE.1,
        std::time::Instant::now(),
    )
    .map_err(|e| e.to_string())
}

#[test]
fn atlas_lights_a_camera_the_precompute_never_used() {
    let world = world();
    let s = settings(Domain::Atlas);
    let file = precompute(&world, &s, SIZE, &mut illume_core::progress::Silent).unwrap();
    assert_eq!(file.header.domain, "atlas");
    // Another position and direction, and another image size: both accepted.
    let elsewhere = posed(
        &world.scene,
        35.0,
        illume_core::Vec3::new(-0.8, -0.3, -0.4),
        true,
    );
    let mut technique = load(&world.with_scene(elsewhere.clone()), &s, file.clone()).unwrap();
    let elsewhere_scene = elsewhere.clone();
    let (ours, expected) = technique_image(
        &mut technique,
        &world,
        elsewhere.clone(),
        &reference(&world, elsewhere),
    );
    let (m_ours, m_ref) = (mean(ours.pixels()), mean(expected.pixels()));
    let rms = block_rms(&ours, &expected);
    eprintln!(
        "atlas, new camera: mean {m_ours:.5} vs reference {m_ref:.5}, 8×8-block RMS {:.1} %",
        100.0 * rms
    );
    assert!(m_ref > 1e-3, "the room must have indirect light ({m_ref})");
    assert!(
        (m_ours - m_ref).abs() < 0.08 * m_ref,
        "means {m_ours} vs {m_ref}"
    );
    assert!(rms < 0.2, "block RMS {rms}");
    check_share(&mut technique, &world, elsewhere_scene, "atlas", 0.08);
    assert!(
        load(&world, &s, file.clone()).is_ok(),
        "the original camera too"
    );

    // The dynamic box is lit by the probes: its pixels against the reference's with the
    // box shown (the reference's box also shadows and bleeds; the box is small).
    let shown = posed(&world.scene, 0.0, illume_core::Vec3::ZERO, false);
    let w = world.with_scene(shown.clone());
    let g = GBuffer::render(&w, SIZE.0, SIZE.1, illume_core::Vec2::splat(0.5));
    let ours = technique.indirect(&w, &g);
    let expected = reference(&world, shown);
    let on_box: Vec<usize> = (0..g.pixels.len())
        .filter(|&i| {
            g.pixels[i].is_some_and(|p| world.scene.instances[p.hit.instance.index()].dynamic)
        })
        .collect();
    assert!(
        on_box.len() >= 8,
        "the box must be in view ({} pixels)",
        on_box.len()
    );
    let pick = |img: &RgbImage| on_box.iter().map(|&i| img.pixels()[i]).collect::<Vec<_>>();
    let (b_ours, b_ref) = (mean(&pick(&ours)), mean(&pick(&expected)));
    eprintln!(
        "dynamic box ({} pixels): probes {b_ours:.5} vs reference {b_ref:.5}",
        on_box.len()
    );
    assert!(
        b_ref > 0.0 && (b_ours - b_ref).abs() < 0.3 * b_ref,
        "box {b_ours} vs {b_ref}"
    );
    // Settled (a viewer stops rendering): another frame of the same world is the same.
    assert!(technique.settled());
    let again = technique.indirect(&w, &g);
    assert!(
        again.pixels() == ours.pixels(),
        "settled, yet the next frame differs"
    );
}

#[test]
fn cube_lets_the_camera_turn_but_not_move() {
    let world = world();
    // Keys denoised (the default). On 24-pixel faces at 48 spp the filter once dropped
    // bright outliers' energy (faces −1 to −2.6 %, the turned view −6.6 % against the
    // reference; issue 36): each face of a denoised key must hold the light of the raw
    // key made of the same samples within the reference agreement's energy tolerance.
    let s = PrecomputedSettings {
        cube_face: 24,
        ..settings(Domain::Cube)
    };
    assert_eq!(s.denoise, Denoise::Atrous);
    let tolerance = illume_agreement::Agreement::registered::<illume_reference::Descriptor>()
        .max_energy_error as f32;
    let time = illume_precomputed::schedule::KeyTime {
        hours: 11.0,
        level: 0,
    };
    let key = |denoise| {
        let s = PrecomputedSettings {
            denoise,
            ..s.clone()
        };
        illume_precomputed::precompute::render_key(&world, &s, time, SIZE)
            .unwrap()
            .image
    };
    let (denoised, raw) = (key(Denoise::Atrous), key(Denoise::None));
    let texels = 24 * 24;
    for f in 0..6 {
        let face = |img: &RgbImage| mean(&img.pixels()[f * texels..(f + 1) * texels]);
        let (d, r) = (face(&denoised), face(&raw));
        eprintln!("cube face {f}: denoised {d:.5}, raw {r:.5}");
        assert!(
            (d - r).abs() <= tolerance * r.max(1e-4),
            "face {f}: denoised {d} vs raw {r} (±{tolerance})"
        );
    }
    let file = precompute(&world, &s, SIZE, &mut illume_core::progress::Silent).unwrap();
    assert_eq!((file.header.width, file.header.height), (24, 144));
    let turned = posed(&world.scene, 50.0, illume_core::Vec3::ZERO, true);
    let turned_scene = turned.clone();
    let mut technique = load(&world.with_scene(turned.clone()), &s, file.clone()).unwrap();
    let (ours, expected) = technique_image(
        &mut technique,
        &world,
        turned.clone(),
        &reference(&world, turned),
    );
    let (m_ours, m_ref) = (mean(ours.pixels()), mean(expected.pixels()));
    let rms = block_rms(&ours, &expected);
    eprintln!(
        "cube, turned camera: mean {m_ours:.5} vs reference {m_ref:.5}, 8×8-block RMS {:.1} %",
        100.0 * rms
    );
    assert!(m_ref > 1e-3);
    assert!(
        (m_ours - m_ref).abs() < 0.06 * m_ref,
        "means {m_ours} vs {m_ref}"
    );
    assert!(rms < 0.15, "block RMS {rms}");
    check_share(&mut technique, &world, turned_scene, "cube", 0.08);
    // At run time a turn keeps the file valid, a move makes it stale (counted).
    let stale = |t: &mut Precomputed, to: &Scene| {
        let change = illume_scene::SceneChange::CameraMoved {
            from: world.scene.camera.world_from_camera,
            to: to.camera.world_from_camera,
        };
        t.scene_changed(&world, &[change]);
        t.stats().get("stale").unwrap_or(-1.0)
    };
    let turned_again = posed(&world.scene, -20.0, illume_core::Vec3::ZERO, true);
    assert_eq!(stale(&mut technique, &turned_again), 0.0);
    let moved = posed(
        &world.scene,
        0.0,
        illume_core::Vec3::new(0.2, 0.0, 0.0),
        true,
    );
    assert_eq!(stale(&mut technique, &moved), 1.0);
    // A moved camera is refused, naming the file and the camera position.
    let moved = posed(
        &world.scene,
        0.0,
        illume_core::Vec3::new(0.2, 0.0, 0.0),
        true,
    );
    let e = load(&world.with_scene(moved), &s, file)
        .err()
        .expect("a moved camera is refused");
    assert!(
        e.contains("room.illumepc") && e.contains("camera position"),
        "{e}"
    );
}

#[test]
fn an_atlas_file_for_another_layout_is_refused() {
    let world = world();
    let s = PrecomputedSettings {
        spp: 1,
        from_h: 12.0,
        to_h: 12.5,
        ..settings(Domain::Atlas)
    };
    let mut file = precompute(&world, &s, SIZE, &mut illume_core::progress::Silent).unwrap();
    file.header.atlas.as_mut().unwrap().density = 7.0;
    let e = load(&world, &s, file)
        .err()
        .expect("another layout is refused");
    assert!(
        e.contains("room.illumepc") && e.contains("atlas layout"),
        "{e}"
    );
}
