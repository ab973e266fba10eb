//! Pixel-wise error metrics between a test image and its reference: MSE, RMSE, relMSE,
//! PSNR and SSIM. All take linear RGB (`RgbImage`, radiance for HDR, display-linear for
//! LDR) and accumulate in `f64`.

use crate::error::{MetricsError, check_not_empty, check_same_size};
use illume_core::image::{Image, RgbImage};
use rayon::prelude::*;

/// Default ε of [`rel_mse`]: 1e-2 keeps near-black reference pixels from dominating
/// (the value used by, e.g., Rousselle et al. 2011 and the denoising literature).
pub const DEFAULT_RELMSE_EPSILON: f64 = 1e-2;

/// Mean squared error over all pixels and the three channels.
pub fn mse(reference: &RgbImage, test: &RgbImage) -> Result<f64, MetricsError> {
    mean_over_channels(reference, test, |r, t| (t - r) * (t - r))
}

/// Root mean squared error: `sqrt(mse)`. A constant offset `c` on every channel gives
/// exactly `c`.
pub fn rmse(reference: &RgbImage, test: &RgbImage) -> Result<f64, MetricsError> {
    mse(reference, test).map(f64::sqrt)
}

/// Relative MSE: the mean over pixels and channels of `(t − r)² / (r² + ε)`, with `r` the
/// reference value. Scale-aware: an error of 10% costs about the same in dark and bright
/// regions. Use [`DEFAULT_RELMSE_EPSILON`] unless there is a reason not to.
pub fn rel_mse(reference: &RgbImage, test: &RgbImage, epsilon: f64) -> Result<f64, MetricsError> {
    if epsilon.is_nan() || epsilon <= 0.0 {
        return Err(MetricsError::InvalidArgument(format!(
            "relMSE ε must be positive, got {epsilon}"
        )));
    }
    mean_over_channels(reference, test, |r, t| {
        (t - r) * (t - r) / (r * r + epsilon)
    })
}

/// The peak signal value that PSNR and SSIM measure against.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Peak {
    /// 1.0 when every reference channel is ≤ 1 (an LDR image), else the largest
    /// reference channel value (an HDR image).
    #[default]
    Auto,
    /// Always 1.0 (display-linear LDR).
    One,
    /// The largest channel value of the reference.
    ReferenceMax,
    /// A stated value.
    Fixed(f64),
}

impl Peak {
    /// The peak value for this reference.
    pub fn value(self, reference: &RgbImage) -> f64 {
        let max = || {
            reference
                .pixels()
                .iter()
                .map(|p| p.max_element() as f64)
                .fold(0.0, f64::max)
        };
        match self {
            Self::Auto => {
                let m = max();
                if m <= 1.0 { 1.0 } else { m }
            }
            Self::One => 1.0,
            Self::ReferenceMax => max(),
            Self::Fixed(v) => v,
        }
    }
}

/// Peak signal-to-noise ratio in dB: `20·log10(peak / rmse)`. Identical images give
/// `f64::INFINITY` (not capped).
pub fn psnr(reference: &RgbImage, test: &RgbImage, peak: Peak) -> Result<f64, MetricsError> {
    let rmse = rmse(reference, test)?;
    let peak = peak.value(reference);
    if rmse == 0.0 {
        Ok(f64::INFINITY)
    } else {
        Ok(20.0 * (peak / rmse).log10())
    }
}

/// Side of the SSIM window in pixels.
pub const SSIM_WINDOW: u32 = 11;
/// Standard deviation of the SSIM window's Gaussian, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;

