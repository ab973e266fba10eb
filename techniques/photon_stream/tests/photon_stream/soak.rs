//! Soak (issue 14): photon streaming's thread runs while frames render and an object and
//! a light move every 100 ms. Passes when no frame takes longer than 5 s (a watchdog: a
//! deadlock fails instead of hanging), resident memory after warm-up stays within 5 % of
//! its value at the end of the warm-up, and the pool's books balance exactly at the end
//! (every VSL's power equals the sum of its pooled impacts, K the pooled photons).
//!
//! It measures this process's resident memory and its watchdog exits the process, so it
//! runs in a process of its own ([`in_own_process`]), not beside the other tests of this
//! binary.
//!
//! CI runs 20 s. The long soak (one hour, not in CI):
//! `ILLUME_SOAK_SECONDS=3600 cargo test --release -p illume-photon-stream --test photon_stream -- soak --nocapture`
//! (it prints the resident-memory curve, one line every 10 s).

use crate::common::in_own_process;
use illume_core::{Affine3A, Vec3};
use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
use illume_render::{RenderSettings, Renderer};
use illume_scene::{Edit, InstanceId, LightId};
use illume_transport::{Budget, Technique, World};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Resident memory of this process [bytes] (Linux: `/proc/self/statm`).
fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm")
        .expect("the soak test reads /proc/self/statm (Linux only)");
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .expect("statm's second field is the resident page count");
    pages * 4096
}

#[test]
fn streaming_soak_keeps_memory_flat_and_books_exact_without_deadlock() {
    if !in_own_process("soak::streaming_soak_keeps_memory_flat_and_books_exact_without_deadlock") {
        return;
    }
    let seconds: f64 = std::env::var("ILLUME_SOAK_SECONDS")
        .ok()
        .map(|s| {
            s.parse()
                .expect("ILLUME_SOAK_SECONDS is a number of seconds")
        })
        .unwrap_or(20.0);
    let warm_up = (seconds * 0.25).min(60.0);

    // The watchdog: the frame loop reports each frame; more than 5 s without one fails
    // the whole process (a deadlock cannot be unwound by a panic in another thread).
    let last_frame_ms = Arc::new(AtomicU64::new(0));
    let done = Arc::new(AtomicBool::new(false));
    let start = Instant::now();
    let watchdog = {
        let (last, done) = (Arc::clone(&last_frame_ms), Arc::clone(&done));
        std::thread::spawn(move || {
            while !done.load(Ordering::Acquire) {
                std::thread::sleep(Duration::from_millis(200));
                let now = start.elapsed().as_millis() as u64;
                let since = now.saturating_sub(last.load(Ordering::Acquire));
                if since > 5_000 && !done.load(Ordering::Acquire) {
                    eprintln!("soak: no frame for {since} ms: deadlock or stall");
                    std::process::exit(101);
                }
            }
        })
    };

    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let mut ps = PhotonStream::new(
        &world,
        PhotonStreamSettings {
            vsl_count: 60,
            pool_size: 50_000,
            ..PhotonStreamSettings::default()
        },
    )
    .unwrap();
    let renderer = Renderer::new(RenderSettings {
        width: 160,
        height: 120,
        ..RenderSettings::default()
    });
    let (sphere, sphere_at, light_at) = {
        let w = world.read().unwrap();
        let s = w
            .scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .expect("cornell-spot has a sphere");
        let node = w.scene.lights[0].node;
        (
            InstanceId(s as u32),
            w.scene.instances[s].world_from_object,
            w.scene.nodes[node.index()].world_from_node,
        )
    };
    let mut frames = 0u64;
    let mut moves = 0u64;
    let mut next_move = 0.0;
    let mut rss_after_warm_up = None;
    let mut rss_max_after = 0u64;
    let mut next_print = 0.0;
    while start.elapsed().as_secs_f64() < seconds {
        let t = start.elapsed().as_secs_f64();
        if t >= next_move {
            // Sphere and light on small circles, a new position every 100 ms.
            let phase = moves as f32 * 0.37;
            let offset = Vec3::new(phase.cos(), 0.0, phase.sin()) * 0.2;
            ps.before_world_write();
            let changes = {
                let mut w = world.write().unwrap();
                let mut c = w
                    .apply_edit(&Edit::SetInstanceTransform {
                        instance: sphere,
                        world_from_object: Affine3A::from_translation(offset) * sphere_at,
                    })
                    .unwrap();
                c.extend(
                    w.apply_edit(&Edit::SetLightTransform {
                        light: LightId(0),
                        world_from_light: Affine3A::from_translation(offset * 0.5) * light_at,
                    })
                    .unwrap(),
                );
                c
            };
            ps.scene_changed(&world.read().unwrap(), &changes);
            moves += 1;
            next_move += 0.1;
        }
        {
            let w = world.read().unwrap();
            ps.advance(&w, &Budget::default());
            let frame = renderer.render(&w, &mut ps, frames);
            assert!(
                frame.full.mean().is_finite(),
                "frame {frames} is not finite"
            );
        }
        frames += 1;
        last_frame_ms.store(start.elapsed().as_millis() as u64, Ordering::Release);
        let rss = resident_bytes();
        if t >= warm_up {
            match rss_after_warm_up {
                None => rss_after_warm_up = Some(rss),
                Some(_) => rss_max_after = rss_max_after.max(rss),
            }
        }
        if t >= next_print {
            // Printed as it goes, so that a long run's curve survives an interruption.
            eprintln!(
                "soak: t = {t:7.1} s, resident {:.1} MB, frames {frames}",
                rss as f64 / 1e6
            );
            next_print += 10.0;
        }
    }
    done.store(true, Ordering::Release);
    watchdog.join().unwrap();
    eprintln!("soak: {frames} frames, {moves} moves in {seconds} s");

    ps.pause();
    std::thread::sleep(Duration::from_millis(100)); // a batch in flight lands
    let stats = ps.stats();
    let impacts = stats.get("impacts_shot").unwrap_or(0.0);
    eprintln!("soak: {impacts} impacts shot");
    assert!(
        impacts > 10.0 * 50_000.0,
        "the thread shot {impacts} impacts: the FIFO pool of 50 000 was not cycled 10 times"
    );
    ps.validate().expect("the pool's books balance");
    let base = rss_after_warm_up.expect("the soak outlasted its warm-up");
    assert!(
        rss_max_after as f64 <= base as f64 * 1.05,
        "resident memory grew from {:.1} MB after warm-up to {:.1} MB",
        base as f64 / 1e6,
        rss_max_after as f64 / 1e6
    );
    assert!(frames > 10 && moves > 10, "{frames} frames, {moves} moves");
}
