//! FLIP, a perceptual difference evaluator for a test image shown alternately with its
//! reference:
//!
//! - **LDR-FLIP**: P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström,
//!   M. D. Fairchild, "FLIP: A Difference Evaluator for Alternating Images", HPG 2020.
//! - **HDR-FLIP**: P. Andersson, J. Nilsson, P. Shirley, T. Akenine-Möller, "Visualizing
//!   Errors in Rendered High Dynamic Range Images", Eurographics 2021.
//!
//! Both produce a per-pixel error in [0, 1]; the mean of that map is the scalar score.
//! The implementation follows the papers and agrees with NVIDIA's reference
//! implementation (the `flip-evaluator` Python package, v1.7) to better than 1e-3 in the
//! mean; see `tests/flip_reference.rs` for the recorded values.
//!
//! LDR-FLIP takes *linear* RGB in [0, 1] (an 8-bit sRGB PNG read by
//! [`illume_core::image::RgbImage::read`] is already decoded to linear); values outside
//! [0, 1] are clamped. HDR-FLIP takes linear radiance, computes LDR-FLIP on a bracket of
//! exposures, each tone mapped, and keeps the per-pixel maximum.
//!
//! ```
//! use illume_core::image::RgbImage;
//! use illume_core::Rgb;
//! use illume_metrics::flip::{ldr_flip, FlipSettings};
//! let reference = RgbImage::filled(16, 16, Rgb::splat(0.5));
//! let map = ldr_flip(&reference, &reference, &FlipSettings::default()).unwrap();
//! assert_eq!(map.mean(), 0.0);
//! ```

mod color;
mod magma;

use crate::error::{MetricsError, check_not_empty, check_same_size};
use color::{
    hunt_lab_from_linear_rgb, hyab, linear_rgb_from_xyz, luminance, xyz_from_linear_rgb,
    xyz_from_ycxcz, ycxcz_from_xyz,
};
use glam::Vec3;
use illume_core::image::{Image, RgbImage};
use rayon::prelude::*;
use std::path::Path;
use std::str::FromStr;

/// Pixels per degree of visual angle of FLIP's default viewing condition: a 0.7 m wide
/// 3840-pixel monitor seen from 0.7 m (≈ 67.0206). The same value the reference
/// implementation uses.
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = 0.7 * (3840.0 / 0.7) * (std::f32::consts::PI / 180.0);

/// Pixels per degree for a monitor `width_m` metres and `width_px` pixels wide, seen from
/// `distance_m` metres (FLIP paper, viewing conditions).
pub fn pixels_per_degree(distance_m: f32, width_px: f32, width_m: f32) -> f32 {
    distance_m * (width_px / width_m) * (std::f32::consts::PI / 180.0)
}

/// Colour-pipeline exponent q_c (FLIP paper, colour pipeline).
const QC: f32 = 0.7;
/// Fraction p_c of the maximal colour difference where the remapping bends (colour pipeline).
const PC: f32 = 0.4;
/// Error value p_t that p_c·c_max maps to (colour pipeline).
const PT: f32 = 0.95;
/// Feature-detector width w in degrees (feature pipeline).
const FEATURE_WIDTH_DEG: f32 = 0.082;
/// Feature-pipeline exponent q_f (feature pipeline).
const QF: f32 = 0.5;

/// The contrast-sensitivity functions of the achromatic (Y), red-green (Cx) and
/// blue-yellow (Cz) channels as sums of Gaussians `a·sqrt(π/b)·exp(−π²x²/b)`
/// (FLIP paper, spatial filtering; the paper's constants): (a1, b1) for all, plus (a2, b2) for Cz.
const CSF_A1: [f32; 3] = [1.0, 1.0, 34.1];
const CSF_B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const CSF_A2_CZ: f32 = 13.5;
const CSF_B2_CZ: f32 = 0.025;
/// The largest scale parameter of all the Gaussians; it sets the filter radius.
const CSF_B_MAX: f32 = 0.04;

