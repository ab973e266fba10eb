//! Yee & Newman's perceptual metric for production testing (SIGGRAPH 2004 sketch; Yee's
//! thesis), the model behind PerceptualDiff [YCS⁺04] that Bahnsen et al. 2012 use to pick
//! key frames (§3.2) and to judge results (§4). Written from the published description;
//! no code of pdiff (GPL) was used.
//!
//! Two 8-bit images (`to_srgb8` output) are compared pixel by pixel:
//!
//! 1. **To luminance.** Bytes are decoded with a pure power law (`gamma`, 2.2 by default,
//!    as pdiff does, not the sRGB curve), taken as Rec.709 linear RGB, converted to CIE
//!    XYZ and to CIE L\*a\*b\* (D65). `Y × luminance` gives cd/m².
//! 2. **Band-pass pyramid.** Each image's luminance is blurred with the 5-tap binomial-like
//!    kernel (0.05, 0.25, 0.4, 0.25, 0.05) *à trous* (the taps 2ⁱ pixels apart at level i),
//!    giving Gaussian levels G₀ … G_n at full resolution and Laplacian bands
//!    Lᵢ = Gᵢ − Gᵢ₊₁ whose peak frequency is `0.5 · ppd / 2ⁱ` cycles per degree, where
//!    `ppd` (pixels per degree) follows from the horizontal field of view `fov_deg`.
//! 3. **Adaptation.** La = the mean of both images' Gaussian level whose blur is about one
//!    degree (level ⌊log₂ ppd⌋, clamped), in cd/m².
//! 4. **Threshold.** The threshold-versus-intensity function of Ward Larson, Rushmeier &
//!    Piatko (1997) gives the just-visible luminance step T(La) of a uniform field. It is
//!    raised per band by the contrast sensitivity function of Barten (as used by Daly's
//!    VDP), `F_freq,i = CSF_max(La) / CSF(max(cpdᵢ, f_peak), La)` (held at the peak below
//!    the peak frequency f_peak: a large uniform step is seen by its edges and judged by
//!    the TVI alone), and by Daly's visual masking
//!    `F_mask,i = (1 + (0.0153 · (392.498 · cᵢ)^0.7)^4)^(1/4)` of the band's contrast
//!    cᵢ·CSF. The elevation F is the contrast-weighted mean
//!    `Σ ΔCᵢ F_freq,i F_mask,i / Σ ΔCᵢ` with ΔCᵢ = |ΔLᵢ| / Gᵢ₊₁ (F = 1 when no band
//!    differs, Σ ΔCᵢ < 10⁻⁴: a uniform step is judged by T alone).
//! 5. **Luminance test.** The pixel differs visibly if |Y_ref − Y_test| > F · T(La).
//! 6. **Colour test** (only if the luminance test passed): it differs if
//!    `colour_factor · s(La) · √(Δa\*² + Δb\*²) > 2.3 · F`, 2.3 being the CIE76 just-noticeable
//!    difference and `s(La) = min(1, La / 10 cd/m²)` turning colour vision off in dim light.
//!
//! The images **differ visibly** when at least `fail_pixels` pixels (100, pdiff's default)
//! fail.
//!
//! ```
//! use illume_metrics::yee::{YeeSettings, yee_diff};
//! let a = vec![128u8; 64 * 64 * 3];
//! let r = yee_diff(64, 64, &a, &a, &YeeSettings::default()).unwrap();
//! assert_eq!(r.failed_pixels, 0);
//! assert!(!r.visible);
//! ```

use crate::error::MetricsError;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The viewing conditions and the decision rule. Defaults are pdiff's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct YeeSettings {
    /// Horizontal field of view of the image on the viewer's retina \[degrees\]. Higher:
    /// fewer pixels per degree, fine detail matters less. Default 45.
    pub fov_deg: f32,
    /// Power-law decoding of the 8-bit values. Default 2.2.
    pub gamma: f32,
    /// Luminance of a white pixel \[cd/m²\]. Higher: brighter display, smaller relative
    /// thresholds. Default 100.
    pub luminance: f32,
    /// Weight of the colour test (0 turns it off). Default 1.
    pub colour_factor: f32,
    /// Number of failing pixels from which the images differ visibly. Default 100.
    pub fail_pixels: usize,
}

