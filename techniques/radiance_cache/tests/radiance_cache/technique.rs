//! The technique on G-buffers: the furnace's closed form, `reuse` against `per_frame`
//! on a static scene, placement independent of the thread count, refused settings.

use crate::common::{H, W, cornell, on_threads};
use illume_core::{Rgb, Vec2};
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_scene::Timeline;
use illume_transport::{GBuffer, Technique, World};

fn cache(world: &World, settings: RadianceCacheSettings) -> RadianceCache {
    let timeline = Timeline::single(world.scene.clone(), 0.0, W, H);
    RadianceCache::new(world, &timeline, settings).unwrap()
}

/// Small records for fast tests: a 16×16 grid.
fn quick(temporal: TemporalMode) -> RadianceCacheSettings {
    RadianceCacheSettings {
        theta_strata: 16,
        phi_strata: 16,
        temporal,
        ..RadianceCacheSettings::default()
    }
}

#[test]
fn furnace_indirect_light_is_rho_squared_le_over_one_minus_rho() {
    // Closed sphere, ρ = 0.5, Le = 1: every gather ray brings back the light reflected
    // at least once, ρ·Le/(1 − ρ), so E = π·ρ·Le/(1 − ρ) and ρ/π·E = ρ²·Le/(1 − ρ) =
    // 0.5. Uniform radiance: no gradient, so only the gather's path noise (Russian
    // roulette, 64×64 rays per record) separates the image from it; 2 % bounds it.
    let rho = 0.5f32;
    let world = World::new(illume_scene::builtin::furnace(rho, Rgb::ONE));
    let g = GBuffer::render(&world, W, H, Vec2::splat(0.5));
    let mut rc = cache(&world, RadianceCacheSettings::default());
    let img = rc.indirect(&world, &g);
    let expect = rho * rho / (1.0 - rho);
    let mean = img.mean();
    for c in mean.to_array() {
        assert!(
            (c / expect - 1.0).abs() < 0.02,
            "indirect {mean} vs {expect}"
        );
    }
    // Every pixel sees the sphere, and every pixel is covered.
    assert!(img.pixels().iter().all(|p| p.min_element() > 0.0));
    assert!(rc.records_alive() > 0);
}

#[test]
fn reuse_keeps_a_static_frame_and_computes_fewer_records_than_per_frame() {
    let (world, g) = cornell();
    let mut per_frame = cache(&world, quick(TemporalMode::PerFrame));
    let mut reuse = cache(&world, quick(TemporalMode::Reuse));
    let p1 = per_frame.indirect(&world, &g);
    let p2 = per_frame.indirect(&world, &g);
    let r1 = reuse.indirect(&world, &g);
    let after_one = reuse.records_created();
    let r2 = reuse.indirect(&world, &g);
    // Frame 1 is the same cache in both modes.
    assert_eq!(p1.pixels(), r1.pixels());
    assert!(after_one > 0);
    // per_frame starts again (new keys: other rays, about as many records); reuse adds
    // none.
    assert!(per_frame.records_created() > 2 * after_one * 9 / 10);
    assert_eq!(reuse.records_created(), after_one);
    assert_eq!(reuse.stats().get("records_reused"), Some(after_one as f64));
    assert_eq!(r1.pixels(), r2.pixels(), "a static frame is kept exactly");
    assert_ne!(p1.pixels(), p2.pixels(), "per_frame draws new records");
}

#[test]
fn reuse_expires_records_after_max_age_frames() {
    let (world, g) = cornell();
    let mut rc = cache(
        &world,
        RadianceCacheSettings {
            max_age_frames: 2,
            ..quick(TemporalMode::Reuse)
        },
    );
    rc.indirect(&world, &g);
    let first = rc.records_created();
    rc.indirect(&world, &g);
    assert_eq!(rc.records_created(), first);
    rc.indirect(&world, &g); // frame 2: the frame-0 records are 2 frames old
    assert!(rc.records_created() > 2 * first * 9 / 10);
    assert_eq!(rc.stats().get("records_reused"), Some(0.0));
}

#[test]
fn a_light_change_expires_every_record_in_reuse() {
    let (world, g) = cornell();
    let mut rc = cache(&world, quick(TemporalMode::Reuse));
    rc.indirect(&world, &g);
    let first = rc.records_created();
    let light = world.scene.lights[0].clone();
    rc.scene_changed(
        &world,
        &[illume_scene::SceneChange::LightChanged {
            light: illume_scene::LightId(0),
            from: Box::new(light.clone()),
            to: Box::new(light),
        }],
    );
    rc.indirect(&world, &g);
    assert!(rc.records_created() > 2 * first * 9 / 10);
    assert_eq!(rc.stats().get("records_reused"), Some(0.0));
}