/// The tone mapper HDR-FLIP assumes the images will be shown with (HDR-FLIP paper,
/// tone mapping). Each is applied after the exposure `2^ev`, then clamped to [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlipToneMapper {
    /// Narkowicz's fit of ACES with its 0.6 pre-exposure cancelled — the reference
    /// implementation's default.
    #[default]
    Aces,
    /// Hable's "Uncharted 2" filmic curve, as fitted in the HDR-FLIP paper.
    Hable,
    /// Reinhard on luminance: `c / (1 + L(c))`.
    Reinhard,
}

impl FlipToneMapper {
    /// Coefficients (a..f) of the rational form `(a x² + b x + c) / (d x² + e x + f)`.
    fn coefficients(self) -> [f32; 6] {
        match self {
            Self::Reinhard => [0.0, 1.0, 0.0, 0.0, 1.0, 1.0],
            Self::Aces => [
                0.6 * 0.6 * 2.51,
                0.6 * 0.03,
                0.0,
                0.6 * 0.6 * 2.43,
                0.6 * 0.59,
                0.14,
            ],
            Self::Hable => [0.231683, 0.013791, 0.0, 0.18, 0.3, 0.018],
        }
    }

    /// Display-linear value (unclamped) of a linear radiance value.
    fn apply(self, c: Vec3) -> Vec3 {
        match self {
            Self::Reinhard => c / (1.0 + luminance(c)),
            _ => {
                let [a, b, k, d, e, f] = self.coefficients();
                (c * c * a + c * b + Vec3::splat(k)) / (c * c * d + c * e + Vec3::splat(f))
            }
        }
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Aces => "aces",
            Self::Hable => "hable",
            Self::Reinhard => "reinhard",
        }
    }
}

impl FromStr for FlipToneMapper {
    type Err = MetricsError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "aces" => Ok(Self::Aces),
            "hable" => Ok(Self::Hable),
            "reinhard" => Ok(Self::Reinhard),
            _ => Err(MetricsError::UnknownName {
                kind: "tone mapper",
                name: s.to_owned(),
                expected: "aces, hable, reinhard",
            }),
        }
    }
}

/// How FLIP views the images.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FlipSettings {
    /// Pixels per degree of visual angle. Default [`DEFAULT_PIXELS_PER_DEGREE`] (≈ 67.02).
    /// Higher: the viewer is further away, so fine detail and noise matter less.
    pub pixels_per_degree: f32,
    /// HDR-FLIP only: the assumed tone mapper. Default ACES.
    pub tone_mapper: FlipToneMapper,
    /// HDR-FLIP only: first exposure in stops; `None` computes it from the reference so
    /// that its brightest pixel maps to 0.85 (HDR-FLIP paper, start exposure).
    pub start_exposure_ev: Option<f32>,
    /// HDR-FLIP only: last exposure in stops; `None` computes it from the reference so
    /// that its median luminance maps to 0.85 (HDR-FLIP paper, stop exposure).
    pub stop_exposure_ev: Option<f32>,
    /// HDR-FLIP only: number of exposures; `None` uses `max(2, ⌈stop − start⌉)`
    /// (about one per stop). Higher: finer bracketing at proportional cost.
    pub exposure_count: Option<u32>,
}

impl Default for FlipSettings {
    fn default() -> Self {
        Self {
            pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE,
            tone_mapper: FlipToneMapper::Aces,
            start_exposure_ev: None,
            stop_exposure_ev: None,
            exposure_count: None,
        }
    }
}

/// A per-pixel FLIP error map, values in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    /// The error of each pixel.
    pub errors: Image<f32>,
}

impl FlipMap {
    /// Mean error over all pixels (the scalar FLIP score).
    pub fn mean(&self) -> f64 {
        let px = self.errors.pixels();
        px.iter().map(|&e| e as f64).sum::<f64>() / px.len().max(1) as f64
    }

    /// The map through the magma colour map, as 8-bit sRGB bytes (RGB, row-major):
    /// error `e` selects entry `⌊255·e + 0.5⌋`, as the reference implementation does.
    pub fn magma_rgb8(&self) -> Vec<u8> {
        self.errors
            .pixels()
            .iter()
            .flat_map(|&e| {
                let index = ((e.clamp(0.0, 1.0) * 255.0 + 0.5) as usize).min(255);
                magma::MAGMA[index].map(|v| (v * 255.0 + 0.5) as u8)
            })
            .collect()
    }

