//! The streaming thread (§6, the default mode): it fills the pool by itself, brings every
//! group up to date after scene changes made while it runs, and leaves exactly the
//! accumulators a from-scratch trace of the final scene gives; frames rendered meanwhile
//! see whole groups only.

use illume_core::{Affine3A, Vec3};
use illume_scene::{Edit, InstanceId};
use illume_selective::{GroupOrder, Selective, SelectiveMode, SelectiveSettings, Streaming};
use illume_transport::{Budget, ChangeResponse, GBuffer, SharedWorld, Technique, World};
use std::time::{Duration, Instant};

fn settings() -> SelectiveSettings {
    SelectiveSettings {
        pilots_per_group: 12,
        ratio: 4,
        element_count: 1500,
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        warm_up: false,
        order: GroupOrder::Priority,
        mode: SelectiveMode::Streaming,
        ..SelectiveSettings::default()
    }
}

/// Polls `done` on the solution until it holds; fails after a minute naming `what`.
fn wait_for(sel: &Streaming, what: &str, done: impl Fn(&Selective) -> bool) {
    let t0 = Instant::now();
    while !sel.with_solution(|s| done(s)) {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the streaming thread did not {what} within 60 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn move_sphere(world: &SharedWorld, sel: &mut Streaming, by: Vec3) {
    sel.before_world_write();
    let mut w = world.write().unwrap();
    let sphere = InstanceId(
        w.scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .expect("cornell-spot has a sphere") as u32,
    );
    let world_from_object =
        Affine3A::from_translation(by) * w.scene.instances[sphere.index()].world_from_object;
    let changes = w
        .apply_edit(&Edit::SetInstanceTransform {
            instance: sphere,
            world_from_object,
        })
        .unwrap();
    drop(w);
    let r = sel.scene_changed(&world.read().unwrap(), &changes);
    assert_eq!(r, ChangeResponse::Updated);
}

/// Asserts that `sel`'s accumulators and impact counts are exactly a from-scratch trace's
/// of `world` as it stands, with `settings` (traced in deterministic mode).
fn assert_fresh_trace(world: &SharedWorld, sel: &Streaming, settings: SelectiveSettings) {
    let w = world.read().unwrap();
    let mut oracle = Selective::for_world(
        &w,
        SelectiveSettings {
            mode: SelectiveMode::Deterministic,
            ..settings
        },
    )
    .unwrap();
    oracle.converge(&w);
    let (ours, counts) = sel.with_solution(|s| (s.accumulators().to_vec(), s.counts().to_vec()));
    crate::common::assert_same_accumulators(&ours, oracle.accumulators());
    assert_eq!(
        counts,
        oracle.counts(),
        "impact counts differ from a fresh trace"
    );
}

#[test]
fn the_thread_fills_the_pool_and_follows_changes_to_the_exact_solution() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let mut sel = Streaming::new(&world, settings()).unwrap();
    let pool = sel.with_solution(|s| s.layout().pool());
    // No warm-up: the thread fills the pool in index order by itself, with no advance.
    wait_for(&sel, "fill the pool", |s| s.filled() == pool);
    assert!(sel.thread_steps() > 0);

    // Two moves while the thread works, frames rendered in between.
    let budget = Budget::default();
    move_sphere(&world, &mut sel, Vec3::new(0.3, 0.0, 0.2));
    let g = GBuffer::render(
        &world.read().unwrap(),
        16,
        12,
        illume_core::Vec2::splat(0.5),
    );
    sel.advance(&world.read().unwrap(), &budget);
    let img = sel.indirect(&world.read().unwrap(), &g);
    assert!(img.mean().x.is_finite() && img.mean().x > 0.0);
    move_sphere(&world, &mut sel, Vec3::new(-0.5, 0.1, 0.0));
    let steps_before = sel.thread_steps();
    wait_for(&sel, "bring every group up to date", |s| {
        s.stale_groups() == 0
    });
    assert!(
        sel.thread_steps() > steps_before,
        "the thread re-traced nothing"
    );

    // Exactly a from-scratch trace of the final scene.
    assert_fresh_trace(&world, &sel, settings());
    assert!(sel.with_solution(|s| s.counters().photons_invalid) > 0);
}

#[test]
fn the_engine_builds_the_streaming_technique_by_default() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    assert_eq!(SelectiveSettings::default().mode, SelectiveMode::Streaming);
    let technique = illume_selective::build(&world, settings()).unwrap();
    // Only the streaming technique reports its thread's steps.
    let t0 = Instant::now();
    while technique.stats().get("thread_steps").unwrap_or(0.0) == 0.0 {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no thread step in 60 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    let deterministic = illume_selective::build(
        &world,
        SelectiveSettings {
            mode: SelectiveMode::Deterministic,
            ..settings()
        },
    )
    .unwrap();
    assert_eq!(deterministic.stats().get("thread_steps"), None);
}

/// An announced world write holds the thread off the world until the frame loop says it
/// is done (`advance` or `scene_changed`): otherwise the thread's next read lock got in
/// ahead of the woken writer, step after step.
#[test]
fn an_announced_world_write_pauses_the_thread_until_the_frame_goes_on() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    // Short steps (4 096 photons), and a pool that keeps growing: the thread never idles.
    let mut sel = Streaming::new(
        &world,
        SelectiveSettings {
            pilots_per_group: 64,
            ratio: 64,
            max_photons: 1 << 32,
            ..settings()
        },
    )
    .unwrap();
    let mut checked = 0;
    for _ in 0..20 {
        let start = Instant::now();
        sel.before_world_write();
        let s1 = sel.thread_steps();
        // At most the step in flight may finish; no new one may start.
        std::thread::sleep(Duration::from_millis(30));
        let s2 = sel.thread_steps();
        let within = start.elapsed() < illume_selective::stream::WORLD_WAIT;
        let w = world.read().unwrap();
        sel.advance(&w, &Budget::default());
        drop(w);
        if within {
            assert!(
                s2 - s1 <= 1,
                "the thread took {} steps while a world write was pending",
                s2 - s1
            );
            checked += 1;
        }
        // Once the frame goes on, the thread does too.
        let t0 = Instant::now();
        while sel.thread_steps() == s2 {
            assert!(
                t0.elapsed() < Duration::from_secs(60),
                "the thread did not resume"
            );
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    assert!(
        checked >= 5,
        "only {checked} of 20 trials were timed within WORLD_WAIT"
    );
}

#[test]
fn settled_once_the_thread_is_done_and_a_frame_took_its_values() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let mut sel = Streaming::new(&world, settings()).unwrap();
    let g = GBuffer::render(
        &world.read().unwrap(),
        16,
        12,
        illume_core::Vec2::splat(0.5),
    );
    // A viewer's loop: a frame, then the question; at most a minute.
    let frame = |sel: &mut Streaming| sel.indirect(&world.read().unwrap(), &g);
    let wait_settled = |sel: &mut Streaming, what: &str| {
        let t0 = Instant::now();
        loop {
            let img = frame(sel);
            if sel.settled() {
                return img;
            }
            assert!(
                t0.elapsed() < Duration::from_secs(60),
                "not settled within 60 s {what}"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
    };
    let settled = wait_settled(&mut sel, "after the fill");
    assert!(sel.with_solution(|s| !s.has_work() && s.stale_groups() == 0));
    let steps = sel.thread_steps();
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(sel.thread_steps(), steps, "a settled thread kept stepping");
    assert!(
        frame(&mut sel).pixels() == settled.pixels(),
        "settled, yet the next frame differs"
    );
    // A move makes groups stale under the frame's lock: not settled from that moment,
    // however far the thread has got.
    move_sphere(&world, &mut sel, Vec3::new(0.3, 0.0, 0.2));
    assert!(!sel.settled(), "settled with the move not yet re-traced");
    let moved = wait_settled(&mut sel, "after the move");
    assert!(sel.thread_steps() > steps, "the thread re-traced nothing");
    assert!(
        moved.pixels() != settled.pixels(),
        "the sphere moved and the indirect light did not change"
    );
}

/// Moves `light` 0 of `world` by `by` (a light change: with one light, a restart).
fn move_light(world: &SharedWorld, sel: &mut Streaming, by: Vec3) {
    sel.before_world_write();
    let mut w = world.write().unwrap();
    let light = illume_scene::LightId(0);
    let world_from_light = Affine3A::from_translation(by) * w.scene.lights[0].world_from_light;
    let changes = w
        .apply_edit(&Edit::SetLightTransform {
            light,
            world_from_light,
        })
        .unwrap();
    drop(w);
    assert_eq!(
        sel.scene_changed(&world.read().unwrap(), &changes),
        ChangeResponse::Updated
    );
}

/// The thread traces a stale group outside the solution's lock and applies it under the
/// lock afterwards. Moves, a restart (the light moved) and a frame thread that brings
/// the solution up to date itself, all while groups are out being traced, must still end
/// in exactly a from-scratch trace's accumulators and counts: a re-trace that came back
/// after a restart or after its group was brought up to date is dropped, one whose group
/// went stale again moves it one state on.
#[test]
fn re_traces_outside_the_lock_end_in_the_exact_solution_whatever_came_between() {
    // Groups of ≈ 1 600 photons, so that a re-trace is out for a while.
    let settings = || SelectiveSettings {
        pilots_per_group: 400,
        ..settings()
    };
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let mut sel = Streaming::new(&world, settings()).unwrap();
    let pool = sel.with_solution(|s| s.layout().pool());
    wait_for(&sel, "fill the pool", |s| s.filled() == pool);
    for round in 0..32 {
        let dx = if round % 2 == 0 { 0.04 } else { -0.03 };
        move_sphere(&world, &mut sel, Vec3::new(dx, 0.0, 0.01));
        std::thread::sleep(Duration::from_millis(3));
        match round % 8 {
            // A restart while a group may be out.
            3 => move_light(&world, &mut sel, Vec3::new(0.02, 0.0, 0.0)),
            // The frame's side brings every group up to date while one may be out.
            6 => sel.with_solution(|s| s.converge(&world.read().unwrap())),
            _ => {}
        }
    }
    wait_for(
        &sel,
        "bring every group up to date and fill the pool",
        |s| s.stale_groups() == 0 && s.filled() == pool,
    );
    assert_fresh_trace(&world, &sel, settings());
}