#[test]
fn a_surprise_move_expires_the_records_on_the_instance_and_those_that_see_it() {
    let world = World::new(illume_scene::builtin::load("cube-in-box").unwrap());
    let g = GBuffer::render(&world, W, H, Vec2::splat(0.5));
    let mut rc = cache(&world, quick(TemporalMode::Reuse));
    rc.indirect(&world, &g);
    let alive = rc.records_alive();
    // The instance with the fewest records on or seeing it, among those with some.
    let touches = |i: usize| {
        rc.records_with_seen()
            .filter(|(r, seen)| {
                r.instance.map(|x| x.index()) == Some(i) || seen.iter().any(|x| x.index() == i)
            })
            .count()
    };
    let (instance, count) = (0..world.scene.instances.len())
        .map(|i| (i, touches(i)))
        .filter(|&(_, n)| n > 0 && n < alive)
        .min_by_key(|&(_, n)| n)
        .expect("an instance touched by some records but not all");
    let on = rc
        .records()
        .filter(|r| r.instance.map(|x| x.index()) == Some(instance))
        .count();
    assert!(
        count > on,
        "rays of records elsewhere hit instance {instance}"
    );
    let id = illume_scene::InstanceId(instance as u32);
    let transform = world.scene.instances[instance].world_from_object;
    rc.scene_changed(
        &world,
        &[illume_scene::SceneChange::InstanceMoved {
            instance: id,
            from: transform,
            to: transform,
        }],
    );
    rc.indirect(&world, &g);
    assert_eq!(rc.stats().get("records_expired"), Some(count as f64));
    assert_eq!(
        rc.stats().get("records_surprise_expired"),
        Some(count as f64)
    );
    assert_eq!(
        rc.stats().get("records_reused"),
        Some((alive - count) as f64)
    );
}

#[test]
fn placement_does_not_depend_on_the_thread_count() {
    let (world, g) = cornell();
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut rc = cache(&world, quick(TemporalMode::PerFrame));
            let img = rc.indirect(&world, &g);
            let records: Vec<_> = rc.records().map(|r| r.position).collect();
            (img, records)
        })
    };
    let (a, ra) = run(1);
    let (b, rb) = run(2);
    assert_eq!(ra, rb);
    assert_eq!(a.pixels(), b.pixels());
}

#[test]
fn bad_settings_are_refused_by_name() {
    let (world, _) = cornell();
    let timeline = Timeline::single(world.scene.clone(), 0.0, W, H);
    let s = RadianceCacheSettings {
        accuracy: 0.0,
        ..RadianceCacheSettings::default()
    };
    let e = RadianceCache::new(&world, &timeline, s)
        .err()
        .unwrap()
        .to_string();
    assert!(e.starts_with("radiance_cache.accuracy: "), "{e}");
}

#[test]
fn show_records_marks_records_coloured_by_lifespan() {
    let (world, g) = cornell();
    for (mode, red) in [(TemporalMode::PerFrame, true), (TemporalMode::Reuse, false)] {
        let plain = cache(&world, quick(mode)).indirect(&world, &g);
        let mut rc = cache(
            &world,
            RadianceCacheSettings {
                show_records: true,
                ..quick(mode)
            },
        );
        let shown = rc.indirect(&world, &g);
        let marked: Vec<Rgb> = plain
            .pixels()
            .iter()
            .zip(shown.pixels())
            .filter(|(a, b)| a != b)
            .map(|(_, b)| *b)
            .collect();
        // Most records lie on surfaces the camera sees (they were placed from its
        // G-buffer); several may share a pixel.
        let alive = rc.records_alive();
        assert!(
            marked.len() * 4 >= alive && marked.len() <= alive,
            "{mode:?}: {} marked, {alive} records",
            marked.len()
        );
        for c in marked {
            assert_eq!(c.z, 0.0, "{mode:?}: {c}");
            // per_frame: lifespan 1, red; reuse on a still frame: δt_max, green.
            if red {
                assert!(c.x > 0.0 && c.y == 0.0, "{mode:?}: {c}");
            } else {
                assert!(c.x == 0.0 && c.y > 0.0, "{mode:?}: {c}");
            }
        }
    }
}

#[test]
fn neighbour_aging_ends_the_records_usable_at_a_shorter_lived_newer_one_with_it() {
    use illume_radiance_cache::record::usable;
    // The Cube in a Box moving at 100 fps: records next to the cube live short lives.
    let scene = illume_scene::builtin::load("cube-in-box").unwrap();
    let timeline = Timeline::new(scene.clone(), vec![0.35, 0.36], W, H).unwrap();
    let mut world = World::new(scene);
    world.set_time(0.35);
    let g = GBuffer::render(&world, W, H, Vec2::splat(0.5));
    let frame0 = |aging: bool| {
        let s = RadianceCacheSettings {
            neighbour_aging: aging,
            ..quick(TemporalMode::Extrapolated)
        };
        let mut rc = RadianceCache::new(&world, &timeline, s).unwrap();
        rc.indirect(&world, &g);
        let aged = rc.stats().get("records_aged").unwrap();
        // Frame 0 fills slots in admission order: id order is the order made.
        let records: Vec<_> = rc.records().cloned().collect();
        (records, aged)
    };
    let (off, aged_off) = frame0(false);
    let (on, aged_on) = frame0(true);
    assert_eq!(aged_off, 0.0);
    assert_eq!(off.len(), on.len(), "aging does not move records");
    let a = RadianceCacheSettings::default().accuracy;
    let mut shortened = 0;
    for (k, rk) in off.iter().enumerate() {
        assert_eq!(rk.position, on[k].position);
        // Of the records made after k, those at whose position k is usable: k ends no
        // later than the shortest-lived of them (all are made at frame 0).
        let expected = off[k + 1..]
            .iter()
            .filter(|l| usable(rk.ward_error(l.position, l.normal), a))
            .map(|l| l.lifespan_frames)
            .fold(rk.lifespan_frames, u32::min);
        assert_eq!(on[k].lifespan_frames, expected, "record {k}");
        shortened += usize::from(expected < rk.lifespan_frames);
    }
    assert!(shortened > 0, "no record was aged");
    // A record may be aged more than once.
    assert!(aged_on >= shortened as f64);
}