    /// Writes the magma-coloured map as an 8-bit PNG.
    pub fn write_png(&self, path: &Path) -> Result<(), MetricsError> {
        image::save_buffer(
            path,
            &self.magma_rgb8(),
            self.errors.width(),
            self.errors.height(),
            image::ColorType::Rgb8,
        )
        .map_err(|e| {
            MetricsError::Image(illume_core::image::ImageError::Write {
                path: path.to_owned(),
                message: e.to_string(),
            })
        })
    }
}

/// The exposures HDR-FLIP brackets, in stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExposureRange {
    /// First exposure.
    pub start_ev: f32,
    /// Last exposure.
    pub stop_ev: f32,
    /// Number of exposures, ≥ 2, evenly spaced from start to stop.
    pub count: u32,
}

/// HDR-FLIP's result.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrFlip {
    /// Per-pixel maximum of LDR-FLIP over the exposures.
    pub map: FlipMap,
    /// The exposures used.
    pub exposures: ExposureRange,
    /// Per pixel, which exposure gave the maximum, as `i / (count − 1)` in [0, 1].
    pub exposure_map: Image<f32>,
}

/// LDR-FLIP between two linear RGB images (values clamped to [0, 1]), at the settings'
/// pixels per degree. Errors if the sizes differ or the images are empty.
pub fn ldr_flip(
    reference: &RgbImage,
    test: &RgbImage,
    settings: &FlipSettings,
) -> Result<FlipMap, MetricsError> {
    check_same_size(reference, test)?;
    check_not_empty(reference, "FLIP")?;
    check_ppd(settings.pixels_per_degree)?;
    let clamp = |c: &Vec3| c.clamp(Vec3::ZERO, Vec3::ONE);
    let r: Vec<Vec3> = reference.pixels().iter().map(clamp).collect();
    let t: Vec<Vec3> = test.pixels().iter().map(clamp).collect();
    let (w, h) = (reference.width(), reference.height());
    let errors = ldr_flip_pixels(&r, &t, w as usize, h as usize, settings.pixels_per_degree);
    Ok(FlipMap {
        errors: Image::from_vec(w, h, errors).expect("one error per pixel"),
    })
}

/// HDR-FLIP between two linear radiance images (HDR-FLIP paper, exposure bracketing): for each
/// exposure `ev` of the bracket, both images are scaled by `2^ev`, tone mapped, clamped
/// and compared with LDR-FLIP; the per-pixel maximum is kept.
///
/// The automatic bracket follows the paper: with `x_max` the radiance the tone mapper
/// sends to 0.85, `start = log2(x_max / Y_max)` and `stop = log2(x_max / Y_median)` over the
/// reference's luminances. Where the median luminance is zero (mostly black images) the
/// smallest nonzero luminance stands in for it, and an all-black reference gets the
/// bracket [0, 0]; the reference implementation has no answer there.
pub fn hdr_flip(
    reference: &RgbImage,
    test: &RgbImage,
    settings: &FlipSettings,
) -> Result<HdrFlip, MetricsError> {
    check_same_size(reference, test)?;
    check_not_empty(reference, "HDR-FLIP")?;
    check_ppd(settings.pixels_per_degree)?;
    let exposures = exposure_range(reference, settings)?;
    let (w, h) = (reference.width() as usize, reference.height() as usize);
    let mut max_error = vec![0.0f32; w * h];
    let mut exposure_map = vec![0.0f32; w * h];
    let step = (exposures.stop_ev - exposures.start_ev) / (exposures.count - 1) as f32;
    let tone = settings.tone_mapper;
    for i in 0..exposures.count {
        let ev = exposures.start_ev + i as f32 * step;
        let scale = 2f32.powf(ev);
        let expose = |c: &Vec3| tone.apply(*c * scale).clamp(Vec3::ZERO, Vec3::ONE);
        let r: Vec<Vec3> = reference.pixels().par_iter().map(expose).collect();
        let t: Vec<Vec3> = test.pixels().par_iter().map(expose).collect();
        let errors = ldr_flip_pixels(&r, &t, w, h, settings.pixels_per_degree);
        let fraction = i as f32 / (exposures.count - 1) as f32;
        for ((best, at), e) in max_error.iter_mut().zip(&mut exposure_map).zip(errors) {
            if e > *best {
                *best = e;
                *at = fraction;
            }
        }
    }
    let (w, h) = (reference.width(), reference.height());
    Ok(HdrFlip {
        map: FlipMap {
            errors: Image::from_vec(w, h, max_error).expect("one error per pixel"),
        },
        exposures,
        exposure_map: Image::from_vec(w, h, exposure_map).expect("one value per pixel"),
    })
}