/// Structural similarity (Z. Wang, A. C. Bovik, H. R. Sheikh, E. P. Simoncelli, "Image
/// Quality Assessment: From Error Visibility to Structural Similarity", IEEE TIP 2004,
/// Eq. 13) with the paper's settings: an 11×11 Gaussian window of σ = 1.5 (normalised),
/// `C1 = (0.01·L)²`, `C2 = (0.03·L)²` with `L` the [`Peak`] value.
///
/// Computed on each RGB channel separately, on the linear values as given, and averaged
/// over the three channels; each channel's SSIM is the mean over the window positions
/// that lie wholly inside the image (no padding, as in the authors' `ssim_index.m`).
/// 1 for identical images; images smaller than 11×11 are an error.
pub fn ssim(reference: &RgbImage, test: &RgbImage, peak: Peak) -> Result<f64, MetricsError> {
    check_same_size(reference, test)?;
    let (w, h) = (reference.width(), reference.height());
    if w < SSIM_WINDOW || h < SSIM_WINDOW {
        return Err(MetricsError::TooSmall {
            width: w,
            height: h,
            metric: "SSIM",
            min: SSIM_WINDOW,
        });
    }
    let l = peak.value(reference);
    let c1 = (0.01 * l) * (0.01 * l);
    let c2 = (0.03 * l) * (0.03 * l);
    let kernel = ssim_kernel();
    let mut total = 0.0;
    for channel in 0..3 {
        let x = reference.map(|p| p[channel] as f64);
        let y = test.map(|p| p[channel] as f64);
        let mu_x = filter_valid(&x, &kernel);
        let mu_y = filter_valid(&y, &kernel);
        let xx = filter_valid(&x.map(|v| v * v), &kernel);
        let yy = filter_valid(&y.map(|v| v * v), &kernel);
        let xy = filter_valid(
            &Image::from_vec(
                w,
                h,
                x.pixels()
                    .iter()
                    .zip(y.pixels())
                    .map(|(a, b)| a * b)
                    .collect(),
            )
            .expect("same size"),
            &kernel,
        );
        let n = mu_x.len();
        let mut sum = 0.0;
        for i in 0..n {
            let (mx, my) = (mu_x[i], mu_y[i]);
            let var_x = xx[i] - mx * mx;
            let var_y = yy[i] - my * my;
            let cov = xy[i] - mx * my;
            sum += ((2.0 * mx * my + c1) * (2.0 * cov + c2))
                / ((mx * mx + my * my + c1) * (var_x + var_y + c2));
        }
        total += sum / n as f64;
    }
    Ok(total / 3.0)
}

/// The normalised 1-D Gaussian of the SSIM window.
fn ssim_kernel() -> Vec<f64> {
    let r = (SSIM_WINDOW / 2) as i32;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp())
        .collect();
    let s: f64 = k.iter().sum();
    k.into_iter().map(|v| v / s).collect()
}

/// Separable filtering of `image` by `kernel` at the window positions wholly inside it;
/// returns `(w − n + 1)·(h − n + 1)` values, row-major.
fn filter_valid(image: &Image<f64>, kernel: &[f64]) -> Vec<f64> {
    let (w, h, n) = (
        image.width() as usize,
        image.height() as usize,
        kernel.len(),
    );
    let (ow, oh) = (w + 1 - n, h + 1 - n);
    let px = image.pixels();
    let mut rows = vec![0.0; ow * h];
    rows.par_chunks_mut(ow).enumerate().for_each(|(y, row)| {
        let src = &px[y * w..(y + 1) * w];
        for (x, out) in row.iter_mut().enumerate() {
            *out = kernel.iter().zip(&src[x..x + n]).map(|(k, v)| k * v).sum();
        }
    });
    let mut out = vec![0.0; ow * oh];
    out.par_chunks_mut(ow).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            *o = kernel
                .iter()
                .enumerate()
                .map(|(k, c)| c * rows[(y + k) * ow + x])
                .sum();
        }
    });
    out
}

/// Mean of `f(reference, test)` over all pixels and channels.
/// Relative L1 error of block sums: the image is cut into `block`×`block` pixel blocks
/// (partial blocks at the right and bottom edges included), and the result is
/// `Σ |test − reference| / Σ reference` over the blocks' channel sums. Averaging within
/// blocks removes per-pixel noise, so this measures bias at the scale of regions — what
/// tests comparing a technique's converged light with the reference's ask.
pub fn block_error(reference: &RgbImage, test: &RgbImage, block: u32) -> Result<f64, MetricsError> {
    check_same_size(reference, test)?;
    check_not_empty(reference, "block error")?;
    if block == 0 {
        return Err(MetricsError::InvalidArgument(
            "block size must be ≥ 1".into(),
        ));
    }
    let (w, h) = (reference.width(), reference.height());
    let bw = w.div_ceil(block);
    let sums = |img: &RgbImage| {
        let mut out = vec![[0f64; 3]; (bw * h.div_ceil(block)) as usize];
        for y in 0..h {
            for x in 0..w {
                let p = img.get(x, y);
                let b = &mut out[((y / block) * bw + x / block) as usize];
                for c in 0..3 {
                    b[c] += p[c] as f64;
                }
            }
        }
        out
    };
    let (r, t) = (sums(reference), sums(test));
    let num: f64 = r
        .iter()
        .zip(&t)
        .map(|(r, t)| (0..3).map(|c| (t[c] - r[c]).abs()).sum::<f64>())
        .sum();
    let den: f64 = r.iter().map(|r| r.iter().sum::<f64>()).sum();
    Ok(num / den)
}

