//! The PCA at the paper's size (§3.2): 480 000 samples (800×600) of 180 keys. f32 blocks
//! must agree with f64 throughout. Runs in the test profile (opt-level 3) in a few seconds.

use illume_precomputed::pca::{Components, Precision, fit};
use rayon::prelude::*;
use std::time::Instant;

#[test]
fn f32_agrees_with_f64_at_480000_by_180() {
    let (rows, keys) = (800 * 600, 180);
    // Smooth "images" (a few spatial modes) with smooth temporal weights, a day-like
    // brightness curve and a little hash noise: variance falls off fast, as in Fig. 5.
    let data: Vec<Vec<f32>> = (0..keys)
        .into_par_iter()
        .map(|t| {
            let s = t as f32 / keys as f32;
            let day = (std::f32::consts::PI * s).sin();
            (0..rows)
                .map(|r| {
                    let (x, y) = ((r % 800) as f32 / 800.0, (r / 800) as f32 / 600.0);
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
        .collect();
    let refs: Vec<&[f32]> = data.iter().map(|k| k.as_slice()).collect();
    let start = Instant::now();
    let single = fit(&refs, Components::Fixed(10), Precision::F32).unwrap();
    let f32_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let double = fit(&refs, Components::Fixed(10), Precision::F64).unwrap();
    let f64_s = start.elapsed().as_secs_f64();
    eprintln!("PCA 480000×180, k = 10: f32 {f32_s:.2} s, f64 {f64_s:.2} s");
    for i in 0..5 {
        let (a, b) = (single.eigenvalues[i], double.eigenvalues[i]);
        assert!(
            (a - b).abs() <= 1e-4 * double.eigenvalues[0],
            "λ{i}: {a} vs {b}"
        );
        let dot: f64 = (0..keys)
            .map(|t| single.coefficient(i, t) as f64 * double.coefficient(i, t) as f64)
            .sum();
        assert!(dot > 0.9999, "eigenvector {i}: |dot| = {dot}");
    }
    for k in [1, 5, 10, 20] {
        let (a, b) = (single.variance_captured(k), double.variance_captured(k));
        assert!((a - b).abs() < 1e-5, "variance at k = {k}: {a} vs {b}");
    }
}
