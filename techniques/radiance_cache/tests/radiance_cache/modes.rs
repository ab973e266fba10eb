//! The four temporal modes over a known animation, the paper's Cube in a Box (§6; at an
//! assumed 100 frames per second, the cube moving 1 m/s: the paper gives neither), against the reference path tracer's
//! indirect light at the same G-buffer points: each mode's error, flicker and record
//! count, a static scene, and a camera pan.

use illume_core::image::RgbImage;
use illume_core::progress::Silent;
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_reference::{ReferenceSettings, ReferenceTechnique};
use illume_scene::Timeline;
use illume_transport::{GBuffer, Technique, World};
use std::sync::OnceLock;

const W: u32 = 64;
const H: u32 = 48;
const FRAMES: usize = 16;
const FPS: f64 = 100.0;
const START_S: f64 = 0.35;

fn times() -> Vec<f64> {
    (0..FRAMES).map(|i| START_S + i as f64 / FPS).collect()
}

fn scene() -> illume_scene::Scene {
    illume_scene::builtin::load("cube-in-box").unwrap()
}

/// A 16×16 grid per record (fast, noisy records: what temporal coherence is for).
fn settings(temporal: TemporalMode) -> RadianceCacheSettings {
    RadianceCacheSettings {
        theta_strata: 16,
        phi_strata: 16,
        temporal,
        ..RadianceCacheSettings::default()
    }
}

struct Run {
    frames: Vec<RgbImage>,
    /// Records computed: pass 1's and every frame's.
    records: u64,
    /// Deleted over the run.
    deleted: f64,
    /// Alive after the last frame.
    alive: usize,
}

/// Renders the timeline `times` as the engine does: precompute, then per frame the time
/// step, the technique's scene change, the G-buffer and the indirect light.
fn run(settings: RadianceCacheSettings, scene: illume_scene::Scene, times: &[f64]) -> Run {
    let timeline = Timeline::new(scene.clone(), times.to_vec(), W, H).unwrap();
    let mut world = World::new(scene);
    world.set_time(times[0]);
    let mut rc = RadianceCache::new(&world, &timeline, settings).unwrap();
    rc.precompute(&world, &mut Silent).unwrap();
    let mut frames = Vec::new();
    let mut deleted = 0.0;
    for (i, &t) in times.iter().enumerate() {
        if i > 0 {
            let changes = world.set_time(t);
            if !changes.is_empty() {
                rc.scene_changed(&world, &changes);
            }
        }
        let g = GBuffer::rasterize(&world, W, H);
        frames.push(rc.indirect(&world, &g));
        deleted += rc.stats().get("records_deleted").unwrap();
    }
    Run {
        frames,
        records: rc.records_created() + rc.records_planned() as u64,
        deleted,
        alive: rc.records_alive(),
    }
}

/// The reference's indirect light at each frame's G-buffer points, 128 samples per
/// pixel.
fn reference() -> &'static Vec<RgbImage> {
    static REF: OnceLock<Vec<RgbImage>> = OnceLock::new();
    REF.get_or_init(|| {
        let mut world = World::new(scene());
        times()
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                world.set_time(t);
                let g = GBuffer::rasterize(&world, W, H);
                let mut r = ReferenceTechnique::new(ReferenceSettings {
                    spp_per_frame: 128,
                    seed: 1000 + i as u64,
                    ..ReferenceSettings::default()
                })
                .unwrap();
                r.advance(&world, &Default::default());
                r.indirect(&world, &g)
            })
            .collect()
    })
}

/// Mean over frames of the 8×8-block error against the reference.
fn error(frames: &[RgbImage]) -> f64 {
    frames
        .iter()
        .zip(reference())
        .map(|(f, r)| illume_metrics::block_error(r, f, 8).unwrap())
        .sum::<f64>()
        / frames.len() as f64
}

fn flicker(frames: &[RgbImage]) -> f64 {
    illume_metrics::flicker(frames, reference()).unwrap().mean
}

