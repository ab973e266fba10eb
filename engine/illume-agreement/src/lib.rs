//! The reference-agreement harness, a dev-only library: each technique's own test renders
//! its converged indirect light on `builtin:cornell-spot` through the engine (the same
//! path as the CLI) and compares it with the reference path tracer's indirect-only light
//! at the same G-buffer points, under the tolerance the technique states beside its code.
//! On failure the test, reference and difference images are written as EXR and named in
//! the message.
//!
//! A technique states the settings that make it converge, its tolerance and why once, in
//! its registration ([`Registration::AGREEMENT`], its `lib.rs`), and joins with one test
//! in its own folder (`tests/NAME/agreement.rs`) that passes
//! [`Agreement::registered`] to [`assert_agrees`] with the lightings to compare under.
//! A variant (another preset, a tighter bound) is an [`Agreement`] built by hand:
//!
//! ```no_run
//! use illume_agreement::{Agreement, Lighting, assert_agrees};
//!
//! let agreement = Agreement {
//!     technique: "reference".into(),
//!     preset: None,
//!     sets: vec!["reference.spp_per_frame=256".into(), "reference.seed=77".into()],
//!     frames: 2,
//!     max_energy_error: 0.02,
//!     max_block_error: 0.06,
//!     why: "another seed of the same estimator: only noise separates the two".into(),
//! };
//! assert_agrees(&agreement, &Lighting::ALL, std::env::temp_dir());
//! ```

use illume_core::Silent;
use illume_core::image::{RgbImage, write_exr};
use illume_engine::{Config, ConfigLayers, Engine, TechniqueKind};
use illume_transport::{Agreement as RegisteredAgreement, Registration, TechniqueSettings};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Width of the compared images [pixels].
pub const WIDTH: u32 = 96;
/// Height of the compared images [pixels].
pub const HEIGHT: u32 = 72;
/// Side of the square blocks whose means the shape error compares [pixels].
pub const BLOCK: u32 = 8;

/// What "agrees with the reference" means for one technique: how to make it converge,
/// the bounds its converged light must keep, and why those bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Agreement {
    /// The technique's name (`--technique NAME`).
    pub technique: String,
    /// `--preset NAME` under the settings, if any; the written images are then named
    /// `<technique>_<preset>`.
    pub preset: Option<String>,
    /// Settings in `--set TABLE.KEY=VALUE` form, applied after the preset, that make the
    /// technique converge.
    pub sets: Vec<String>,
    /// Frames stepped at t = 0 before the indirect image is taken (at least one).
    pub frames: u32,
    /// |mean(test) / mean(reference) − 1| must stay below this (energy).
    pub max_energy_error: f64,
    /// Relative L1 error of 8×8-pixel block means must stay below this (shape).
    pub max_block_error: f64,
    /// Why these bounds: the technique's known bias and noise at these settings.
    pub why: String,
}

impl Agreement {
    /// The agreement a technique registers ([`Registration::AGREEMENT`]): the tolerance
    /// and its reason live once, in the technique's own `lib.rs`. Panics, naming the
    /// technique, when it registers its check as made elsewhere.
    pub fn registered<R: Registration>() -> Self {
        let name = <R::Settings as TechniqueSettings>::NAME;
        match R::AGREEMENT {
            RegisteredAgreement::CornellSpot(spec) => Self {
                technique: name.into(),
                preset: None,
                sets: spec.sets.iter().map(|s| (*s).to_owned()).collect(),
                frames: spec.frames,
                max_energy_error: spec.max_energy_error,
                max_block_error: spec.max_block_error,
                why: spec.why.into(),
            },
            RegisteredAgreement::Elsewhere(why) => {
                panic!("{name} registers its agreement as checked elsewhere: {why}")
            }
        }
    }

    /// The name the images of this comparison are written under (before the lighting's
    /// suffix): the technique, and the preset when there is one.
    pub fn name(&self) -> String {
        match &self.preset {
            Some(preset) => format!("{}_{preset}", self.technique),
            None => self.technique.clone(),
        }
    }

    /// The engine configuration of this agreement at [`WIDTH`] × [`HEIGHT`].
    ///
    /// Panics naming the technique when the name, preset or a setting is refused.
    pub fn config(&self) -> Config {
        let kind: TechniqueKind = self
            .technique
            .parse()
            .unwrap_or_else(|e| panic!("agreement: {e}"));
        let mut c = Config::layered(&ConfigLayers {
            technique: Some(kind),
            preset: self.preset.as_deref(),
            sets: &self.sets,
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{}: {e}", self.technique));
        c.render.width = WIDTH;
        c.render.height = HEIGHT;
        c
    }
}

impl Agreement {
    /// The reference path tracer as the ground truth: 512 spp (two frames of 256),
    /// seed 1.
    pub fn ground_truth() -> Self {
        Self {
            technique: "reference".into(),
            preset: None,
            sets: vec![
                "reference.spp_per_frame=256".into(),
                "reference.seed=1".into(),
            ],
            frames: 2,
            max_energy_error: 0.0,
            max_block_error: 0.0,
            why: "the ground truth".into(),
        }
    }
}

/// The scenes every technique is compared on: `builtin:cornell-spot` as it is, and with
/// a uniform sky (light entering through the open front; sky photons, sky NEE).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lighting {
    /// The spot light alone.
    Spot,
    /// The spot light and a uniform sky of radiance (0.3, 0.4, 0.6) W/(m²·sr).
    SpotAndSky,
}

impl Lighting {
    /// Both lightings, the spot alone first.
    pub const ALL: [Lighting; 2] = [Lighting::Spot, Lighting::SpotAndSky];

