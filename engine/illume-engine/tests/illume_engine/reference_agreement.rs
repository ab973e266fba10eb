//! The shared reference-agreement harness: every technique of [`TechniqueKind::ALL`]
//! renders its converged indirect light on `builtin:cornell-spot` through the engine
//! (the same path as the CLI), and it is compared with the reference path tracer's
//! indirect-only light at the same G-buffer points, under the technique's stated
//! tolerance. On failure the test, reference and difference images are written as EXR
//! next to the test output and named in the message.
//!
//! A new technique joins by adding its arm to [`agreement`]: the settings that make it
//! converge, and its tolerance with the reason for it.

use illume_core::Silent;
use illume_core::image::{RgbImage, write_exr};
use illume_engine::{Config, ConfigLayers, Engine, TechniqueKind};
use std::path::PathBuf;
use std::sync::OnceLock;

const W: u32 = 96;
const H: u32 = 72;
const BLOCK: u32 = 8;

/// What "agrees" means for one technique.
struct Agreement {
    /// Settings (`--set` form) that make the technique converge.
    sets: &'static [&'static str],
    /// Frames stepped at t = 0 before the indirect image is taken.
    frames: u32,
    /// |mean(test) / mean(reference) − 1| must stay below this (energy).
    max_energy_error: f64,
    /// Relative L1 error of 8×8-pixel block means must stay below this (shape).
    max_block_error: f64,
}

/// Each technique's converged settings and tolerance, with the reason.
fn agreement(kind: TechniqueKind) -> Agreement {
    match kind {
        // Another seed of the same estimator, 512 spp: only noise separates the two.
        // The reference's own block noise at 512 spp is ≈ 0.02 (two independent
        // halves, photon_stream/tests/reference.rs), its energy noise well below 1 %.
        TechniqueKind::Reference => Agreement {
            sets: &["reference.spp_per_frame=256", "reference.seed=77"],
            frames: 2,
            max_energy_error: 0.02,
            max_block_error: 0.06,
        },
        // The paper's approximations are biased (100 VSLs for 27 m² of surface, one
        // normal per VSL, no VSL visibility: over-illumination behind occluders);
        // measured +6 % energy and 0.25 block error (docs/techniques/photon_stream.md).
        TechniqueKind::PhotonStream => Agreement {
            sets: &[
                "photon_stream.mode=deterministic",
                "photon_stream.pool_size=1000000",
                "photon_stream.photons_per_frame=400000",
                "photon_stream.warm_up=false",
            ],
            frames: 1,
            max_energy_error: 0.15,
            max_block_error: 0.32,
        },
        // Every photon of a 1.15 M pool (N_g = 72, N_p = 1000, R = 16) bucketed in
        // 12 400 elements: unbiased up to element-scale blur (irradiance constant per
        // element, Gouraud-smoothed) and the element noise of ≈ 90 impacts per element.
        // Issue 10's bounds: energy ±5 %, block error ≤ 0.15.
        TechniqueKind::Selective => Agreement {
            sets: &[
                "selective.mode=deterministic",
                "selective.pilots_per_group=1000",
            ],
            frames: 1,
            max_energy_error: 0.05,
            max_block_error: 0.15,
        },
        // per_frame, the paper's values (a = 0.2, 64×64 rays per record, R_k clamped
        // to [1 %, 50 %] of the scene diagonal and to E/|∇_p E|): consistent up to
        // interpolation between records (Eq. 1 with Ward–Heckbert gradients) and each
        // record's gather noise (4096 rays, Russian roulette after 3 bounces), which
        // the interpolation spreads over its sphere of influence as smooth blotches.
        // Measured +0.6 % energy and 0.016 block error (sky: +0.2 %, 0.011); the bounds
        // leave room for other seeds and the reference's own noise (block ≈ 0.006).
        TechniqueKind::RadianceCache => Agreement {
            sets: &["radiance_cache.temporal=per_frame"],
            frames: 1,
            max_energy_error: 0.03,
            max_block_error: 0.06,
        },
        // Needs a scene with a sun path and a precomputed day; cornell-spot has neither.
        // Its agreement test is techniques/precomputed/tests/sun_room.rs.
        TechniqueKind::Precomputed => unreachable!("excluded by on_cornell_spot()"),
    }
}

/// The techniques this harness runs on `builtin:cornell-spot`: all but `precomputed`,
/// which needs a `[sun]` (see its own test on `builtin:sun-room`).
fn on_cornell_spot() -> impl Iterator<Item = TechniqueKind> {
    TechniqueKind::ALL
        .iter()
        .copied()
        .filter(|k| *k != TechniqueKind::Precomputed)
}