#[test]
fn interpolated_flickers_least_and_computes_fewest_records_at_per_frame_error() {
    let t = times();
    let per_frame = run(settings(TemporalMode::PerFrame), scene(), &t);
    let reuse = run(settings(TemporalMode::Reuse), scene(), &t);
    let extrapolated = run(settings(TemporalMode::Extrapolated), scene(), &t);
    let interpolated = run(settings(TemporalMode::Interpolated), scene(), &t);
    let rows = [
        ("per_frame", &per_frame),
        ("reuse", &reuse),
        ("extrapolated", &extrapolated),
        ("interpolated", &interpolated),
    ];
    for (name, r) in rows {
        eprintln!(
            "{name:>12}: error {:.4}, flicker {:.5}, records {}, deleted {}",
            error(&r.frames),
            flicker(&r.frames),
            r.records,
            r.deleted
        );
    }
    let reference_flicker = {
        let r = reference();
        let shifted: Vec<RgbImage> = r.iter().skip(1).cloned().collect();
        let base: Vec<RgbImage> = r.iter().take(r.len() - 1).cloned().collect();
        illume_metrics::flicker(&shifted, &base).unwrap().mean
    };
    eprintln!("reference flicker (its own noise) {reference_flicker:.5}");
    // Tolerance: 16×16 records carry per-record noise of a few per cent; 0.06 is the
    // reference-agreement harness's block tolerance.
    for (name, r) in rows {
        assert!(
            error(&r.frames) < 0.06,
            "{name}: error {}",
            error(&r.frames)
        );
    }
    assert!(error(&interpolated.frames) <= 1.1 * error(&per_frame.frames));
    let (fp, fe, fi) = (
        flicker(&per_frame.frames),
        flicker(&extrapolated.frames),
        flicker(&interpolated.frames),
    );
    assert!(fi <= 0.5 * fp, "interpolated {fi} vs per_frame {fp}");
    assert!(
        fi <= fe && fe <= fp,
        "extrapolated {fe} between {fi} and {fp}"
    );
    assert!(interpolated.records < per_frame.records);
}

#[test]
fn a_static_scene_gives_no_flicker_and_no_new_records() {
    // The cube's animation is dropped: every frame is the same scene.
    let mut still = scene();
    still.active_animation = None;
    let t = times();
    for mode in [
        TemporalMode::Reuse,
        TemporalMode::Extrapolated,
        TemporalMode::Interpolated,
    ] {
        let one = run(settings(mode), still.clone(), &t[..1]);
        let r = run(settings(mode), still.clone(), &t[..8]);
        for f in &r.frames[1..] {
            assert_eq!(f.pixels(), r.frames[0].pixels(), "{mode:?}");
        }
        assert_eq!(r.records, one.records, "{mode:?}");
    }
}

#[test]
fn records_that_leave_the_view_in_a_camera_pan_are_deleted() {
    use illume_core::{Quat, Vec4};
    use illume_scene::{Animation, Channel, ChannelValues, Interpolation};
    // The cube stands still; the camera turns 50° to the left over 0.15 s, then holds.
    let mut s = scene();
    let pitch = Quat::from_rotation_x(-12f32.to_radians());
    let turned = Quat::from_rotation_y(50f32.to_radians()) * pitch;
    let q = |q: Quat| Vec4::new(q.x, q.y, q.z, q.w);
    s.animations = vec![Animation {
        name: "pan".into(),
        channels: vec![Channel {
            node: s.camera.node,
            times: vec![0.0, 0.15],
            values: ChannelValues::Rotation(vec![q(pitch), q(turned)]),
            interpolation: Interpolation::Linear,
        }],
        properties: Vec::new(),
    }];
    s.active_animation = Some(0);
    // δt_max = 20: the first frame's records expire at frame 20, after the pan.
    let t: Vec<f64> = (0..24).map(|i| i as f64 / FPS).collect();
    let with = run(settings(TemporalMode::Extrapolated), s.clone(), &t);
    let without = run(
        RadianceCacheSettings {
            deletion: false,
            ..settings(TemporalMode::Extrapolated)
        },
        s,
        &t,
    );
    eprintln!(
        "deletion on: {} deleted, {} alive; off: {} deleted, {} alive",
        with.deleted, with.alive, without.deleted, without.alive
    );
    assert!(with.deleted > 50.0, "{}", with.deleted);
    assert_eq!(without.deleted, 0.0);
    assert!(with.alive + 50 < without.alive);
}
