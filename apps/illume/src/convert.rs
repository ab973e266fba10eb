//! `illume convert IN.exr OUT.png`: a linear image tone-mapped the way `render` writes
//! PNGs (the same automatic exposure, `--exposure` stops on top, the same ACES curve and
//! sRGB encoding, through [`illume_core::image::RgbImage::write`]).

use anyhow::{Result, bail};
use clap::Args;
use illume_core::image::{RgbImage, ToneMap, auto_exposure_ev};
use std::path::PathBuf;

/// Arguments of `illume convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// The linear image to read (.exr, or .hdr).
    pub input: PathBuf,
    /// The image to write: .png (tone-mapped, as `render` writes one) or .exr (linear).
    pub output: PathBuf,
    /// Exposure [stops] added to the automatic one (or to 0 with `--exposure-mode
    /// fixed`), within ±64.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::exposure_stops, allow_hyphen_values = true)]
    pub exposure: f32,
    /// `auto` (default): exposure from the image (log-average luminance to middle grey),
    /// as `render` picks it; `fixed`: exposure 0 + `--exposure`.
    #[arg(long, value_enum, default_value_t)]
    pub exposure_mode: crate::setup::ExposureMode,
}

/// Runs `illume convert`.
pub fn run(a: ConvertArgs) -> Result<()> {
    crate::render::check_output(&a.output)?;
    if a.input == a.output {
        bail!(
            "{}: the input and the output are the same file",
            a.input.display()
        );
    }
    let image = RgbImage::read(&a.input)?;
    if let Some((x, y, v)) = image.first_non_finite() {
        bail!(
            "{}: pixel ({x}, {y}) = {v} is not finite: it cannot be tone-mapped",
            a.input.display()
        );
    }
    let tone = ToneMap {
        exposure_ev: a.exposure_mode.stops(auto_exposure_ev(&image), a.exposure),
        ..Default::default()
    };
    image.write(&a.output, &tone)?;
    eprintln!(
        "wrote {} (exposure {:+.2} EV, {:?})",
        a.output.display(),
        tone.exposure_ev,
        a.exposure_mode
    );
    Ok(())
}