fn config(kind: TechniqueKind, sets: &[&str]) -> Config {
    config_preset(kind, None, sets)
}

/// [`config`] on top of the named preset.
fn config_preset(kind: TechniqueKind, preset: Option<&str>, sets: &[&str]) -> Config {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let mut c = Config::layered(&ConfigLayers {
        technique: Some(kind),
        preset,
        sets: &sets,
        ..Default::default()
    })
    .unwrap_or_else(|e| panic!("{kind}: {e}"));
    c.render.width = W;
    c.render.height = H;
    c
}

/// The scenes every technique is compared on: `builtin:cornell-spot` as it is, and with
/// a uniform sky (light entering through the open front; sky photons, sky NEE).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lighting {
    Spot,
    SpotAndSky,
}

fn scene(lighting: Lighting) -> illume_scene::Scene {
    let mut scene = illume_scene::builtin::load("cornell-spot").expect("built-in scene");
    if lighting == Lighting::SpotAndSky {
        scene.sky = Some(illume_scene::Sky::Uniform {
            radiance: illume_core::Rgb::new(0.3, 0.4, 0.6),
        });
    }
    scene
}

/// The technique's indirect image after `frames` frames at t = 0.
fn indirect(kind: TechniqueKind, sets: &[&str], frames: u32) -> RgbImage {
    indirect_in(Lighting::Spot, kind, sets, frames)
}

/// [`indirect`] under `lighting`.
fn indirect_in(lighting: Lighting, kind: TechniqueKind, sets: &[&str], frames: u32) -> RgbImage {
    indirect_with(lighting, &config(kind, sets), frames)
}

/// The indirect image of `config` under `lighting` after `frames` frames at t = 0.
fn indirect_with(lighting: Lighting, config: &Config, frames: u32) -> RgbImage {
    let scene = scene(lighting);
    let mut engine = Engine::new(scene, config).unwrap_or_else(|e| panic!("{e}"));
    engine
        .precompute(&mut Silent)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut image = None;
    for _ in 0..frames.max(1) {
        image = Some(
            engine
                .step(0.0)
                .unwrap_or_else(|e| panic!("{e}"))
                .frame
                .indirect,
        );
    }
    image.expect("at least one frame")
}

/// The reference's indirect light at the engine's G-buffer points, 512 spp.
fn reference() -> &'static RgbImage {
    static REFERENCE: OnceLock<RgbImage> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        indirect(
            TechniqueKind::Reference,
            &["reference.spp_per_frame=256", "reference.seed=1"],
            2,
        )
    })
}

/// Relative L1 error of block means (shared metric, `illume_metrics::block_error`).
fn block_error(img: &RgbImage, reference: &RgbImage) -> f64 {
    illume_metrics::block_error(reference, img, BLOCK).expect("same sizes")
}

fn energy_error(img: &RgbImage, reference: &RgbImage) -> f64 {
    img.mean().element_sum() as f64 / reference.mean().element_sum() as f64 - 1.0
}

/// Compares `test` with `reference` under `a`; on failure writes the three EXRs as
/// `<dir>/<name>_{test,reference,difference}.exr` and returns the message naming them.
fn check(
    name: &str,
    test: &RgbImage,
    reference: &RgbImage,
    a: &Agreement,
    dir: &std::path::Path,
) -> Result<String, String> {
    let (energy, block) = (energy_error(test, reference), block_error(test, reference));
    let summary = format!(
        "{name}: energy {:+.3} (tolerance ±{}), block L1 {block:.3} (tolerance {})",
        energy, a.max_energy_error, a.max_block_error
    );
    if energy.abs() < a.max_energy_error && block < a.max_block_error {
        return Ok(summary);
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{summary}; {}: {e}", dir.display()))?;
    let difference = RgbImage::from_vec(
        W,
        H,
        test.pixels()
            .iter()
            .zip(reference.pixels())
            .map(|(t, r)| *t - *r)
            .collect(),
    )
    .expect("one value per pixel");
    let mut written = Vec::new();
    for (suffix, img) in [
        ("test", test),
        ("reference", reference),
        ("difference", &difference),
    ] {
        let path = dir.join(format!("{name}_{suffix}.exr"));
        write_exr(img, &path).map_err(|e| format!("{summary}; {}: {e}", path.display()))?;
        written.push(path.display().to_string());
    }
    Err(format!("{summary} — wrote {}", written.join(", ")))
}

/// The reference's indirect light of the sky-lit box, 512 spp.
fn sky_reference() -> &'static RgbImage {
    static REFERENCE: OnceLock<RgbImage> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        indirect_in(
            Lighting::SpotAndSky,
            TechniqueKind::Reference,
            &["reference.spp_per_frame=256", "reference.seed=1"],
            2,
        )
    })
}