/// The per-pixel FLIP map for writing as an error image: HDR-FLIP when `hdr`, LDR-FLIP
/// otherwise.
pub fn flip_error_map(
    reference: &RgbImage,
    test: &RgbImage,
    hdr: bool,
    settings: &FlipSettings,
) -> Result<FlipMap, MetricsError> {
    if hdr {
        Ok(hdr_flip(reference, test, settings)?.map)
    } else {
        ldr_flip(reference, test, settings)
    }
}

/// The exposure bracket HDR-FLIP uses for `reference` under `settings` (user values
/// where given, the paper's automatic choice otherwise).
pub fn exposure_range(
    reference: &RgbImage,
    settings: &FlipSettings,
) -> Result<ExposureRange, MetricsError> {
    let (auto_start, auto_stop) = automatic_exposures(reference, settings.tone_mapper);
    let start_ev = settings.start_exposure_ev.unwrap_or(auto_start);
    let stop_ev = settings.stop_exposure_ev.unwrap_or(auto_stop);
    if !(start_ev.is_finite() && stop_ev.is_finite() && start_ev <= stop_ev) {
        return Err(MetricsError::InvalidArgument(format!(
            "HDR-FLIP exposures must be finite with start ≤ stop (start {start_ev}, stop {stop_ev})"
        )));
    }
    let count = match settings.exposure_count {
        Some(n) if n >= 2 => n,
        Some(n) => {
            return Err(MetricsError::InvalidArgument(format!(
                "HDR-FLIP needs at least 2 exposures, got {n}"
            )));
        }
        None => (stop_ev - start_ev).ceil().max(2.0) as u32,
    };
    Ok(ExposureRange {
        start_ev,
        stop_ev,
        count,
    })
}

fn check_ppd(ppd: f32) -> Result<(), MetricsError> {
    if ppd.is_finite() && ppd > 0.0 {
        Ok(())
    } else {
        Err(MetricsError::InvalidArgument(format!(
            "pixels per degree must be positive, got {ppd}"
        )))
    }
}

/// HDR-FLIP paper, start and stop exposures: the exposures that send the reference's maximum and median
/// luminance to 0.85 after tone mapping.
fn automatic_exposures(reference: &RgbImage, tone: FlipToneMapper) -> (f32, f32) {
    // Solve tone(x) = t for the rational tone curve: (a−t·d)x² + (b−t·e)x + (c−t·f) = 0.
    let t = 0.85f32;
    let k = tone.coefficients();
    let (a, b, c) = (k[0] - t * k[3], k[1] - t * k[4], k[2] - t * k[5]);
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        d1 + (d1 * d1 - c / a).sqrt()
    };
    let mut lums: Vec<f32> = reference.pixels().iter().map(|&p| luminance(p)).collect();
    let y_max = lums.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let y_min_nonzero = lums
        .iter()
        .copied()
        .filter(|&l| l > 0.0)
        .fold(f32::INFINITY, f32::min);
    let middle = lums.len() / 2;
    let (_, &mut median, _) = lums.select_nth_unstable_by(middle, f32::total_cmp);
    if y_max <= 0.0 {
        return (0.0, 0.0);
    }
    let y_median = if median > 0.0 { median } else { y_min_nonzero };
    ((x_max / y_max).log2(), (x_max / y_median).log2())
}