impl Default for YeeSettings {
    fn default() -> Self {
        Self {
            fov_deg: 45.0,
            gamma: 2.2,
            luminance: 100.0,
            colour_factor: 1.0,
            fail_pixels: 100,
        }
    }
}

/// The outcome of one comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct YeeResult {
    /// Pixels that differ visibly.
    pub failed_pixels: usize,
    /// `failed_pixels ≥ fail_pixels`.
    pub visible: bool,
    /// Per-pixel failure mask (row-major), for error images.
    pub failed: Vec<bool>,
}

/// Number of Gaussian levels (bands = levels − 1).
const LEVELS: usize = 8;
/// CIE76 just-noticeable colour difference.
const JND_LAB: f32 = 2.3;

/// Compares two 8-bit RGB images (`width × height × 3` bytes each, row-major).
pub fn yee_diff(
    width: u32,
    height: u32,
    reference: &[u8],
    test: &[u8],
    settings: &YeeSettings,
) -> Result<YeeResult, MetricsError> {
    let n = width as usize * height as usize;
    if n == 0 {
        return Err(MetricsError::TooSmall {
            width,
            height,
            metric: "Yee",
            min: 1,
        });
    }
    for (data, what) in [
        (reference, "Yee: width × height × 3 vs reference bytes"),
        (test, "Yee: width × height × 3 vs test bytes"),
    ] {
        if data.len() != n * 3 {
            return Err(MetricsError::LengthMismatch {
                what,
                left: n * 3,
                right: data.len(),
            });
        }
    }
    let lut: Vec<f32> = (0..256)
        .map(|v| (v as f32 / 255.0).powf(settings.gamma))
        .collect();
    let convert = |data: &[u8]| -> (Vec<f32>, Vec<[f32; 2]>) {
        data.par_chunks_exact(3)
            .map(|p| {
                let (r, g, b) = (lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]);
                let x = 0.4124 * r + 0.3576 * g + 0.1805 * b;
                let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
                let z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
                let (_, a, bb) = xyz_to_lab(x, y, z);
                (y * settings.luminance, [a, bb])
            })
            .unzip()
    };
    let (y_ref, lab_ref) = convert(reference);
    let (y_test, lab_test) = convert(test);
    let (w, h) = (width as usize, height as usize);
    let g_ref = pyramid(&y_ref, w, h);
    let g_test = pyramid(&y_test, w, h);

    // Pixels per degree and the level blurred to about one degree.
    let ppd = width as f32 / settings.fov_deg.max(1e-3);
    let adaptation_level = (ppd.max(1.0).log2().floor() as usize).min(LEVELS - 1);
    let cpd: Vec<f32> = (0..LEVELS - 1)
        .map(|i| 0.5 * ppd / (1u32 << i) as f32)
        .collect();

    let failed: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|p| {
            let la = (0.5 * (g_ref[adaptation_level][p] + g_test[adaptation_level][p])).max(1e-5);
            let (csf_max, peak_cpd) = csf_peak(la);
            let (mut sum_c, mut sum_weighted) = (0.0f32, 0.0f32);
            for i in 0..LEVELS - 1 {
                let band_ref = g_ref[i][p] - g_ref[i + 1][p];
                let band_test = g_test[i][p] - g_test[i + 1][p];
                let base = (0.5 * (g_ref[i + 1][p] + g_test[i + 1][p])).max(1e-5);
                let dc = (band_ref - band_test).abs() / base;
                let sensitivity = csf(cpd[i].max(peak_cpd), la).max(1e-6);
                let f_freq = csf_max / sensitivity;
                let masking_contrast = band_ref.abs() / base * sensitivity;
                let f_mask = daly_masking(masking_contrast);
                sum_c += dc;
                sum_weighted += dc * f_freq * f_mask;
            }
            // Threshold elevation by frequency and masking, bounded to [1, 10] as pdiff
            // bounds it: masking never hides a difference of more than ten thresholds.
            let elevation = if sum_c > 1e-4 {
                (sum_weighted / sum_c).clamp(1.0, 10.0)
            } else {
                1.0
            };
            let threshold = elevation * tvi(la);
            if (y_ref[p] - y_test[p]).abs() > threshold {
                return true;
            }
            if settings.colour_factor > 0.0 {
                let scale = (la / 10.0).min(1.0);
                let da = lab_ref[p][0] - lab_test[p][0];
                let db = lab_ref[p][1] - lab_test[p][1];
                let de = (da * da + db * db).sqrt();
                if settings.colour_factor * scale * de > JND_LAB * elevation {
                    return true;
                }
            }
            false
        })
        .collect();
    let failed_pixels = failed.iter().filter(|f| **f).count();
    Ok(YeeResult {
        failed_pixels,
        visible: failed_pixels >= settings.fail_pixels,
        failed,
    })
}

