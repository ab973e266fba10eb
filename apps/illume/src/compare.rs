//! `illume compare`.

use anyhow::{Result, bail};
use clap::Args;
use illume_core::image::RgbImage;
use illume_metrics::{CompareSettings, Metric, compare_files, compare_folders, hdr_flip, ldr_flip};
use std::path::PathBuf;

/// Arguments of `illume compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// The reference image (or folder of frames).
    pub reference: PathBuf,
    /// The image (or folder of frames) to measure against it.
    pub test: PathBuf,
    /// Metrics, comma-separated: rmse, relmse, psnr, ssim, flip, hdr-flip.
    #[arg(long, default_value = "rmse,relmse,psnr,ssim,flip,hdr-flip")]
    pub metric: String,
    /// Write the FLIP error map (magma colour map) to this PNG (HDR-FLIP for EXR inputs).
    #[arg(long)]
    pub error_map: Option<PathBuf>,
}

/// Runs `illume compare`.
pub fn run(a: CompareArgs) -> Result<()> {
    let metrics = illume_metrics::compare::parse_metric_list(&a.metric)?;
    if metrics.is_empty() {
        bail!(
            "--metric {:?}: give at least one of rmse, relmse, psnr, ssim, flip, hdr-flip",
            a.metric
        );
    }
    if let Some(path) = &a.error_map {
        let png = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if path.is_dir() || !png {
            bail!(
                "--error-map {}: the error map is written as a PNG file: give a name ending in .png",
                path.display()
            );
        }
    }
    let settings = CompareSettings::default();
    match (a.reference.is_dir(), a.test.is_dir()) {
        (true, true) => {
            if a.error_map.is_some() {
                bail!("--error-map needs two images, not two folders");
            }
            let cmp = compare_folders(&a.reference, &a.test, &metrics, &settings)?;
            if cmp.files.is_empty() {
                bail!(
                    "{} and {}: no image file names in common",
                    a.reference.display(),
                    a.test.display()
                );
            }
            print!("{}", cmp.to_table().to_markdown());
            if let Some(means) = cmp.means() {
                println!();
                for (m, v) in means {
                    println!("mean {:<9} {}", m.name(), fmt_value(m, v));
                }
            }
            if let Some(means) = cmp.means()
                && let Some((m, _)) = means.iter().find(|(_, v)| v.is_nan())
            {
                eprintln!(
                    "warning: mean {} is NaN: some frames have non-finite pixels or metrics",
                    m.name()
                );
            }
            for n in &cmp.only_in_reference {
                eprintln!("warning: {n} only in {}", a.reference.display());
            }
            for n in &cmp.only_in_test {
                eprintln!("warning: {n} only in {}", a.test.display());
            }
        }
        (false, false) => {
            let r = RgbImage::read(&a.reference)?;
            let t = RgbImage::read(&a.test)?;
            // A NaN or infinite pixel makes every metric NaN (or FLIP's exposure fail):
            // refused, naming the pixel.
            for (path, image) in [(&a.reference, &r), (&a.test, &t)] {
                if let Some((x, y, v)) = image.first_non_finite() {
                    bail!(
                        "{}: pixel ({x}, {y}) = {v} is not finite: the metrics would be NaN",
                        path.display()
                    );
                }
            }
            let linear = |p: &std::path::Path| {
                p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("exr") || e.eq_ignore_ascii_case("hdr"))
            };
            if linear(&a.reference) != linear(&a.test) {
                eprintln!(
                    "warning: {} and {}: one is linear radiance (EXR/HDR), the other tone-mapped \
                     8-bit (PNG): the metrics compare different quantities (convert the EXR with \
                     `illume convert` first, or compare two EXRs)",
                    a.reference.display(),
                    a.test.display()
                );
            }
            for (m, v) in compare_files(&a.reference, &a.test, &metrics, &settings)? {
                if v.is_nan() {
                    eprintln!("warning: {} is NaN for these images", m.name());
                }
                println!("{:<9} {}", m.name(), fmt_value(m, v));
            }
            print!("{}", channel_means(&r, &t));
            if let Some(path) = &a.error_map {
                let is_hdr = a
                    .reference
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
                let map = if is_hdr {
                    hdr_flip(&r, &t, &settings.flip)?.map
                } else {
                    ldr_flip(&r, &t, &settings.flip)?
                };
                map.write_png(path)?;
                eprintln!("wrote {}", path.display());
            }
        }
        _ => bail!("compare two images or two folders, not one of each"),
    }
    Ok(())
}

/// Per-channel means of both images and the test's relative difference: a bias in
/// energy or colour that per-pixel metrics do not name.
fn channel_means(reference: &RgbImage, test: &RgbImage) -> String {
    let (mr, mt) = (reference.mean(), test.mean());
    let rel = |t: f32, r: f32| {
        if r > 0.0 {
            format!("{:+.2} %", 100.0 * (t as f64 / r as f64 - 1.0))
        } else {
            "-".to_string()
        }
    };
    format!(
        "mean ref  {:.6} {:.6} {:.6}\nmean test {:.6} {:.6} {:.6}\nmean diff {} {} {}\n",
        mr.x,
        mr.y,
        mr.z,
        mt.x,
        mt.y,
        mt.z,
        rel(mt.x, mr.x),
        rel(mt.y, mr.y),
        rel(mt.z, mr.z)
    )
}

fn fmt_value(m: Metric, v: f64) -> String {
    if v.is_infinite() {
        format!("{v}")
    } else if m == Metric::Psnr {
        format!("{v:.3} dB")
    } else {
        format!("{v:.6}")
    }
}
