//! The image metrics through the public API, on images read back from files as the CLI
//! reads them.

use illume_core::Rgb;
use illume_core::image::{RgbImage, ToneCurve, ToneMap};
use illume_core::sampling::Pcg32;
use illume_metrics::{
    CompareSettings, Metric, Peak, compare_files, compare_folders, compare_images,
    compare_images_with,
};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illume-metrics-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// 48×40 PCG-random values that are multiples of 1/256 in [0, 0.75]: adding 1/8 is exact.
fn random_image(seed: u64) -> RgbImage {
    let mut rng = Pcg32::new(seed, 7);
    let mut img = RgbImage::black(48, 40);
    for p in img.pixels_mut() {
        *p = Rgb::new(
            rng.next_below(193) as f32 / 256.0,
            rng.next_below(193) as f32 / 256.0,
            rng.next_below(193) as f32 / 256.0,
        );
    }
    img
}

#[test]
fn identical_images_score_perfectly_on_every_metric() {
    let dir = scratch("identical");
    let img = random_image(1);
    let path = dir.join("a.exr");
    img.write(&path, &ToneMap::default()).unwrap();
    let values = compare_files(&path, &path, &Metric::ALL, &CompareSettings::default()).unwrap();
    let expected = [
        (Metric::Rmse, 0.0),
        (Metric::RelMse, 0.0),
        (Metric::Psnr, f64::INFINITY),
        (Metric::Ssim, 1.0),
        (Metric::Flip, 0.0),
        (Metric::HdrFlip, 0.0),
    ];
    for ((m, v), (em, ev)) in values.iter().zip(expected) {
        assert_eq!(*m, em);
        assert!(
            *v == ev || (v - ev).abs() < 1e-12,
            "{m}: {v}, expected {ev}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn constant_offset_gives_exact_rmse_and_psnr() {
    let a = random_image(2);
    let c = 0.125f64;
    let b = a.map(|p| *p + Rgb::splat(c as f32));
    let v = compare_images(&a, &b, &[Metric::Rmse, Metric::Psnr]).unwrap();
    assert_eq!(v[0], (Metric::Rmse, c));
    // LDR reference (all values ≤ 1) → peak 1.
    assert_eq!(v[1], (Metric::Psnr, 20.0 * (1.0 / c).log10()));

    // HDR: scale both by 8; the auto peak becomes the reference maximum.
    let (a8, b8) = (a.map(|p| *p * 8.0), b.map(|p| *p * 8.0));
    let peak = a8
        .pixels()
        .iter()
        .map(|p| p.max_element() as f64)
        .fold(0.0, f64::max);
    assert!(peak > 1.0);
    let v = compare_images(&a8, &b8, &[Metric::Rmse, Metric::Psnr]).unwrap();
    assert_eq!(v[0].1, 8.0 * c);
    assert_eq!(v[1].1, 20.0 * (peak / (8.0 * c)).log10());
    let fixed = CompareSettings {
        peak: Peak::Fixed(10.0),
        ..CompareSettings::default()
    };
    let v = compare_images_with(&a8, &b8, &[Metric::Psnr], &fixed).unwrap();
    assert_eq!(v[0].1, 20.0 * (10.0 / (8.0 * c)).log10());
}

#[test]
fn png_folders_compare_by_name() {
    let (ref_dir, test_dir) = (scratch("png-ref"), scratch("png-test"));
    let clamp = ToneMap {
        exposure_ev: 0.0,
        curve: ToneCurve::Clamp,
    };
    let a = random_image(3);
    a.write(&ref_dir.join("f.png"), &clamp).unwrap();
    a.write(&test_dir.join("f.png"), &clamp).unwrap();
    let b = random_image(4);
    a.write(&ref_dir.join("g.png"), &clamp).unwrap();
    b.write(&test_dir.join("g.png"), &clamp).unwrap();
    let c = compare_folders(
        &ref_dir,
        &test_dir,
        &[Metric::Rmse, Metric::Flip],
        &CompareSettings::default(),
    )
    .unwrap();
    assert_eq!(c.files.len(), 2);
    assert_eq!(c.files[0].name, "f.png");
    assert_eq!(
        c.files[0].values,
        vec![(Metric::Rmse, 0.0), (Metric::Flip, 0.0)]
    );
    assert!(
        c.files[1].values[0].1 > 0.1 && c.files[1].values[1].1 > 0.1,
        "{:?}",
        c.files[1]
    );
    let means = c.means().unwrap();
    assert_eq!(means[0].1, c.files[1].values[0].1 / 2.0);
    std::fs::remove_dir_all(&ref_dir).unwrap();
    std::fs::remove_dir_all(&test_dir).unwrap();
}
