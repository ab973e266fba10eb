//! `precomputed` on `builtin:sun-room`: keys from the reference path tracer, PCA, and the
//! run-time reconstruction at a time between keys against the reference's indirect light.

use crate::common::{SIZE, blocks, reference_with_sky_direct, world};
use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_precomputed::Precomputed;
use illume_precomputed::precompute::{differs_visibly, precompute, render_key};
use illume_precomputed::schedule::KeyTime;
use illume_precomputed::settings::{PrecomputedSettings, ScheduleKind};
use illume_transport::World;

fn settings() -> PrecomputedSettings {
    PrecomputedSettings {
        schedule: ScheduleKind::Uniform,
        // 10:00–13:30 every 30 min (`to_h` is inclusive): 8 keys.
        from_h: 10.0,
        to_h: 13.5,
        step_min: 30.0,
        spp: 96,
        components: 20,
        // The room's indirect light is ~0.003 W/(m²·sr): ×64 puts it at mid-grey, where
        // the Yee metric sees differences (at exposure 1 it would be nearly black).
        exposure: 64.0,
        ..Default::default()
    }
}

#[test]
fn indirect_between_keys_matches_the_reference() {
    let world = world();
    let s = settings();
    let file = precompute(&world, &s, SIZE, &mut illume_core::progress::Silent).unwrap();
    assert_eq!(file.header.keys.len(), 8);
    let dir = std::env::temp_dir().join(format!("illumepc-sunroom-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("day.illumepc");
    file.write(&path).unwrap();
    let mut technique = Precomputed::load(&world, s.clone(), &path, SIZE.0, SIZE.1).unwrap();

    // 11:45, between the keys of 11:30 and 12:00. The reference: the whole scene at that
    // time (sun and scaled sky), dynamic box masked like the precompute's.
    let sun = world.scene.sun.as_ref().unwrap().settings.clone();
    let hours = 11.75;
    let mut scene = world.scene.clone();
    for i in scene.instances.iter_mut().filter(|i| i.dynamic) {
        i.mask = 0;
    }
    scene.set_time(sun.scene_time(hours));
    let elevation = illume_scene::sun::solar_position(&sun, hours)
        .unwrap()
        .elevation_deg;
    // Ours holds the sky's direct light too (the renderer skips it): the reference adds
    // the direct light of the sky alone at that time.
    let reference_world = world.with_scene(scene.clone());
    let reference = reference_with_sky_direct(&world, scene, 256, (99, 98));
    let ours = technique.reconstruct(hours, illume_scene::sun::sky_scale(elevation));
    // A frame blends the two key images around the time (Eq. 2): the same image as the
    // reconstruction from blended coefficients, up to rounding and the clamp at 0.
    {
        use illume_transport::Technique;
        let g = illume_transport::GBuffer::render(
            &reference_world,
            SIZE.0,
            SIZE.1,
            illume_core::Vec2::splat(0.5),
        );
        let frame = technique.indirect(&reference_world, &g);
        let mut close = 0;
        for (i, (a, b)) in frame.pixels().iter().zip(&ours).enumerate() {
            if g.pixels[i].is_none() {
                continue;
            }
            if (*a - *b).abs().max_element() <= 1e-4 * b.max_element().max(1e-3) {
                close += 1;
            }
        }
        let seen = g.pixels.iter().filter(|p| p.is_some()).count();
        assert!(close * 100 >= seen * 99, "{close} of {seen} pixels agree");
    }

    let mean = |v: &[Rgb]| v.iter().map(|p| (p.x + p.y + p.z) / 3.0).sum::<f32>() / v.len() as f32;
    let (m_ref, m_ours) = (mean(reference.pixels()), mean(&ours));
    eprintln!("mean indirect: reference {m_ref:.5}, precomputed {m_ours:.5}");
    assert!(
        m_ref > 1e-3,
        "the room must have indirect light at noon ({m_ref})"
    );
    assert!(
        (m_ours - m_ref).abs() < 0.05 * m_ref,
        "image means differ by more than 5 %: {m_ours} vs {m_ref}"
    );
    let (b_ref, b_ours) = (blocks(reference.pixels()), blocks(&ours));
    let rms = (b_ref
        .iter()
        .zip(&b_ours)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f32>()
        / b_ref.len() as f32)
        .sqrt();
    eprintln!(
        "8×8-block RMS difference {rms:.5} ({:.1} % of the mean)",
        100.0 * rms / m_ref
    );
    assert!(rms < 0.15 * m_ref, "block RMS {rms} vs mean {m_ref}");

    // The sky's share is scaled by s(t): half the scale, sky part halves.
    let no_sky = technique.reconstruct(hours, 0.0);
    let with_sky = technique.reconstruct(hours, 1.0);
    let half = technique.reconstruct(hours, 0.5);
    for i in (0..ours.len()).step_by(37) {
        let expect = (no_sky[i] + with_sky[i]) * 0.5;
        assert!((half[i] - expect).abs().max_element() < 1e-5);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// §4.3: with k = 20 (here all keys), restored keys show no perceptual difference.
#[test]
fn restored_keys_pass_yee_and_night_is_black() {
    let world = world();
    let s = settings();
    let file = precompute(&world, &s, SIZE, &mut illume_core::progress::Silent).unwrap();
    let technique = Precomputed::from_file(
        &world,
        s.clone(),
        std::path::Path::new("memory"),
        file.clone(),
        SIZE.0,
        SIZE.1,
        std::time::Instant::now(),
    )
    .unwrap();
    for key in file.header.keys.iter().step_by(3) {
        let original = render_key(
            &world,
            &s,
            KeyTime {
                hours: key.hours,
                level: 0,
            },
            SIZE,
        )
        .unwrap();
        let restored =
            RgbImage::from_vec(SIZE.0, SIZE.1, technique.reconstruct(key.hours, 0.0)).unwrap();
        assert!(
            !differs_visibly(&original.image, &restored, s.exposure),
            "key {}",
            key.hours
        );
    }
    // A night key is dark and exactly black.
    let night = render_key(
        &world,
        &s,
        KeyTime {
            hours: 1.0,
            level: 0,
        },
        SIZE,
    )
    .unwrap();
    assert!(night.dark);
    assert!(night.image.pixels().iter().all(|p| *p == Rgb::ZERO));
}

/// A screen file used with another camera or image size, or for a scene whose static
/// part changed: one error naming the file and what differs, never a wrong image.
#[test]
fn another_camera_size_or_scene_is_refused() {
    let world = world();
    let s = PrecomputedSettings {
        from_h: 12.0,
        to_h: 13.0,
        step_min: 60.0,
        spp: 4,
        ..settings()
    };
    let small = (8, 6);
    let file = precompute(&world, &s, small, &mut illume_core::progress::Silent).unwrap();
    let path = std::path::Path::new("room.illumepc");
    let load = |w: &World, size: (u32, u32)| {
        Precomputed::from_file(
            w,
            s.clone(),
            path,
            file.clone(),
            size.0,
            size.1,
            std::time::Instant::now(),
        )
        .err()
        .map(|e| e.to_string())
    };
    assert_eq!(load(&world, small), None);
    let e = load(&world, (16, 6)).expect("another size is refused");
    assert!(
        e.contains("room.illumepc") && e.contains("image size"),
        "{e}"
    );
    let mut scene = world.scene.clone();
    scene.camera.world_from_camera.translation.x += 0.1;
    let e = load(&world.with_scene(scene), small).expect("another camera is refused");
    assert!(e.contains("room.illumepc") && e.contains("camera"), "{e}");
    let mut scene = world.scene.clone();
    scene.materials[0].base_color *= 0.5;
    let e = load(&world.with_scene(scene), small).expect("another scene is refused");
    assert!(
        e.contains("room.illumepc") && e.contains("another scene"),
        "{e}"
    );
    let mut scene = world.scene.clone();
    scene.sun.as_mut().unwrap().settings.latitude_deg += 1.0;
    let e = load(&world.with_scene(scene), small).expect("another sun is refused");
    assert!(e.contains("room.illumepc") && e.contains("[sun]"), "{e}");
    // The dynamic box may move: the file still fits.
    let mut scene = world.scene.clone();
    let i = scene.instances.iter().position(|i| i.dynamic).unwrap();
    scene.instances[i].world_from_object.translation.x -= 0.3;
    assert_eq!(load(&world.with_scene(scene), small), None);
}

/// Linear and cubic interpolation both return the keys at key times, and blend between.
#[test]
fn interpolation_returns_keys_at_key_times() {
    use illume_precomputed::settings::Interpolation;
    let world = world();
    let s = PrecomputedSettings {
        from_h: 10.0,
        to_h: 14.0,
        step_min: 60.0,
        spp: 4,
        components: 4,
        ..settings()
    };
    let size = (8, 6);
    let file = precompute(&world, &s, size, &mut illume_core::progress::Silent).unwrap();
    let build = |interpolation| {
        Precomputed::from_file(
            &world,
            PrecomputedSettings {
                interpolation,
                ..s.clone()
            },
            std::path::Path::new("memory"),
            file.clone(),
            size.0,
            size.1,
            std::time::Instant::now(),
        )
        .unwrap()
    };
    let (linear, cubic) = (build(Interpolation::Linear), build(Interpolation::Cubic));
    for hours in [10.0, 11.0, 12.0, 13.0] {
        let (a, b) = (
            linear.reconstruct(hours, 0.0),
            cubic.reconstruct(hours, 0.0),
        );
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (*x - *y).abs().max_element() <= 1e-6 * (1.0 + x.max_element()),
                "{hours} h"
            );
        }
    }
    // Between keys: linear is the average of its neighbours' values.
    let (k11, k12, mid) = (
        linear.reconstruct(11.0, 0.0),
        linear.reconstruct(12.0, 0.0),
        linear.reconstruct(11.5, 0.0),
    );
    for i in 0..mid.len() {
        let expect = (k11[i] + k12[i]) * 0.5;
        // Clamping at 0 happens per key restored value; where both are ≥ 0 the blend is exact.
        if k11[i].min_element() > 0.0 && k12[i].min_element() > 0.0 {
            assert!((mid[i] - expect).abs().max_element() < 1e-5 * (1.0 + expect.max_element()));
        }
    }
}

/// `colour = "joint"` (one PCA over the three channels) through a file: with as many
/// components as keys both fits are exact, so joint and per-channel restore the same
/// frames (a wrong channel layout, basis or header in the joint path breaks this).
#[test]
fn joint_colour_restores_the_keys_through_a_file() {
    use illume_precomputed::settings::Colour;
    let world = world();
    let size = (8, 6);
    let dir = std::env::temp_dir().join(format!("illumepc-joint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fit = |colour, components| {
        let s = PrecomputedSettings {
            from_h: 10.0,
            to_h: 14.0,
            step_min: 60.0,
            spp: 4,
            components,
            colour,
            ..settings()
        };
        let file = precompute(&world, &s, size, &mut illume_core::progress::Silent).unwrap();
        let path = dir.join(format!("{colour:?}-{components}.illumepc"));
        file.write(&path).unwrap();
        Precomputed::load(&world, s, &path, size.0, size.1).unwrap()
    };
    let keys = 5; // 10:00 … 14:00 hourly
    let (joint, per_channel) = (fit(Colour::Joint, keys), fit(Colour::PerChannel, keys));
    for hours in [10.0, 11.0, 12.0, 13.0, 14.0] {
        let (a, b) = (
            joint.reconstruct(hours, 0.0),
            per_channel.reconstruct(hours, 0.0),
        );
        assert!(
            a.iter().any(|p| p.max_element() > 0.0),
            "{hours} h is black"
        );
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (*x - *y).abs().max_element() <= 1e-4 * (1.0 + y.max_element()),
                "{hours} h: joint {x} vs per-channel {y}"
            );
        }
    }
}
