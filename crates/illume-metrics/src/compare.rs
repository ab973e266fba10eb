//! The entry points the CLI uses: a [`Metric`] enum with command-line names, one call to
//! compare two images, and one to compare two folders of same-named images.

use crate::error::MetricsError;
use crate::flip::{FlipSettings, hdr_flip, ldr_flip};
use crate::pixel::{DEFAULT_RELMSE_EPSILON, Peak, psnr, rel_mse, rmse, ssim};
use crate::report::{Cell, Table};
use illume_core::image::RgbImage;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// An image metric. Lower is better for every metric except PSNR and SSIM.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// Root mean squared error ([`crate::pixel::rmse`]).
    Rmse,
    /// Relative MSE with ε from [`CompareSettings::relmse_epsilon`] ([`crate::pixel::rel_mse`]).
    #[serde(rename = "relmse")]
    RelMse,
    /// Peak signal-to-noise ratio in dB ([`crate::pixel::psnr`]).
    Psnr,
    /// Structural similarity ([`crate::pixel::ssim`]).
    Ssim,
    /// Mean LDR-FLIP ([`crate::flip::ldr_flip`]); values are clamped to [0, 1] first.
    Flip,
    /// Mean HDR-FLIP ([`crate::flip::hdr_flip`]).
    HdrFlip,
}

impl Metric {
    /// Every metric, in the order reports list them.
    pub const ALL: [Metric; 6] = [
        Metric::Rmse,
        Metric::RelMse,
        Metric::Psnr,
        Metric::Ssim,
        Metric::Flip,
        Metric::HdrFlip,
    ];

    /// The command-line and column name: `rmse, relmse, psnr, ssim, flip, hdr-flip`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rmse => "rmse",
            Self::RelMse => "relmse",
            Self::Psnr => "psnr",
            Self::Ssim => "ssim",
            Self::Flip => "flip",
            Self::HdrFlip => "hdr-flip",
        }
    }

    /// True when larger values mean a better match (PSNR, SSIM).
    pub fn higher_is_better(self) -> bool {
        matches!(self, Self::Psnr | Self::Ssim)
    }
}

impl fmt::Display for Metric {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Metric {
    type Err = MetricsError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        Metric::ALL
            .into_iter()
            .find(|m| m.name() == lower || (lower == "hdrflip" && *m == Metric::HdrFlip))
            .ok_or_else(|| MetricsError::UnknownName {
                kind: "metric",
                name: s.to_owned(),
                expected: "rmse, relmse, psnr, ssim, flip, hdr-flip",
            })
    }
}

/// Parses a comma-separated list of metric names, e.g. `"rmse,flip,hdr-flip"`.
pub fn parse_metric_list(list: &str) -> Result<Vec<Metric>, MetricsError> {
    list.split(',')
        .filter(|s| !s.trim().is_empty())
        .map(str::parse)
        .collect()
}

/// The knobs of the image metrics; the defaults are what `illume compare` uses.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CompareSettings {
    /// ε of relMSE. Default [`DEFAULT_RELMSE_EPSILON`] (1e-2).
    pub relmse_epsilon: f64,
    /// Peak of PSNR and dynamic range `L` of SSIM. Default [`Peak::Auto`]: 1 for LDR
    /// references (all values ≤ 1), the reference maximum for HDR ones.
    pub peak: Peak,
    /// FLIP viewing condition and HDR-FLIP exposure settings.
    pub flip: FlipSettings,
}

impl Default for CompareSettings {
    fn default() -> Self {
        Self {
            relmse_epsilon: DEFAULT_RELMSE_EPSILON,
            peak: Peak::Auto,
            flip: FlipSettings::default(),
        }
    }
}

/// One metric between two images.
pub fn measure(
    reference: &RgbImage,
    test: &RgbImage,
    metric: Metric,
    settings: &CompareSettings,
) -> Result<f64, MetricsError> {
    match metric {
        Metric::Rmse => rmse(reference, test),
        Metric::RelMse => rel_mse(reference, test, settings.relmse_epsilon),
        Metric::Psnr => psnr(reference, test, settings.peak),
        Metric::Ssim => ssim(reference, test, settings.peak),
        Metric::Flip => Ok(ldr_flip(reference, test, &settings.flip)?.mean()),
        Metric::HdrFlip => Ok(hdr_flip(reference, test, &settings.flip)?.map.mean()),
    }
}

