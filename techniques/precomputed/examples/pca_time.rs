//! Times `pca::fit` (f32, k = 10) on day-like keys: 180 keys of 64×48 and of 320×240
//! values, medians of several runs. Used for docs/robustness.md (issue 38, fifth round):
//! `cargo run --release -p illume-precomputed --example pca_time`.

use illume_precomputed::pca::{Components, Precision, fit};
use std::time::Instant;

/// Smooth key images with smooth temporal weights and a little hash noise.
fn keys(width: usize, height: usize, count: usize) -> Vec<Vec<f32>> {
    (0..count)
        .map(|t| {
            let s = t as f32 / count as f32;
            let day = (std::f32::consts::PI * s).sin();
            (0..width * height)
                .map(|r| {
                    let x = (r % width) as f32 / width as f32;
                    let y = (r / width) as f32 / height as f32;
                    let noise = ((r as u32).wrapping_mul(2_654_435_761) ^ (t as u32 * 97))
                        .wrapping_mul(2_246_822_519) as f32
                        / u32::MAX as f32;
                    day * (1.0 + x)
                        + 0.3 * (6.0 * s).sin() * (3.0 * y).cos()
                        + 0.1 * (13.0 * s).cos() * (9.0 * x * y).sin()
                        + 0.01 * noise
                })
                .collect()
        })
        .collect()
}

/// CPU time of the whole process (all threads), in seconds, from `/proc/self/stat`
/// (clock ticks of 10 ms; 0 where there is no such file).
fn process_cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // The fields after the command name (which ends with the last ')'): utime and stime
    // are the 12th and 13th of them.
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn main() {
    for (width, height, runs) in [(64, 48, 15), (320, 240, 7)] {
        let data = keys(width, height, 180);
        let refs: Vec<&[f32]> = data.iter().map(Vec::as_slice).collect();
        let cpu_start = process_cpu_seconds();
        let mut times: Vec<f64> = (0..runs)
            .map(|_| {
                let start = Instant::now();
                let basis = fit(&refs, Components::Fixed(10), Precision::F32).unwrap();
                std::hint::black_box(&basis);
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        let cpu_ms = (process_cpu_seconds() - cpu_start) * 1e3 / runs as f64;
        times.sort_by(f64::total_cmp);
        let basis = fit(&refs, Components::Fixed(10), Precision::F32).unwrap();
        println!(
            "180 keys of {width}×{height}: median {:.1} ms (min {:.1}, max {:.1}, {runs} runs), CPU {cpu_ms:.0} ms a fit; λ0..2 = {:.6e} {:.6e} {:.6e}",
            times[runs / 2],
            times[0],
            times[runs - 1],
            basis.eigenvalues[0],
            basis.eigenvalues[1],
            basis.eigenvalues[2]
        );
    }
}
