//! LDR-FLIP and HDR-FLIP against NVIDIA's reference implementation.
//!
//! The cases below are small deterministic images (64×64, PCG-seeded). The expected mean
//! errors were produced once, offline, by the reference implementation — the PyPI package
//! `flip-evaluator` 1.7 — with:
//!
//! ```text
//! pip install flip-evaluator==1.7
//! ILLUME_FLIP_FIXTURE_DIR=/tmp/flip-fixtures \
//!   cargo test -p illume-metrics --test illume_metrics -- --ignored write_flip_fixtures
//! python3 crates/illume-metrics/tests/flip_reference.py /tmp/flip-fixtures
//! ```
//!
//! The script reads `manifest.txt` (written by `write_flip_fixtures`), evaluates each
//! pair from the files with `flip_evaluator.evaluate`, and prints the `EXPECTED` table
//! below. Running these tests needs no Python.

use illume_core::Rgb;
use illume_core::image::{RgbImage, write_exr};
use illume_core::sampling::{Pcg32, SampleStream};
use illume_metrics::flip::{FlipSettings, FlipToneMapper, hdr_flip, ldr_flip};
use std::path::Path;

const SIZE: u32 = 64;

/// Agreement required with the reference implementation, for the mean and for single
/// pixels. The measured disagreement is below 2e-6 (float rounding); 1e-4 leaves room for
/// other platforms' `libm` and still catches any real difference in the method.
const TOLERANCE: f64 = 1e-4;

/// Pixels `(x, y)` whose errors are checked one by one (corners exercise the clamped
/// borders of the filters).
const SAMPLE_PIXELS: [(u32, u32); 4] = [(0, 0), (31, 20), (63, 63), (10, 50)];

/// What the reference implementation computed for one case.
struct Expected {
    name: &'static str,
    /// Mean FLIP.
    mean: f64,
    /// Largest per-pixel FLIP.
    max: f64,
    /// Per-pixel FLIP at [`SAMPLE_PIXELS`].
    samples: [f64; 4],
    /// HDR-FLIP's automatic exposure bracket: (start, stop, count).
    exposures: Option<(f32, f32, u32)>,
}

/// The reference implementation's results, printed by `flip_reference.py` (see the
/// module docs).
#[rustfmt::skip]
const EXPECTED: &[Expected] = &[
    Expected { name: "ldr_gradient_noise", mean: 0.1226666, max: 0.4064708, samples: [0.1214708, 0.1305383, 0.3056737, 0.0638491], exposures: None },
    Expected { name: "ldr_gradient_noise_ppd30", mean: 0.2289893, max: 0.5558790, samples: [0.1308359, 0.3075932, 0.3179933, 0.2546426], exposures: None },
    Expected { name: "ldr_checker_shift", mean: 0.2221520, max: 0.8370089, samples: [0.0455524, 0.4160519, 0.8370089, 0.1455911], exposures: None },
    Expected { name: "ldr_blocks_blur", mean: 0.1773107, max: 0.5618722, samples: [0.0114465, 0.0986730, 0.0069437, 0.2253028], exposures: None },
    Expected { name: "hdr_gradient_noise", mean: 0.0806090, max: 0.2371700, samples: [0.0591331, 0.1299106, 0.0937904, 0.0896788], exposures: Some((-4.841882, 0.552255, 6)) },
    Expected { name: "hdr_gradient_noise_reinhard", mean: 0.0998836, max: 0.2577642, samples: [0.0835892, 0.1482677, 0.1359216, 0.0790930], exposures: Some((-3.422678, 1.971459, 6)) },
    Expected { name: "hdr_window", mean: 0.0632609, max: 0.7096941, samples: [0.0521674, 0.1216437, 0.1646341, 0.0417755], exposures: Some((-6.015851, 3.853763, 10)) },
    Expected { name: "hdr_window_hable", mean: 0.0559272, max: 0.7148299, samples: [0.0437964, 0.1673525, 0.1409700, 0.0365210], exposures: Some((-5.454023, 4.415591, 10)) },
];