/// Separable 1-D weights of the contrast-sensitivity filters (FLIP paper, spatial filtering),
/// sampled at pixel spacing `1/ppd` degrees. Y and Cx are single Gaussians, each
/// normalised to unit sum; Cz is a sum of two 2-D Gaussians, written as
/// `g1(x)g1(y) + g2(x)g2(y)` and normalised so that the 2-D kernel sums to one.
struct SpatialFilters {
    radius: usize,
    y: Vec<f32>,
    cx: Vec<f32>,
    cz1: Vec<f32>,
    cz2: Vec<f32>,
}

impl SpatialFilters {
    fn new(ppd: f32) -> Self {
        let pi = std::f32::consts::PI;
        let pi2 = pi * pi;
        let radius = (3.0 * (CSF_B_MAX / (2.0 * pi2)).sqrt() * ppd).ceil() as usize;
        let gaussian = |x2: f32, a: f32, b: f32| a * (pi / b).sqrt() * (-pi2 * x2 / b).exp();
        // Square root of a 2-D Gaussian's amplitude, so that g(x)·g(y) is the 2-D kernel.
        let root_gaussian =
            |x2: f32, a: f32, b: f32| (a * (pi / b).sqrt()).sqrt() * (-pi2 * x2 / b).exp();
        let n = 2 * radius + 1;
        let (mut y, mut cx, mut cz1, mut cz2) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for i in 0..n {
            let x = (i as f32 - radius as f32) / ppd;
            let x2 = x * x;
            y.push(gaussian(x2, CSF_A1[0], CSF_B1[0]));
            cx.push(gaussian(x2, CSF_A1[1], CSF_B1[1]));
            cz1.push(root_gaussian(x2, CSF_A1[2], CSF_B1[2]));
            cz2.push(root_gaussian(x2, CSF_A2_CZ, CSF_B2_CZ));
        }
        let normalise = |v: &mut Vec<f32>, by: f32| v.iter_mut().for_each(|w| *w /= by);
        let (sy, scx) = (y.iter().sum::<f32>(), cx.iter().sum::<f32>());
        let (s1, s2) = (cz1.iter().sum::<f32>(), cz2.iter().sum::<f32>());
        let scz = (s1 * s1 + s2 * s2).sqrt();
        normalise(&mut y, sy);
        normalise(&mut cx, scx);
        normalise(&mut cz1, scz);
        normalise(&mut cz2, scz);
        Self {
            radius,
            y,
            cx,
            cz1,
            cz2,
        }
    }
}

/// Separable edge and point detectors (FLIP paper, feature detection): a Gaussian of standard
/// deviation `σ = ½·w·ppd` pixels and its first and second derivatives, radius ⌈3σ⌉. The
/// Gaussian sums to one; the positive and negative lobes of each derivative sum to +1
/// and −1.
struct FeatureFilters {
    radius: usize,
    gaussian: Vec<f32>,
    first: Vec<f32>,
    second: Vec<f32>,
}

impl FeatureFilters {
    fn new(ppd: f32) -> Self {
        let sigma = 0.5 * FEATURE_WIDTH_DEG * ppd;
        let radius = (3.0 * sigma).ceil() as usize;
        let n = 2 * radius + 1;
        let mut gaussian = Vec::with_capacity(n);
        let mut first = Vec::with_capacity(n);
        let mut second = Vec::with_capacity(n);
        for i in 0..n {
            let x = i as f32 - radius as f32;
            let g = (-(x * x) / (2.0 * sigma * sigma)).exp();
            gaussian.push(g);
            first.push(-x * g);
            second.push((x * x / (sigma * sigma) - 1.0) * g);
        }
        let sum = gaussian.iter().sum::<f32>();
        gaussian.iter_mut().for_each(|g| *g /= sum);
        for lobe in [&mut first, &mut second] {
            let positive: f32 = lobe.iter().filter(|&&v| v > 0.0).sum();
            let negative: f32 = -lobe.iter().filter(|&&v| v < 0.0).sum::<f32>();
            lobe.iter_mut()
                .for_each(|v| *v /= if *v > 0.0 { positive } else { negative });
        }
        Self {
            radius,
            gaussian,
            first,
            second,
        }
    }
}