    /// The suffix of the images written for this lighting (`""` or `"_sky"`).
    pub fn suffix(self) -> &'static str {
        match self {
            Lighting::Spot => "",
            Lighting::SpotAndSky => "_sky",
        }
    }
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

/// The indirect image of `config` under `lighting` after `frames` frames at t = 0.
pub fn indirect(lighting: Lighting, config: &Config, frames: u32) -> RgbImage {
    indirect_of(scene(lighting), config, frames)
}

/// The indirect image of `config` in `scene` (any scene: a technique's own checks beyond
/// the shared lightings) after `frames` frames at t = 0.
pub fn indirect_of(scene: illume_scene::Scene, config: &Config, frames: u32) -> RgbImage {
    indirect_at(scene, config, frames, 0.0)
}

/// [`indirect_of`] at scene time `t` \[s\] (e.g. a sunlit hour of `builtin:sun-room`,
/// whose time is seconds since local midnight).
pub fn indirect_at(scene: illume_scene::Scene, config: &Config, frames: u32, t: f64) -> RgbImage {
    let mut engine = Engine::new(scene, config).unwrap_or_else(|e| panic!("{e}"));
    engine
        .precompute(&mut Silent)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut image = None;
    for _ in 0..frames.max(1) {
        image = Some(
            engine
                .step(t)
                .unwrap_or_else(|e| panic!("{e}"))
                .frame
                .indirect,
        );
    }
    image.expect("at least one frame")
}

/// The reference's indirect light under `lighting` at the engine's G-buffer points,
/// 512 spp (seed 1), rendered once per process.
///
/// Panics if it is black, or if the sky does not add light (more than 20 %) to the
/// spot's: a comparison against those would prove nothing.
pub fn reference(lighting: Lighting) -> &'static RgbImage {
    static SPOT: OnceLock<RgbImage> = OnceLock::new();
    static SKY: OnceLock<RgbImage> = OnceLock::new();
    let render = || {
        let reference = Agreement::ground_truth();
        indirect(lighting, &reference.config(), reference.frames)
    };
    match lighting {
        Lighting::Spot => {
            let image = SPOT.get_or_init(render);
            assert!(
                image.mean().element_sum() > 0.0,
                "the reference's indirect light is black"
            );
            image
        }
        Lighting::SpotAndSky => {
            let image = SKY.get_or_init(render);
            let dark = reference(Lighting::Spot);
            assert!(
                image.mean().element_sum() > 1.2 * dark.mean().element_sum(),
                "the sky adds indirect light: {} vs {}",
                image.mean(),
                dark.mean()
            );
            image
        }
    }
}

