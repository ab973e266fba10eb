//! illume's measuring harness: every claim about a technique (quality, stability, latency,
//! speed) comes from here. It depends on images and counters only, never on a technique.
//!
//! - **Image metrics** ([`pixel`], [`flip`], [`compare`]) between a test image and its
//!   reference, both linear RGB (`.exr` radiance, or `.png` decoded to linear):
//!   RMSE, relMSE, PSNR, SSIM (Wang et al. 2004), LDR-FLIP (Andersson et al., HPG 2020)
//!   and HDR-FLIP (Andersson et al., EG 2021), plus the FLIP error map as a magma PNG.
//! - **Temporal metrics** ([`temporal`]): flicker beyond the reference's own change,
//!   latency after an event, error-versus-time curves.
//! - **Reports** ([`report`]): `results.csv`, `report.md`, SVG plots.
//! - **Counters** ([`Counters`]): ordered `technique.name → value`, as CSV rows.
//!
//! # Definitions
//!
//! | metric | definition | notes |
//! | --- | --- | --- |
//! | `rmse` | `sqrt(mean over pixels and RGB channels of (t − r)²)` | linear values |
//! | `relmse` | `mean over pixels and channels of (t − r)² / (r² + ε)` | ε = 1e-2 ([`pixel::DEFAULT_RELMSE_EPSILON`]) |
//! | `psnr` | `20·log10(peak / rmse)` dB | peak 1 for LDR references (all values ≤ 1), the reference maximum for HDR ([`Peak::Auto`]); identical images give `+∞` (`inf` in CSV) |
//! | `ssim` | Wang et al. 2004, 11×11 Gaussian σ = 1.5, C1 = (0.01·L)², C2 = (0.03·L)² | per RGB channel on linear values, averaged; `L` = the PSNR peak; valid window positions only |
//! | `flip` | mean LDR-FLIP, 67.02 pixels per degree by default | inputs clamped to [0, 1] |
//! | `hdr-flip` | mean HDR-FLIP, ACES, automatic exposures | matches NVIDIA's reference implementation to < 2e-6 on the test set |
//! | flicker | `mean_p max(0, abs(ΔY_test) − abs(ΔY_ref))` per frame pair, `Y` = Rec.709 luminance | see [`temporal::Flicker`] |
//! | `yee` | pixels that differ visibly by Yee & Newman 2004 (PerceptualDiff's model) | 8-bit inputs, see [`yee`] |
//! | latency | frames (and seconds) from the event until the error is below a threshold for good | see [`temporal::latency_after_event`] |
//!
//! ```
//! use illume_core::image::RgbImage;
//! use illume_core::Rgb;
//! use illume_metrics::{compare_images, Metric};
//! let reference = RgbImage::filled(32, 32, Rgb::splat(0.5));
//! let test = RgbImage::filled(32, 32, Rgb::splat(0.25));
//! let values = compare_images(&reference, &test, &[Metric::Rmse, Metric::Psnr]).unwrap();
//! assert_eq!(values[0], (Metric::Rmse, 0.25));
//! assert!((values[1].1 - 12.0412).abs() < 1e-4); // 20·log10(1 / 0.25) dB
//! ```

pub mod compare;
pub mod counters;
pub mod error;
pub mod flip;
pub mod pixel;
pub mod report;
pub mod temporal;
pub mod yee;

pub use compare::{
    CompareSettings, FileComparison, FolderComparison, Metric, compare_files, compare_folders,
    compare_images, compare_images_with, measure, parse_metric_list,
};
pub use counters::{CounterReport, Counters, counters_table};
pub use error::MetricsError;
pub use flip::{
    FlipMap, FlipSettings, FlipToneMapper, HdrFlip, flip_error_map, hdr_flip, ldr_flip,
};
pub use pixel::{Peak, block_error, mse, psnr, rel_mse, rmse, ssim};
pub use temporal::{ErrorCurve, Flicker, Latency, error_curve, flicker, latency_after_event};
pub use yee::{YeeResult, YeeSettings, yee_diff};