/// Index of `i + k − radius`, clamped to `[0, n)` (edge pixels extend outwards).
#[inline]
fn tap(i: usize, k: usize, radius: usize, n: usize) -> usize {
    (i + k).saturating_sub(radius).min(n - 1)
}

/// LDR-FLIP on linear RGB pixels already in [0, 1] (FLIP paper, Fig. 2): colour pipeline
/// ΔE_c, feature pipeline ΔE_f, combined as `ΔE_c^(1 − ΔE_f)`.
fn ldr_flip_pixels(reference: &[Vec3], test: &[Vec3], w: usize, h: usize, ppd: f32) -> Vec<f32> {
    let to_ycxcz = |c: &Vec3| ycxcz_from_xyz(xyz_from_linear_rgb(*c));
    let r: Vec<Vec3> = reference.par_iter().map(to_ycxcz).collect();
    let t: Vec<Vec3> = test.par_iter().map(to_ycxcz).collect();

    let spatial = SpatialFilters::new(ppd);
    let r_filtered = filter_spatially(&r, w, h, &spatial);
    let t_filtered = filter_spatially(&t, w, h, &spatial);

    let features = FeatureFilters::new(ppd);
    let r_features = detect_features(&r, w, h, &features);
    let t_features = detect_features(&t, w, h, &features);

    // Maximal colour difference: between pure green and pure blue.
    let c_max = hyab(
        hunt_lab_from_linear_rgb(Vec3::new(0.0, 1.0, 0.0)),
        hunt_lab_from_linear_rgb(Vec3::new(0.0, 0.0, 1.0)),
    )
    .powf(QC);
    let pc_cmax = PC * c_max;

    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let to_lab = |ycxcz: Vec3| {
                let rgb = linear_rgb_from_xyz(xyz_from_ycxcz(ycxcz)).clamp(Vec3::ZERO, Vec3::ONE);
                hunt_lab_from_linear_rgb(rgb)
            };
            // Colour difference, compressed and remapped to [0, 1].
            let d = hyab(to_lab(r_filtered[i]), to_lab(t_filtered[i])).powf(QC);
            let colour = if d < pc_cmax {
                d * (PT / pc_cmax)
            } else {
                PT + (d - pc_cmax) / (c_max - pc_cmax) * (1.0 - PT)
            };
            // Feature difference.
            let (re, rp) = r_features[i];
            let (te, tp) = t_features[i];
            let feature =
                (std::f32::consts::FRAC_1_SQRT_2 * (re - te).abs().max((rp - tp).abs())).powf(QF);
            colour.powf(1.0 - feature)
        })
        .collect()
}

/// The YCxCz image convolved with the contrast-sensitivity filters.
fn filter_spatially(image: &[Vec3], w: usize, h: usize, f: &SpatialFilters) -> Vec<Vec3> {
    let n = 2 * f.radius + 1;
    // Horizontal pass: (Y, Cx, Cz through g1, Cz through g2).
    let mut rows = vec![[0.0f32; 4]; w * h];
    rows.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 4];
            for k in 0..n {
                let c = image[y * w + tap(x, k, f.radius, w)];
                acc[0] += f.y[k] * c.x;
                acc[1] += f.cx[k] * c.y;
                acc[2] += f.cz1[k] * c.z;
                acc[3] += f.cz2[k] * c.z;
            }
            *out = acc;
        }
    });
    let mut out = vec![Vec3::ZERO; w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 4];
            for k in 0..n {
                let c = rows[tap(y, k, f.radius, h) * w + x];
                acc[0] += f.y[k] * c[0];
                acc[1] += f.cx[k] * c[1];
                acc[2] += f.cz1[k] * c[2];
                acc[3] += f.cz2[k] * c[3];
            }
            *o = Vec3::new(acc[0], acc[1], acc[2] + acc[3]);
        }
    });
    out
}