/// Gaussian levels G₀ (the input) … G_{LEVELS−1}, à trous, clamped at the borders.
fn pyramid(y: &[f32], w: usize, h: usize) -> Vec<Vec<f32>> {
    const K: [f32; 5] = [0.05, 0.25, 0.4, 0.25, 0.05];
    let mut levels = vec![y.to_vec()];
    for i in 0..LEVELS - 1 {
        let step = 1isize << i;
        let src = &levels[i];
        let blur_row: Vec<f32> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let (x, row) = ((p % w) as isize, p / w);
                K.iter()
                    .enumerate()
                    .map(|(k, weight)| {
                        let xx = (x + (k as isize - 2) * step).clamp(0, w as isize - 1) as usize;
                        weight * src[row * w + xx]
                    })
                    .sum()
            })
            .collect();
        let blurred: Vec<f32> = (0..w * h)
            .into_par_iter()
            .map(|p| {
                let (x, row) = (p % w, (p / w) as isize);
                K.iter()
                    .enumerate()
                    .map(|(k, weight)| {
                        let yy = (row + (k as isize - 2) * step).clamp(0, h as isize - 1) as usize;
                        weight * blur_row[yy * w + x]
                    })
                    .sum()
            })
            .collect();
        levels.push(blurred);
    }
    levels
}

/// Threshold versus intensity (Ward Larson, Rushmeier & Piatko 1997): the smallest
/// visible luminance step \[cd/m²\] on a uniform field adapted to `la` cd/m².
pub fn tvi(la: f32) -> f32 {
    let l = la.max(1e-10).log10();
    let log_t = if l < -3.94 {
        -2.86
    } else if l < -1.44 {
        (0.405 * l + 1.6).powf(2.18) - 2.86
    } else if l < -0.0184 {
        l - 0.395
    } else if l < 1.9 {
        (0.249 * l + 0.65).powf(2.7) - 0.72
    } else {
        l - 1.255
    };
    10f32.powf(log_t)
}

/// Barten's contrast sensitivity at `cpd` cycles per degree and adaptation `la` cd/m²:
/// `A·f·exp(−B f)·√(1 + 0.06 exp(B f))`, A = 440 (1 + 0.7/La)^−0.2,
/// B = 0.3 (1 + 100/La)^0.15.
pub fn csf(cpd: f32, la: f32) -> f32 {
    let a = 440.0 * (1.0 + 0.7 / la).powf(-0.2);
    let b = 0.3 * (1.0 + 100.0 / la).powf(0.15);
    let bf = (b * cpd).min(80.0);
    a * cpd * (-bf).exp() * (1.0 + 0.06 * bf.exp()).sqrt()
}

/// The peak of [`csf`] over frequency at adaptation `la` and the frequency \[cpd\] where
/// it lies (searched on a 10 % log grid from 0.5 cpd).
fn csf_peak(la: f32) -> (f32, f32) {
    (0..64)
        .map(|i| {
            let f = 0.5 * 1.1f32.powi(i);
            (csf(f, la), f)
        })
        .fold((0.0, 0.5), |best, c| if c.0 > best.0 { c } else { best })
}

/// Daly's masking elevation for a band contrast (already multiplied by the CSF).
fn daly_masking(contrast: f32) -> f32 {
    (1.0 + (0.0153 * (392.498 * contrast).powf(0.7)).powi(4)).powf(0.25)
}

