//! Temporal radiance caching's measurements in kind of the paper's §6, printed as tables
//! (recorded in BENCHMARKS.md):
//!
//! * `fig10` — the accuracy of frame-0 records over frames 0–19 of the Cube in a Box
//!   (100 frames per second) for each way of carrying a record through time: kept as is
//!   (`reuse`), extrapolated (Eq. 18–20, from the §4.3 reprojection) and interpolated
//!   towards the record traced again at frame 19 (Eq. 21–23); the paper reports above
//!   98 % with interpolation;
//! * `costs` — a record's gather (64×64 rays through `continue_path`) against its
//!   reprojection to the next frame (the paper: 4.58 ms against 0.46 ms on its GPU);
//! * `deletion` — 100 frames of the Cube in a Box at 160×120 with deletion on and off
//!   (the paper: −25–30 % storage, −20–30 % time), `extrapolated`.
//!
//! `cargo bench -p illume-radiance-cache --bench temporal [-- fig10|costs|deletion]`

use illume_core::progress::Silent;
use illume_core::{Rgb, Vec3};
use illume_radiance_cache::record::RecordSettings;
use illume_radiance_cache::reproject::reproject;
use illume_radiance_cache::{
    HemisphereGather, IrradianceRecord, RadianceCache, RadianceCacheSettings, TemporalMode,
};
use illume_scene::Timeline;
use illume_transport::{GBuffer, Technique, World};
use std::time::Instant;

const FPS: f64 = 100.0;
const START_S: f64 = 0.35;

fn cube_world(t: f64) -> World {
    World::new(illume_scene::builtin::load("cube-in-box").unwrap()).at_time(t)
}

/// Record points: a 6×6 grid over the floor around the cube's first leg (records the
/// motion reaches), plus four on the back wall.
fn points() -> Vec<(Vec3, Vec3)> {
    let mut p: Vec<(Vec3, Vec3)> = (0..36)
        .map(|i| {
            let x = -0.9 + 0.36 * (i % 6) as f32;
            let z = -0.9 + 0.3 * (i / 6) as f32;
            (Vec3::new(x, 0.0, z), Vec3::Y)
        })
        .collect();
    for x in [-0.6f32, -0.2, 0.2, 0.6] {
        p.push((Vec3::new(x, 0.3, -1.0), Vec3::Z));
    }
    p
}

fn relative_error(predicted: Rgb, truth: Rgb) -> f64 {
    let (a, b) = (predicted.element_sum() as f64, truth.element_sum() as f64);
    if b > 0.0 { (a - b).abs() / b } else { 0.0 }
}

fn fig10() {
    let s = RecordSettings::default();
    let frames = 20usize;
    let worlds: Vec<World> = (0..frames)
        .map(|i| cube_world(START_S + i as f64 / FPS))
        .collect();
    let mut kept = vec![0.0f64; frames];
    let mut extrapolated = vec![0.0f64; frames];
    let mut interpolated = vec![0.0f64; frames];
    let pts = points();
    // Records under the cube at frame 0 lie inside it: skipped (no surface there).
    let mut used = 0usize;
    for (k, &(p, n)) in pts.iter().enumerate() {
        let key = 7000 + k as u64;
        let (g, paths) = HemisphereGather::trace_keeping_paths(&worlds[0], p, n, key, &s).unwrap();
        let e0 = g.irradiance();
        if e0.element_sum() <= 0.0 {
            continue;
        }
        used += 1;
        let next = reproject(&worlds[0], &worlds[1], p, &g, &paths, &s, 64)
            .gather
            .irradiance();
        let truth: Vec<Rgb> = worlds
            .iter()
            .map(|w| {
                HemisphereGather::trace(w, p, n, key, &s)
                    .unwrap()
                    .irradiance()
            })
            .collect();
        let last = truth[frames - 1];
        for t in 0..frames {
            let dt = t as f32;
            kept[t] += relative_error(e0, truth[t]);
            extrapolated[t] += relative_error(e0 + (next - e0) * dt, truth[t]);
            interpolated[t] +=
                relative_error(e0 + (last - e0) * (dt / (frames - 1) as f32), truth[t]);
        }
    }
    println!(
        "fig10: accuracy (1 − mean relative error of E) of {used} frame-0 records of \
         builtin:cube-in-box (100 fps, from t = {START_S} s), 64×64 rays, same rays every frame"
    );
    println!("| frame | kept (reuse) | extrapolated | interpolated |");
    println!("|---:|---:|---:|---:|");
    for t in 0..frames {
        let u = used as f64;
        println!(
            "| {t} | {:.2} % | {:.2} % | {:.2} % |",
            100.0 * (1.0 - kept[t] / u),
            100.0 * (1.0 - extrapolated[t] / u),
            100.0 * (1.0 - interpolated[t] / u)
        );
    }
}