/// Each of `metrics` between `test` and `reference`, with default settings, in the order
/// asked.
pub fn compare_images(
    reference: &RgbImage,
    test: &RgbImage,
    metrics: &[Metric],
) -> Result<Vec<(Metric, f64)>, MetricsError> {
    compare_images_with(reference, test, metrics, &CompareSettings::default())
}

/// [`compare_images`] with explicit settings.
pub fn compare_images_with(
    reference: &RgbImage,
    test: &RgbImage,
    metrics: &[Metric],
    settings: &CompareSettings,
) -> Result<Vec<(Metric, f64)>, MetricsError> {
    metrics
        .iter()
        .map(|&m| Ok((m, measure(reference, test, m, settings)?)))
        .collect()
}

/// Reads two image files (`.exr` linear, `.png` decoded to linear) and compares them;
/// errors name both files.
pub fn compare_files(
    reference: &Path,
    test: &Path,
    metrics: &[Metric],
    settings: &CompareSettings,
) -> Result<Vec<(Metric, f64)>, MetricsError> {
    let r = RgbImage::read(reference)?;
    let t = RgbImage::read(test)?;
    compare_images_with(&r, &t, metrics, settings).map_err(|e| MetricsError::Pair {
        reference: reference.to_owned(),
        test: test.to_owned(),
        source: Box::new(e),
    })
}

/// The comparison of one file present in both folders.
#[derive(Clone, Debug, PartialEq)]
pub struct FileComparison {
    /// File name (the same in both folders).
    pub name: String,
    /// The metric values, in the order asked.
    pub values: Vec<(Metric, f64)>,
}

/// The result of [`compare_folders`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FolderComparison {
    /// Files present in both folders, sorted by name.
    pub files: Vec<FileComparison>,
    /// Image files only in the reference folder.
    pub only_in_reference: Vec<String>,
    /// Image files only in the test folder.
    pub only_in_test: Vec<String>,
}

impl FolderComparison {
    /// One row per file: `file`, then one column per metric.
    pub fn to_table(&self) -> Table {
        let mut columns = vec!["file".to_owned()];
        if let Some(first) = self.files.first() {
            columns.extend(first.values.iter().map(|(m, _)| m.name().to_owned()));
        }
        let rows = self
            .files
            .iter()
            .map(|f| {
                std::iter::once(Cell::Text(f.name.clone()))
                    .chain(f.values.iter().map(|&(_, v)| Cell::Number(v)))
                    .collect()
            })
            .collect();
        Table { columns, rows }
    }

    /// Mean of each metric over the files (`None` when no file matched).
    pub fn means(&self) -> Option<Vec<(Metric, f64)>> {
        let first = self.files.first()?;
        let n = self.files.len() as f64;
        Some(
            first
                .values
                .iter()
                .enumerate()
                .map(|(i, &(m, _))| (m, self.files.iter().map(|f| f.values[i].1).sum::<f64>() / n))
                .collect(),
        )
    }
}

/// Compares every `.exr`/`.png` file of `test_dir` with the same-named file of
/// `reference_dir`. Files present on one side only are listed, not errors.
pub fn compare_folders(
    reference_dir: &Path,
    test_dir: &Path,
    metrics: &[Metric],
    settings: &CompareSettings,
) -> Result<FolderComparison, MetricsError> {
    let reference_names = image_names(reference_dir)?;
    let test_names = image_names(test_dir)?;
    let mut out = FolderComparison::default();
    for name in &test_names {
        if reference_names.contains(name) {
            let values = compare_files(
                &reference_dir.join(name),
                &test_dir.join(name),
                metrics,
                settings,
            )?;
            out.files.push(FileComparison {
                name: name.clone(),
                values,
            });
        } else {
            out.only_in_test.push(name.clone());
        }
    }
    out.only_in_reference = reference_names
        .into_iter()
        .filter(|n| !test_names.contains(n))
        .collect();
    Ok(out)
}