fn output_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("reference_agreement")
}

#[test]
fn every_technique_agrees_with_the_reference_indirect_light() {
    let reference = reference();
    assert!(
        reference.mean().element_sum() > 0.0,
        "the reference's indirect light is black"
    );
    let mut failures = Vec::new();
    for kind in on_cornell_spot() {
        let a = agreement(kind);
        let img = indirect(kind, a.sets, a.frames);
        match check(kind.name(), &img, reference, &a, &output_dir()) {
            Ok(summary) => eprintln!("{summary}"),
            Err(failure) => failures.push(failure),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The same tolerances with a sky added: every technique carries sky light into its
/// indirect image (photon_stream through sky photons).
#[test]
fn every_technique_agrees_with_the_reference_under_a_sky() {
    let reference = sky_reference();
    let dark = self::reference();
    assert!(
        reference.mean().element_sum() > 1.2 * dark.mean().element_sum(),
        "the sky adds indirect light: {} vs {}",
        reference.mean(),
        dark.mean()
    );
    let mut failures = Vec::new();
    for kind in on_cornell_spot() {
        let a = agreement(kind);
        let img = indirect_in(Lighting::SpotAndSky, kind, a.sets, a.frames);
        let name = format!("{}_sky", kind.name());
        match check(&name, &img, reference, &a, &output_dir()) {
            Ok(summary) => eprintln!("{summary}"),
            Err(failure) => failures.push(failure),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// photon_stream's `still` preset (`illume render`'s default: the whole indirect light
/// gathered over 3200 VSL cells, issue 15) under the tightened tolerance, with and
/// without the sky. What is left is the cells' averaging (each gather hit reads its
/// cell's mean exitance), the gather noise of 576 rays per shaded pixel spread by
/// stride-3 interpolation, and the reference's own noise (block ≈ 0.02). Bounds:
/// energy ±3 % (the target for stills), block L1 < 0.06 (measured +0.8 % and
/// 0.028, sky +0.6 % and 0.019).
#[test]
fn photon_stream_still_preset_agrees_within_the_tightened_tolerance() {
    let a = Agreement {
        sets: &[],
        frames: 1,
        max_energy_error: 0.03,
        max_block_error: 0.06,
    };
    let config = config_preset(TechniqueKind::PhotonStream, Some("still"), a.sets);
    let mut failures = Vec::new();
    for (lighting, reference, name) in [
        (Lighting::Spot, reference(), "photon_stream_still"),
        (
            Lighting::SpotAndSky,
            sky_reference(),
            "photon_stream_still_sky",
        ),
    ] {
        let img = indirect_with(lighting, &config, a.frames);
        match check(name, &img, reference, &a, &output_dir()) {
            Ok(summary) => eprintln!("{summary}"),
            Err(failure) => failures.push(failure),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_failing_comparison_writes_and_names_its_three_images() {
    let reference = reference();
    // photon_stream with 2 000 photons against an impossible tolerance.
    let img = indirect(
        TechniqueKind::PhotonStream,
        &[
            "photon_stream.mode=deterministic",
            "photon_stream.photons_per_frame=2000",
            "photon_stream.warm_up=false",
        ],
        1,
    );
    let strict = Agreement {
        sets: &[],
        frames: 1,
        max_energy_error: 0.0,
        max_block_error: 0.0,
    };
    let dir = output_dir().join("made_to_fail");
    let _ = std::fs::remove_dir_all(&dir);
    let message = check("photon_stream", &img, reference, &strict, &dir)
        .expect_err("a zero tolerance cannot pass");
    for suffix in ["test", "reference", "difference"] {
        let path = dir.join(format!("photon_stream_{suffix}.exr"));
        assert!(path.is_file(), "{} not written", path.display());
        assert!(
            message.contains(&path.display().to_string()),
            "{message} does not name {}",
            path.display()
        );
        let back = illume_core::image::read_exr(&path).unwrap();
        assert_eq!((back.width(), back.height()), (W, H));
    }
}