fn costs() {
    let s = RecordSettings::default();
    let (w0, w1) = (cube_world(START_S), cube_world(START_S + 1.0 / FPS));
    let pts = points();
    let (mut gather_s, mut reproject_s, mut records) = (0.0, 0.0, 0);
    for round in 0..3 {
        for (k, &(p, n)) in pts.iter().enumerate() {
            let key = 100 * round + k as u64;
            let t0 = Instant::now();
            let (g, paths) = HemisphereGather::trace_keeping_paths(&w0, p, n, key, &s).unwrap();
            let _ = IrradianceRecord::from_gather(p, &g, 0, None, &s);
            let t1 = Instant::now();
            let r = reproject(&w0, &w1, p, &g, &paths, &s, 64);
            let _ = IrradianceRecord::from_gather(p, &r.gather, 1, None, &s);
            let t2 = Instant::now();
            gather_s += (t1 - t0).as_secs_f64();
            reproject_s += (t2 - t1).as_secs_f64();
            records += 1;
        }
    }
    println!(
        "costs: {records} records of builtin:cube-in-box, one thread, 64×64 rays: gather + record {:.3} ms, \
         reprojection to the next frame + its record {:.3} ms (ratio {:.3})",
        1e3 * gather_s / records as f64,
        1e3 * reproject_s / records as f64,
        reproject_s / gather_s
    );
}

fn deletion() {
    let (w, h) = (160u32, 120u32);
    let times: Vec<f64> = (0..100).map(|i| i as f64 / FPS).collect();
    println!(
        "deletion: builtin:cube-in-box, {w}×{h}, 100 frames at 100 fps, extrapolated, 64×64 rays"
    );
    println!("| deletion | time s | records computed | alive at the end | memory MB | deleted |");
    println!("|---|---:|---:|---:|---:|---:|");
    for deletion in [true, false] {
        let scene = illume_scene::builtin::load("cube-in-box").unwrap();
        let timeline = Timeline::new(scene.clone(), times.clone(), w, h).unwrap();
        let mut world = World::new(scene);
        let settings = RadianceCacheSettings {
            temporal: TemporalMode::Extrapolated,
            deletion,
            ..RadianceCacheSettings::default()
        };
        let mut rc = RadianceCache::new(&world, &timeline, settings).unwrap();
        let start = Instant::now();
        rc.precompute(&world, &mut Silent).unwrap();
        let mut deleted = 0.0;
        let mut memory: f64 = 0.0;
        for (i, &t) in times.iter().enumerate() {
            if i > 0 {
                let changes = world.set_time(t);
                if !changes.is_empty() {
                    rc.scene_changed(&world, &changes);
                }
            }
            let g = GBuffer::rasterize(&world, w, h);
            let _ = rc.indirect(&world, &g);
            let stats = rc.stats();
            deleted += stats.get("records_deleted").unwrap_or(0.0);
            memory = memory.max(stats.get("memory_bytes").unwrap_or(0.0));
        }
        println!(
            "| {} | {:.1} | {} | {} | {:.2} | {} |",
            if deletion { "on" } else { "off" },
            start.elapsed().as_secs_f64(),
            rc.records_created(),
            rc.records_alive(),
            memory / 1e6,
            deleted
        );
    }
}

fn main() {
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let run = |name: &str| filter.is_empty() || filter.iter().any(|f| name.contains(f.as_str()));
    if run("fig10") {
        fig10();
    }
    if run("costs") {
        costs();
    }
    if run("deletion") {
        deletion();
    }
}
