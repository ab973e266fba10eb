//! The converged reference's own noise: its cache keeps the mean of its first half of
//! samples, the full image is unchanged by that, and the metric between the two halves
//! predicts the reference's actual error against a far more converged image.

use crate::common::{options_in, temp_dir};
use illume_bench::run::reference_settings;
use illume_bench::{Scenario, Silent, run, write_report};
use illume_core::image::RgbImage;
use illume_metrics::{Metric, compare_images};
use illume_reference::ReferenceRenderer;
use illume_transport::World;

const STILL: &str = r#"
name = "still"
scene = "builtin:cornell-spot"
width = 32
height = 24
times_s = [0.0, 0.5]
metrics = ["rmse", "flip"]

[reference]
spp = 64
equal_time = false

[[technique]]
name = "reference"
work = 1
"#;

fn rmse(a: &RgbImage, b: &RgbImage) -> f64 {
    compare_images(a, b, &[Metric::Rmse]).unwrap()[0].1
}

#[test]
fn halves_are_stored_and_their_difference_predicts_the_references_error() {
    let root = temp_dir("halves");
    let scenario = Scenario::parse(STILL, &root.join("still.toml")).unwrap();
    let options = options_in(&root, false);
    let outcome = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!(outcome.cache_renders, 1, "one still state");
    let key = &outcome.reference_keys[0];
    let cache = illume_bench::ReferenceCache::new(&options.cache_dir);
    let full = RgbImage::read(&cache.path(key)).unwrap();
    let half = RgbImage::read(&cache.half_path(key)).unwrap();

    // Keeping the half changes nothing: the full image is the one-go render's, bit for
    // bit, and the half is the one-go render of half the samples.
    let world = World::new(scenario.load_scene().unwrap());
    let render = |spp: u32, seed: u64| {
        let mut settings = reference_settings(&scenario);
        settings.spp = spp;
        settings.seed = seed;
        let mut r = ReferenceRenderer::new(settings, scenario.width, scenario.height);
        r.add_samples(&world, spp);
        r.images().full
    };
    assert_eq!(full.pixels(), render(64, 0).pixels(), "full image changed");
    assert_eq!(half.pixels(), render(32, 0).pixels(), "half is not 32 spp");

    // Both frames show the one state and get its noise.
    let noise: Vec<_> = outcome
        .reference_noise
        .iter()
        .map(|n| n.clone().unwrap())
        .collect();
    assert_eq!(noise[0], noise[1]);
    let halves_rmse = noise[0][0].1;
    assert_eq!(noise[0][0].0, Metric::Rmse);
    // RMSE between halves is 2σ of the full mean; the full image's error against an
    // independent 1 024-spp render is √(σ² + σ²/16) ≈ 1.03σ.
    let actual = rmse(&full, &render(1024, 1));
    let predicted = halves_rmse / 2.0;
    assert!(
        (0.75..1.33).contains(&(predicted / actual)),
        "halves predict RMSE {predicted:.5}, actual {actual:.5}"
    );
    let summary = outcome.reference_noise_summary();
    assert_eq!(summary.len(), 2);
    assert_eq!((summary[0].0, summary[0].3), (Metric::Rmse, 2));
    let report = write_report(&scenario, &outcome, &options).unwrap();
    let md = std::fs::read_to_string(&report.report_md).unwrap();
    assert!(md.contains("## The converged reference's own noise"));
    assert!(md.contains("(32 spp each)"), "{md}");

    // A cache hit reads the same halves back.
    let again = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!((again.cache_hits, again.cache_renders), (1, 0));
    assert_eq!(again.reference_noise, outcome.reference_noise);

    // An image cached without its half (an older cache) is still used, and the report
    // says the noise was not measured.
    std::fs::remove_file(cache.half_path(key)).unwrap();
    let old = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!(old.cache_hits, 1);
    assert!(old.reference_noise.iter().all(Option::is_none));
    assert!(old.reference_noise_summary().is_empty());
    let report = write_report(&scenario, &old, &options).unwrap();
    let md = std::fs::read_to_string(&report.report_md).unwrap();
    assert!(md.contains("Not measured"), "{md}");
    let _ = std::fs::remove_dir_all(&root);
}