/// CIE XYZ (Y of white = 1) to CIE L\*a\*b\* with the D65 white point.
fn xyz_to_lab(x: f32, y: f32, z: f32) -> (f32, f32, f32) {
    let f = |t: f32| {
        if t > 0.008856 {
            t.cbrt()
        } else {
            7.787 * t + 16.0 / 116.0
        }
    };
    let (fx, fy, fz) = (f(x / 0.9505), f(y), f(z / 1.089));
    (116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(w: usize, h: usize, v: u8) -> Vec<u8> {
        vec![v; w * h * 3]
    }

    #[test]
    fn identical_images_fail_no_pixel() {
        let (w, h) = (48, 32);
        // A busy image: a gradient with a checker.
        let img: Vec<u8> = (0..w * h)
            .flat_map(|p| {
                let (x, y) = (p % w, p / w);
                let v = (x * 5 + if (x / 4 + y / 4) % 2 == 0 { 40 } else { 0 }) as u8;
                [v, v / 2, 255 - v]
            })
            .collect();
        let r = yee_diff(w as u32, h as u32, &img, &img, &YeeSettings::default()).unwrap();
        assert_eq!(r.failed_pixels, 0);
        assert!(!r.visible);
    }

    #[test]
    fn tvi_matches_hand_computed_values() {
        // log La = 1.7: (0.249·1.7 + 0.65)^2.7 − 0.72 = 0.4905 → 3.095 cd/m².
        assert!((tvi(10f32.powf(1.7)) - 3.095).abs() < 0.01, "{}", tvi(50.1));
        // Photopic range: T = La / 10^1.255 (Weber fraction 5.6 %).
        assert!((tvi(1000.0) - 1000.0 / 10f32.powf(1.255)).abs() < 0.01);
    }

    /// A uniform field against a uniform field one step brighter: every pixel fails just
    /// above the TVI threshold, none just below (no band differs, so F = 1).
    #[test]
    fn uniform_steps_just_above_and_below_threshold() {
        let s = YeeSettings {
            colour_factor: 0.0,
            ..Default::default()
        };
        let (w, h) = (40, 30);
        let y = |v: u8| (v as f32 / 255.0).powf(s.gamma) * s.luminance;
        let base = 160u8;
        // The smallest step that is above threshold, and the one before it.
        let above = (base + 1..=255)
            .find(|&v| {
                let la = 0.5 * (y(base) + y(v));
                y(v) - y(base) > tvi(la)
            })
            .unwrap();
        let below = above - 1;
        let la = 0.5 * (y(base) + y(above));
        let margin_above = (y(above) - y(base)) / tvi(la);
        assert!(margin_above > 1.0 && margin_above < 1.2, "{margin_above}");
        let r = yee_diff(w, h, &grey(40, 30, base), &grey(40, 30, above), &s).unwrap();
        assert_eq!(r.failed_pixels, 1200);
        assert!(r.visible);
        let r = yee_diff(w, h, &grey(40, 30, base), &grey(40, 30, below), &s).unwrap();
        assert_eq!(r.failed_pixels, 0);
        assert!(!r.visible);
    }

    /// A small bright square: visible when its contrast is large, invisible when it is a
    /// fraction of the threshold.
    #[test]
    fn local_contrast_steps() {
        let s = YeeSettings::default();
        let (w, h) = (64, 64);
        let base = grey(w, h, 120);
        let with_square = |v: u8| {
            let mut img = base.clone();
            for y in 16..48 {
                for x in 16..48 {
                    img[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(v);
                }
            }
            img
        };
        let strong = yee_diff(64, 64, &base, &with_square(200), &s).unwrap();
        assert!(strong.failed_pixels >= 32 * 32, "{}", strong.failed_pixels);
        assert!(strong.visible);
        let faint = yee_diff(64, 64, &base, &with_square(121), &s).unwrap();
        assert_eq!(faint.failed_pixels, 0);
    }

    /// A black image against a bright, finely textured one: every pixel differs by far
    /// more than any masking can hide (the threshold elevation is bounded).
    #[test]
    fn black_against_a_bright_texture_is_visible() {
        let (w, h) = (96, 72);
        let texture: Vec<u8> = (0..w * h)
            .flat_map(|p| {
                let v = if (p % w + p / w) % 2 == 0 { 255 } else { 140 };
                [v, v, v]
            })
            .collect();
        let black = grey(w, h, 0);
        let r = yee_diff(
            w as u32,
            h as u32,
            &black,
            &texture,
            &YeeSettings::default(),
        )
        .unwrap();
        assert!(
            r.failed_pixels * 10 >= w * h * 9,
            "{} of {}",
            r.failed_pixels,
            w * h
        );
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let a = grey(4, 4, 1);
        assert!(yee_diff(4, 4, &a, &a[..12], &YeeSettings::default()).is_err());
        assert!(yee_diff(0, 4, &[], &[], &YeeSettings::default()).is_err());
    }
}