/// Sorted names of the `.exr` and `.png` files directly in `dir`.
fn image_names(dir: &Path) -> Result<Vec<String>, MetricsError> {
    let entries = std::fs::read_dir(dir).map_err(|e| MetricsError::io(dir, e))?;
    let mut names = Vec::new();
    for entry in entries {
        let path: PathBuf = entry.map_err(|e| MetricsError::io(dir, e))?.path();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let name = path.file_name().and_then(|n| n.to_str());
        if let (true, Some(name)) = (
            path.is_file() && matches!(ext.as_deref(), Some("exr" | "png")),
            name,
        ) {
            names.push(name.to_owned());
        }
    }
    names.sort();
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::Rgb;
    use illume_core::image::ToneMap;

    #[test]
    fn metric_names_round_trip() {
        for m in Metric::ALL {
            assert_eq!(m.name().parse::<Metric>().unwrap(), m);
            assert_eq!(m.to_string(), m.name());
        }
        assert_eq!("HDR-FLIP".parse::<Metric>().unwrap(), Metric::HdrFlip);
        let e = "mse".parse::<Metric>().unwrap_err();
        assert!(e.to_string().contains("hdr-flip"), "{e}");
        assert_eq!(
            parse_metric_list("rmse, flip").unwrap(),
            vec![Metric::Rmse, Metric::Flip]
        );
    }

    #[test]
    fn compare_images_keeps_order_and_values() {
        let a = RgbImage::filled(16, 16, Rgb::splat(0.5));
        let b = RgbImage::filled(16, 16, Rgb::splat(0.25));
        let v = compare_images(&a, &b, &[Metric::Psnr, Metric::Rmse]).unwrap();
        assert_eq!(v[0], (Metric::Psnr, 20.0 * 4f64.log10()));
        assert_eq!(v[1], (Metric::Rmse, 0.25));
    }

    #[test]
    fn compare_folders_pairs_by_name() {
        let root =
            std::env::temp_dir().join(format!("illume-metrics-folders-{}", std::process::id()));
        let (ref_dir, test_dir) = (root.join("ref"), root.join("test"));
        std::fs::create_dir_all(&ref_dir).unwrap();
        std::fs::create_dir_all(&test_dir).unwrap();
        let a = RgbImage::filled(12, 12, Rgb::splat(1.0));
        let b = RgbImage::filled(12, 12, Rgb::splat(1.5));
        let tone = ToneMap::default();
        a.write(&ref_dir.join("frame.exr"), &tone).unwrap();
        b.write(&test_dir.join("frame.exr"), &tone).unwrap();
        a.write(&ref_dir.join("only_ref.exr"), &tone).unwrap();
        b.write(&test_dir.join("only_test.exr"), &tone).unwrap();
        let c = compare_folders(
            &ref_dir,
            &test_dir,
            &[Metric::Rmse],
            &CompareSettings::default(),
        )
        .unwrap();
        assert_eq!(
            c.files,
            vec![FileComparison {
                name: "frame.exr".into(),
                values: vec![(Metric::Rmse, 0.5)]
            }]
        );
        assert_eq!(c.only_in_reference, vec!["only_ref.exr".to_owned()]);
        assert_eq!(c.only_in_test, vec!["only_test.exr".to_owned()]);
        assert_eq!(c.to_table().columns, vec!["file", "rmse"]);

        // A size mismatch names both files.
        RgbImage::filled(8, 8, Rgb::ONE)
            .write(&test_dir.join("frame.exr"), &tone)
            .unwrap();
        let e = compare_folders(
            &ref_dir,
            &test_dir,
            &[Metric::Rmse],
            &CompareSettings::default(),
        )
        .unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("ref/frame.exr") && msg.contains("test/frame.exr"),
            "{msg}"
        );
        std::fs::remove_dir_all(&root).unwrap();
    }
}