/// An 8-bit sRGB image as bytes (RGB, row-major).
struct Srgb8 {
    bytes: Vec<u8>,
}

impl Srgb8 {
    fn from_fn(f: impl Fn(u32, u32) -> [f32; 3]) -> Self {
        let mut bytes = Vec::with_capacity((SIZE * SIZE * 3) as usize);
        for y in 0..SIZE {
            for x in 0..SIZE {
                bytes.extend(f(x, y).map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8));
            }
        }
        Self { bytes }
    }

    fn get(&self, x: u32, y: u32) -> [f32; 3] {
        let i = ((y.min(SIZE - 1) * SIZE + x.min(SIZE - 1)) * 3) as usize;
        [0, 1, 2].map(|c| self.bytes[i + c] as f32 / 255.0)
    }

    fn write(&self, path: &Path) {
        image::save_buffer(path, &self.bytes, SIZE, SIZE, image::ColorType::Rgb8).unwrap();
    }
}

fn linear_from_fn(f: impl Fn(u32, u32) -> Rgb) -> RgbImage {
    let mut img = RgbImage::black(SIZE, SIZE);
    for y in 0..SIZE {
        for x in 0..SIZE {
            *img.get_mut(x, y) = f(x, y);
        }
    }
    img
}

/// Uniform noise in [−1, 1) per pixel and channel, a pure function of (seed, x, y, c).
fn noise(seed: u64, x: u32, y: u32, c: u32) -> f32 {
    let mut rng = Pcg32::new(seed, ((y * SIZE + x) * 3 + c) as u64);
    2.0 * rng.next_1d() - 1.0
}

fn ldr_gradient() -> Srgb8 {
    Srgb8::from_fn(|x, y| [x as f32 / 63.0, y as f32 / 63.0, 0.5])
}

fn ldr_gradient_noisy() -> Srgb8 {
    let g = ldr_gradient();
    Srgb8::from_fn(|x, y| {
        let p = g.get(x, y);
        [0, 1, 2].map(|c| p[c as usize] + 0.1 * noise(1, x, y, c))
    })
}

fn ldr_checker(shift: u32, second: [f32; 3]) -> Srgb8 {
    Srgb8::from_fn(|x, y| {
        if ((x + shift) / 8 + y / 8) & 1 == 0 {
            [0.8, 0.15, 0.15]
        } else {
            second
        }
    })
}

/// 8×8-pixel blocks of PCG-random colours.
fn ldr_blocks() -> Srgb8 {
    Srgb8::from_fn(|x, y| [0, 1, 2].map(|c| 0.5 + 0.5 * noise(2, x / 8, y / 8, c)))
}

/// 3×3 box blur of `img` (edges clamped).
fn ldr_blurred(img: &Srgb8) -> Srgb8 {
    Srgb8::from_fn(|x, y| {
        let mut sum = [0.0f32; 3];
        for dy in 0..3 {
            for dx in 0..3 {
                let p = img.get((x + dx).saturating_sub(1), (y + dy).saturating_sub(1));
                (0..3).for_each(|c| sum[c] += p[c] / 9.0);
            }
        }
        sum
    })
}

/// Radiance spanning 10 stops left to right, tinted top to bottom.
fn hdr_gradient() -> RgbImage {
    linear_from_fn(|x, y| {
        let l = 2f32.powf(-4.0 + 10.0 * x as f32 / 63.0);
        l * Rgb::new(1.0, 0.4 + 0.6 * y as f32 / 63.0, 0.3)
    })
}

fn hdr_gradient_noisy() -> RgbImage {
    let g = hdr_gradient();
    linear_from_fn(|x, y| {
        let p = *g.get(x, y);
        Rgb::new(
            p.x * (1.0 + 0.2 * noise(3, x, y, 0)),
            p.y * (1.0 + 0.2 * noise(3, x, y, 1)),
            p.z * (1.0 + 0.2 * noise(3, x, y, 2)),
        )
    })
}