fn mean_over_channels(
    reference: &RgbImage,
    test: &RgbImage,
    f: impl Fn(f64, f64) -> f64,
) -> Result<f64, MetricsError> {
    check_same_size(reference, test)?;
    check_not_empty(reference, "a pixel metric")?;
    let sum: f64 = reference
        .pixels()
        .iter()
        .zip(test.pixels())
        .map(|(r, t)| (0..3).map(|c| f(r[c] as f64, t[c] as f64)).sum::<f64>())
        .sum();
    Ok(sum / (3 * reference.pixels().len()) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::Rgb;

    #[test]
    fn block_error_ignores_noise_within_blocks_and_sees_bias() {
        let reference = RgbImage::filled(8, 8, Rgb::ONE);
        // A checkerboard of 0.5 and 1.5: zero-mean noise within every 2×2 block.
        let mut noisy = reference.clone();
        for y in 0..8 {
            for x in 0..8 {
                *noisy.get_mut(x, y) = Rgb::splat(if (x + y) % 2 == 0 { 0.5 } else { 1.5 });
            }
        }
        assert!(block_error(&reference, &noisy, 2).unwrap() < 1e-12);
        assert!((block_error(&reference, &noisy, 1).unwrap() - 0.5).abs() < 1e-12);
        // 10 % too dark everywhere: 0.1 at any block size, partial blocks included.
        let dark = RgbImage::filled(8, 8, Rgb::splat(0.9));
        assert!((block_error(&reference, &dark, 3).unwrap() - 0.1).abs() < 1e-6);
        assert!(block_error(&reference, &dark, 0).is_err());
        assert!(block_error(&reference, &RgbImage::filled(4, 8, Rgb::ONE), 2).is_err());
    }
    use illume_core::sampling::Pcg32;

    /// A deterministic image whose values are multiples of 1/64 in [0, 0.75], so that adding
    /// 0.125 is exact in `f32`.
    fn pattern(w: u32, h: u32, seed: u64) -> RgbImage {
        let mut rng = Pcg32::new(seed, 1);
        let mut img = RgbImage::black(w, h);
        for p in img.pixels_mut() {
            *p = Rgb::new(
                rng.next_below(49) as f32 / 64.0,
                rng.next_below(49) as f32 / 64.0,
                rng.next_below(49) as f32 / 64.0,
            );
        }
        img
    }

    #[test]
    fn identical_images() {
        let a = pattern(32, 24, 1);
        assert_eq!(rmse(&a, &a).unwrap(), 0.0);
        assert_eq!(rel_mse(&a, &a, DEFAULT_RELMSE_EPSILON).unwrap(), 0.0);
        assert_eq!(psnr(&a, &a, Peak::Auto).unwrap(), f64::INFINITY);
        assert!((ssim(&a, &a, Peak::Auto).unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn constant_offset() {
        let a = pattern(32, 24, 2);
        let c = 0.125;
        let b = a.map(|p| *p + Rgb::splat(c as f32));
        assert_eq!(rmse(&a, &b).unwrap(), c);
        // Peak 1 (all values ≤ 1): PSNR = 20·log10(1/c) exactly.
        assert_eq!(psnr(&a, &b, Peak::Auto).unwrap(), 20.0 * (1.0 / c).log10());
        assert_eq!(
            psnr(&a, &b, Peak::Fixed(4.0)).unwrap(),
            20.0 * (4.0f64 / c).log10()
        );
        // relMSE: mean of c²/(r²+ε), computed independently.
        let expected: f64 = a
            .pixels()
            .iter()
            .flat_map(|p| p.to_array())
            .map(|r| c * c / (r as f64 * r as f64 + 0.01))
            .sum::<f64>()
            / (3.0 * a.pixels().len() as f64);
        assert!((rel_mse(&a, &b, 0.01).unwrap() - expected).abs() < 1e-12 * expected);
        // An offset lowers SSIM only through the luminance term.
        let s = ssim(&a, &b, Peak::Auto).unwrap();
        assert!(s < 1.0 && s > 0.5, "{s}");
    }

    #[test]
    fn peak_auto_picks_hdr_maximum() {
        let mut a = pattern(4, 4, 3);
        a.pixels_mut()[5] = Rgb::new(0.0, 12.5, 0.0);
        assert_eq!(Peak::Auto.value(&a), 12.5);
        assert_eq!(Peak::One.value(&a), 1.0);
    }

    #[test]
    fn ssim_of_uncorrelated_noise_is_low() {
        let a = pattern(64, 64, 4);
        let b = pattern(64, 64, 5);
        let s = ssim(&a, &b, Peak::One).unwrap();
        assert!(s.abs() < 0.1, "{s}");
    }

    #[test]
    fn size_mismatch_and_tiny_images_are_errors() {
        let a = pattern(12, 12, 6);
        let b = pattern(12, 11, 6);
        assert!(matches!(
            rmse(&a, &b),
            Err(MetricsError::SizeMismatch { .. })
        ));
        let tiny = pattern(8, 8, 7);
        assert!(matches!(
            ssim(&tiny, &tiny, Peak::One),
            Err(MetricsError::TooSmall { .. })
        ));
    }
}