/// Checks that `--preset paper` is the paper (issue 35) and returns it: the technique
/// has a `paper` preset that passes its checks, every `(key, holds_the_papers_value)` of
/// `paper_values` (the technique's own list of its departures from the paper) holds in
/// it, and every setting whose documentation says "beyond the paper" is in that list, so
/// a new departure cannot be added without the preset and its test knowing of it.
pub fn assert_paper_preset<S>(paper_values: fn(&S) -> Vec<(&'static str, bool)>) -> S
where
    S: TechniqueSettings + illume_transport::SettingsTable,
{
    let paper = S::preset("paper").expect("a `paper` preset");
    if let Err(e) = paper.check() {
        panic!("the `paper` preset is refused: {e}");
    }
    let values = paper_values(&paper);
    for (key, is_paper) in &values {
        assert!(is_paper, "`paper` keeps `{key}` beyond the paper");
    }
    for field in S::FIELDS {
        if field.doc.to_lowercase().contains("beyond the paper") {
            assert!(
                values.iter().any(|(k, _)| *k == field.key),
                "`{}` is documented as beyond the paper but the paper preset's list does \
                 not cover it",
                field.key
            );
        }
    }
    paper
}

/// Glossy receivers (issue 34 goal 4): the mean indirect radiance (sum of channels) over
/// the metal pixels of `builtin:metal-box` — a white room whose sphere (roughness 0.3)
/// and tall box (0.6) are white metals — in `config`'s image after `frames` frames, over
/// the reference's at the same pixels (512 spp, seed 1, rendered once per process). An
/// irradiance-storing technique that lights a metal as Lambertian shows it ≈ 10–20 % too
/// bright there, one that reflects by the BRDF's directional albedo within a few
/// percent.
pub fn metal_box_metals_ratio(config: &Config, frames: u32) -> f64 {
    static REFERENCE: OnceLock<f64> = OnceLock::new();
    let scene = || illume_scene::builtin::load("metal-box").expect("built-in scene");
    let metals: &'static [bool] = {
        static MASK: OnceLock<Vec<bool>> = OnceLock::new();
        MASK.get_or_init(|| {
            let world = illume_transport::World::new(scene());
            illume_transport::GBuffer::rasterize(&world, WIDTH, HEIGHT)
                .pixels
                .iter()
                .map(|p| p.is_some_and(|p| p.hit.metallic > 0.5))
                .collect()
        })
    };
    let mean = |img: &RgbImage| {
        let (sum, n) = img
            .pixels()
            .iter()
            .zip(metals)
            .filter(|(_, m)| **m)
            .fold((0.0, 0u32), |(s, n), (p, _)| {
                (s + p.element_sum() as f64, n + 1)
            });
        assert!(n > 100, "metal-box shows {n} metal pixels");
        sum / n as f64
    };
    let reference = *REFERENCE.get_or_init(|| {
        let reference = Agreement::ground_truth();
        mean(&indirect_of(scene(), &reference.config(), reference.frames))
    });
    assert!(reference > 0.0, "the reference lights the metals");
    mean(&indirect_of(scene(), config, frames)) / reference
}

/// Relative L1 error of block means (shared metric, `illume_metrics::block_error`).
pub fn block_error(img: &RgbImage, reference: &RgbImage) -> f64 {
    illume_metrics::block_error(reference, img, BLOCK).expect("same sizes")
}

/// mean(img) / mean(reference) − 1, over the sum of the channels.
pub fn energy_error(img: &RgbImage, reference: &RgbImage) -> f64 {
    img.mean().element_sum() as f64 / reference.mean().element_sum() as f64 - 1.0
}

/// Compares `test` with `reference` under the tolerance of `a`: `Ok` with a one-line
/// summary when both errors stay below their bounds; otherwise writes the three EXRs as
/// `<dir>/<name>_{test,reference,difference}.exr` and returns the message naming them.
pub fn compare(
    name: &str,
    test: &RgbImage,
    reference: &RgbImage,
    a: &Agreement,
    dir: &Path,
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
        test.width(),
        test.height(),
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

/// Where a test binary's failing comparisons are written: `reference_agreement` under
/// `target_tmp_dir` (pass `env!("CARGO_TARGET_TMPDIR")`).
pub fn output_dir(target_tmp_dir: impl AsRef<Path>) -> PathBuf {
    target_tmp_dir.as_ref().join("reference_agreement")
}

/// Renders the technique of `a` under each of `lightings`, compares it with
/// [`reference`] and panics with the messages of [`compare`] (which name the written
/// images) and `a.why` when it does not agree under one or more; prints the summaries
/// when it does.
///
/// The images are named `<name>` ([`Agreement::name`]) plus the lighting's suffix and
/// written under [`output_dir`]`(target_tmp_dir)`.
pub fn assert_agrees(a: &Agreement, lightings: &[Lighting], target_tmp_dir: impl AsRef<Path>) {
    let dir = output_dir(target_tmp_dir);
    let mut failures = Vec::new();
    for &lighting in lightings {
        let reference = reference(lighting);
        let img = indirect(lighting, &a.config(), a.frames);
        let name = format!("{}{}", a.name(), lighting.suffix());
        match compare(&name, &img, reference, a, &dir) {
            Ok(summary) => eprintln!("{summary}"),
            Err(failure) => failures.push(failure),
        }
    }
    assert!(
        failures.is_empty(),
        "{}\n{}'s tolerance: {}",
        failures.join("\n"),
        a.name(),
        a.why
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failing_comparison_writes_and_names_its_three_images() {
        let reference = reference(Lighting::Spot);
        // photon_stream with 2 000 photons against an impossible tolerance.
        let strict = Agreement {
            technique: "photon_stream".into(),
            preset: None,
            sets: vec![
                "photon_stream.mode=deterministic".into(),
                "photon_stream.photons_per_frame=2000".into(),
                "photon_stream.warm_up=false".into(),
            ],
            frames: 1,
            max_energy_error: 0.0,
            max_block_error: 0.0,
            why: "made to fail".into(),
        };
        let img = indirect(Lighting::Spot, &strict.config(), strict.frames);
        // A unit test has no CARGO_TARGET_TMPDIR: the system's temporary folder.
        let tmp = std::env::temp_dir().join(format!("illume-agreement-{}", std::process::id()));
        let dir = output_dir(tmp).join("made_to_fail");
        let _ = std::fs::remove_dir_all(&dir);
        let message = compare("photon_stream", &img, reference, &strict, &dir)
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
            assert_eq!((back.width(), back.height()), (WIDTH, HEIGHT));
        }
    }
}