/// A dim, slightly textured room with a small very bright "window".
fn hdr_window(window: f32, offset: u32, noise_amount: f32) -> RgbImage {
    linear_from_fn(|x, y| {
        let inside = (28 + offset..34 + offset).contains(&x) && (20..26).contains(&y);
        if inside {
            Rgb::new(window, window * 0.9, window * 0.8)
        } else {
            let base = 0.05 + 0.25 * (y as f32 / 63.0);
            Rgb::new(
                base * (1.0 + noise_amount * noise(4, x, y, 0)),
                base * 0.8 * (1.0 + noise_amount * noise(4, x, y, 1)),
                base * 0.6 * (1.0 + noise_amount * noise(4, x, y, 2)),
            )
        }
    })
}

/// One comparison: how to evaluate it and the two images.
struct Case {
    name: &'static str,
    ppd: Option<f32>,
    tone_mapper: Option<FlipToneMapper>,
    images: Images,
}

enum Images {
    Ldr(Srgb8, Srgb8),
    Hdr(RgbImage, RgbImage),
}

fn cases() -> Vec<Case> {
    let ldr = |name, ppd, r, t| Case {
        name,
        ppd,
        tone_mapper: None,
        images: Images::Ldr(r, t),
    };
    let hdr = |name, tone_mapper, r, t| Case {
        name,
        ppd: None,
        tone_mapper,
        images: Images::Hdr(r, t),
    };
    vec![
        ldr(
            "ldr_gradient_noise",
            None,
            ldr_gradient(),
            ldr_gradient_noisy(),
        ),
        ldr(
            "ldr_gradient_noise_ppd30",
            Some(30.0),
            ldr_gradient(),
            ldr_gradient_noisy(),
        ),
        ldr(
            "ldr_checker_shift",
            None,
            ldr_checker(0, [0.1, 0.1, 0.6]),
            ldr_checker(1, [0.15, 0.1, 0.55]),
        ),
        ldr(
            "ldr_blocks_blur",
            None,
            ldr_blocks(),
            ldr_blurred(&ldr_blocks()),
        ),
        hdr(
            "hdr_gradient_noise",
            None,
            hdr_gradient(),
            hdr_gradient_noisy(),
        ),
        hdr(
            "hdr_gradient_noise_reinhard",
            Some(FlipToneMapper::Reinhard),
            hdr_gradient(),
            hdr_gradient_noisy(),
        ),
        hdr(
            "hdr_window",
            None,
            hdr_window(150.0, 0, 0.0),
            hdr_window(120.0, 1, 0.1),
        ),
        hdr(
            "hdr_window_hable",
            Some(FlipToneMapper::Hable),
            hdr_window(150.0, 0, 0.0),
            hdr_window(120.0, 1, 0.1),
        ),
    ]
}

/// Writes each case's reference and test to `dir`, plus `manifest.txt`
/// (`name kind reference test width height ppd tone_mapper`, `-` for defaults). Returns
/// the file paths. HDR images are written twice: as EXR for the Rust side and as raw
/// little-endian `f32` RGB (row-major, no header) for the Python side, because the
/// reference package's EXR loader (tinyexr) crashes on the EXR files the `exr` crate
/// writes. The two hold the same floats bit for bit.
fn write_cases(dir: &Path) -> Vec<(Case, std::path::PathBuf, std::path::PathBuf)> {
    std::fs::create_dir_all(dir).unwrap();
    let mut manifest = String::new();
    let mut out = Vec::new();
    for case in cases() {
        let (kind, ext) = match case.images {
            Images::Ldr(..) => ("ldr", "png"),
            Images::Hdr(..) => ("hdr", "exr"),
        };
        let r = dir.join(format!("{}_ref.{ext}", case.name));
        let t = dir.join(format!("{}_test.{ext}", case.name));
        let (python_r, python_t) = match &case.images {
            Images::Ldr(a, b) => {
                a.write(&r);
                b.write(&t);
                (r.clone(), t.clone())
            }
            Images::Hdr(a, b) => {
                write_exr(a, &r).unwrap();
                write_exr(b, &t).unwrap();
                let (raw_r, raw_t) = (r.with_extension("f32"), t.with_extension("f32"));
                write_raw_f32(a, &raw_r);
                write_raw_f32(b, &raw_t);
                (raw_r, raw_t)
            }
        };
        manifest.push_str(&format!(
            "{} {kind} {} {} {SIZE} {SIZE} {} {}\n",
            case.name,
            python_r.file_name().unwrap().to_str().unwrap(),
            python_t.file_name().unwrap().to_str().unwrap(),
            case.ppd.map_or("-".to_owned(), |p| p.to_string()),
            case.tone_mapper.map_or("-", |m| m.name()),
        ));
        out.push((case, r, t));
    }
    std::fs::write(dir.join("manifest.txt"), manifest).unwrap();
    out
}