/// Per pixel, the magnitude of the edge (gradient) and point (second-derivative)
/// responses of the achromatic channel normalised to [0, 1] (FLIP paper, feature detection).
fn detect_features(image: &[Vec3], w: usize, h: usize, f: &FeatureFilters) -> Vec<(f32, f32)> {
    let n = 2 * f.radius + 1;
    let normalised = |c: Vec3| c.x * (1.0 / 116.0) + 16.0 / 116.0;
    // Horizontal pass: (∂x, ∂²x, Gaussian) of the normalised achromatic channel.
    let mut rows = vec![[0.0f32; 3]; w * h];
    rows.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = [0.0f32; 3];
            for k in 0..n {
                let v = normalised(image[y * w + tap(x, k, f.radius, w)]);
                acc[0] += f.first[k] * v;
                acc[1] += f.second[k] * v;
                acc[2] += f.gaussian[k] * v;
            }
            *out = acc;
        }
    });
    let mut out = vec![(0.0, 0.0); w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
            for k in 0..n {
                let c = rows[tap(y, k, f.radius, h) * w + x];
                dx += f.gaussian[k] * c[0];
                ddx += f.gaussian[k] * c[1];
                dy += f.first[k] * c[2];
                ddy += f.second[k] * c[2];
            }
            *o = ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt());
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::Rgb;

    #[test]
    fn default_ppd_matches_reference_viewing_condition() {
        assert!((DEFAULT_PIXELS_PER_DEGREE - 67.0206).abs() < 1e-3);
        assert_eq!(
            pixels_per_degree(0.7, 3840.0, 0.7),
            DEFAULT_PIXELS_PER_DEGREE
        );
    }

    #[test]
    fn filters_are_normalised() {
        let s = SpatialFilters::new(DEFAULT_PIXELS_PER_DEGREE);
        assert_eq!(s.radius, 10);
        assert!((s.y.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        let (s1, s2) = (s.cz1.iter().sum::<f32>(), s.cz2.iter().sum::<f32>());
        assert!((s1 * s1 + s2 * s2 - 1.0).abs() < 1e-5);
        let f = FeatureFilters::new(DEFAULT_PIXELS_PER_DEGREE);
        assert_eq!(f.radius, 9);
        assert!((f.gaussian.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(f.first.iter().sum::<f32>().abs() < 1e-5);
    }

    #[test]
    fn identical_images_have_zero_error_everywhere() {
        let mut img = RgbImage::black(20, 12);
        for (i, p) in img.pixels_mut().iter_mut().enumerate() {
            *p = Rgb::new((i % 7) as f32 / 7.0, (i % 5) as f32 / 5.0, 0.3);
        }
        let map = ldr_flip(&img, &img, &FlipSettings::default()).unwrap();
        assert!(map.errors.pixels().iter().all(|&e| e == 0.0));
        let hdr = hdr_flip(&img, &img, &FlipSettings::default()).unwrap();
        assert_eq!(hdr.map.mean(), 0.0);
    }

    #[test]
    fn black_against_white_is_near_maximal() {
        let black = RgbImage::black(16, 16);
        let white = RgbImage::filled(16, 16, Rgb::ONE);
        let mean = ldr_flip(&black, &white, &FlipSettings::default())
            .unwrap()
            .mean();
        assert!(mean > 0.9 && mean <= 1.0, "{mean}");
    }

    #[test]
    fn tone_mapper_names_parse() {
        for t in [
            FlipToneMapper::Aces,
            FlipToneMapper::Hable,
            FlipToneMapper::Reinhard,
        ] {
            assert_eq!(t.name().parse::<FlipToneMapper>().unwrap(), t);
        }
        assert!("filmic".parse::<FlipToneMapper>().is_err());
    }

    #[test]
    fn magma_map_ends_are_the_colour_map_ends() {
        let errors = Image::from_vec(2, 1, vec![0.0, 1.0]).unwrap();
        let bytes = FlipMap { errors }.magma_rgb8();
        assert_eq!(&bytes[..3], &[0, 0, 4]);
        assert_eq!(&bytes[3..], &[252, 253, 191]);
    }
}
