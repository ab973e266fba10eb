//! Reference path tracer: samples per second and time to converge.
//!
//! `cargo bench -p illume-reference --bench convergence` renders the Cornell spot scene
//! (`builtin:cornell-spot`, or `ILLUME_BENCH_SCENE=path`) at 320×240: first a long run
//! (`ILLUME_BENCH_LONG_SPP`, default 2048 spp, seed 1000) as the converged image, then a
//! progressive run (seed 0) timed at 1, 2, 4, … spp, reporting relMSE (illume-metrics'
//! definition, ε = 1e-2) against the long run and the wall time at which it falls below
//! 1e-3. The long run's own error (≈ relMSE(1 spp)/long_spp) is printed too: it adds to
//! every measured relMSE.

use illume_metrics::rel_mse;
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_transport::World;
use std::time::Instant;

fn main() {
    // `cargo bench` passes `--bench`; ignore arguments.
    let scene_name =
        std::env::var("ILLUME_BENCH_SCENE").unwrap_or_else(|_| "builtin:cornell-spot".into());
    let long_spp: u32 = std::env::var("ILLUME_BENCH_LONG_SPP")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2048);
    let (w, h) = (320, 240);
    let scene = illume_scene::load_scene(std::path::Path::new(&scene_name)).expect("scene loads");
    let world = World::new(scene);
    let threads = rayon::current_num_threads();
    println!("scene {scene_name}, {w}×{h}, {threads} threads");

    let t0 = Instant::now();
    let mut long = ReferenceRenderer::new(
        ReferenceSettings {
            seed: 1000,
            ..Default::default()
        },
        w,
        h,
    );
    let chunk = 64;
    while long.samples() < long_spp {
        long.add_samples(&world, chunk.min(long_spp - long.samples()));
    }
    let long_s = t0.elapsed().as_secs_f64();
    let converged = long.images().full;
    println!(
        "long run: {long_spp} spp in {long_s:.1} s = {:.3} M samples/s",
        (w * h) as f64 * long_spp as f64 / long_s / 1e6
    );

    let mut r = ReferenceRenderer::new(
        ReferenceSettings {
            seed: 0,
            ..Default::default()
        },
        w,
        h,
    );
    let mut elapsed = 0.0f64;
    let mut converged_at: Option<(u32, f64)> = None;
    let mut first_relmse = None;
    println!(
        "{:>6} {:>10} {:>12} {:>16} {:>14}",
        "spp", "time [s]", "relMSE", "minus long own", "M samples/s"
    );
    let mut target = 1u32;
    while target <= long_spp / 2 {
        let t = Instant::now();
        r.add_samples(&world, target - r.samples());
        elapsed += t.elapsed().as_secs_f64();
        let e = rel_mse(&converged, &r.images().full, 1e-2).expect("same size");
        let own = *first_relmse.get_or_insert(e) / long_spp as f64;
        println!(
            "{:>6} {:>10.3} {:>12.3e} {:>16.3e} {:>14.3}",
            target,
            elapsed,
            e,
            e - own,
            (w * h) as f64 * target as f64 / elapsed / 1e6
        );
        if e < 1e-3 && converged_at.is_none() {
            converged_at = Some((target, elapsed));
        }
        target *= 2;
    }
    if let Some(e1) = first_relmse {
        println!(
            "long run's own relMSE ≈ {:.2e} (relMSE at 1 spp / {long_spp})",
            e1 / long_spp as f64
        );
    }
    match converged_at {
        Some((spp, s)) => println!("relMSE < 1e-3 at {spp} spp after {s:.2} s"),
        None => println!("relMSE did not fall below 1e-3 within {} spp", long_spp / 2),
    }
}