/// Raw little-endian `f32` RGB, row-major.
fn write_raw_f32(img: &RgbImage, path: &Path) {
    let bytes: Vec<u8> = img
        .pixels()
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    std::fs::write(path, bytes).unwrap();
}

/// Writes the fixtures for `flip_reference.py` into `$ILLUME_FLIP_FIXTURE_DIR` (default:
/// `illume-flip-fixtures` in the temporary directory).
#[test]
#[ignore = "writes the fixtures for the offline reference run; see the module docs"]
fn write_flip_fixtures() {
    let dir = std::env::var_os("ILLUME_FLIP_FIXTURE_DIR").map_or_else(
        || std::env::temp_dir().join("illume-flip-fixtures"),
        Into::into,
    );
    write_cases(&dir);
    println!("FLIP fixtures written to {}", dir.display());
}

#[test]
fn flip_matches_reference_implementation() {
    let dir = std::env::temp_dir().join(format!("illume-flip-reference-{}", std::process::id()));
    let mut report = String::new();
    let mut worst = 0.0f64;
    for (case, r, t) in write_cases(&dir) {
        let expected = EXPECTED
            .iter()
            .find(|e| e.name == case.name)
            .expect("every case has a reference value");
        // Read the files back as a user would: PNG decoded to linear, EXR as is.
        let reference = RgbImage::read(&r).unwrap();
        let test = RgbImage::read(&t).unwrap();
        let mut settings = FlipSettings::default();
        if let Some(ppd) = case.ppd {
            settings.pixels_per_degree = ppd;
        }
        if let Some(tm) = case.tone_mapper {
            settings.tone_mapper = tm;
        }
        let map = match case.images {
            Images::Ldr(..) => ldr_flip(&reference, &test, &settings).unwrap(),
            Images::Hdr(..) => {
                let hdr = hdr_flip(&reference, &test, &settings).unwrap();
                let (start, stop, count) = expected
                    .exposures
                    .expect("HDR cases record their exposures");
                assert!(
                    (hdr.exposures.start_ev - start).abs() < 1e-4,
                    "{}: {:?}",
                    case.name,
                    hdr.exposures
                );
                assert!(
                    (hdr.exposures.stop_ev - stop).abs() < 1e-4,
                    "{}: {:?}",
                    case.name,
                    hdr.exposures
                );
                assert_eq!(hdr.exposures.count, count, "{}", case.name);
                hdr.map
            }
        };
        let ours_max = map.errors.pixels().iter().copied().fold(0.0f32, f32::max) as f64;
        let ours_samples = SAMPLE_PIXELS.map(|(x, y)| *map.errors.get(x, y) as f64);
        report.push_str(&format!(
            "{:28} mean {:.7} (reference {:.7})  max {:.7} ({:.7})  samples {ours_samples:.7?} ({:.7?})\n",
            case.name,
            map.mean(),
            expected.mean,
            ours_max,
            expected.max,
            expected.samples
        ));
        worst = worst
            .max((map.mean() - expected.mean).abs())
            .max((ours_max - expected.max).abs());
        for (ours, theirs) in ours_samples.iter().zip(expected.samples) {
            worst = worst.max((ours - theirs).abs());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
    println!("{report}largest difference to the reference: {worst:.2e}");
    assert!(
        worst <= TOLERANCE,
        "FLIP disagrees with the reference by {worst:.2e}:\n{report}"
    );
}
