//! `illume render`.

use crate::progress;
use anyhow::{Context, Result};
use clap::Args;
use illume_core::image::{RgbImage, ToneMap, auto_exposure_ev};
use illume_engine::render_still;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `illume render`.
#[derive(Args)]
#[command(after_help = crate::setup::techniques_help())]
pub struct RenderArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME.
    pub scene: PathBuf,
    /// Technique, image size and configuration file.
    #[command(flatten)]
    pub setup: crate::setup::SetupArgs,
    /// Scene time [s] at which the active animation is evaluated.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::finite_f64, allow_hyphen_values = true)]
    pub time: f64,
    /// Animation to play (default: the scene's first).
    #[arg(long)]
    pub animation: Option<String>,
    /// Samples per pixel of the still (at least 1), for techniques that have such a
    /// setting (the reference's `spp`); others warn that it is ignored.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Output image: .exr (linear radiance) or .png (tone-mapped sRGB).
    #[arg(long, short, default_value = "out/render.png")]
    pub output: PathBuf,
    /// Also write FILE_direct and FILE_indirect beside the output.
    #[arg(long)]
    pub split: bool,
    /// Exposure for PNG output [stops] added to the automatic one (or to 0 with
    /// `--exposure-mode fixed`), within ±64.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::exposure_stops, allow_hyphen_values = true)]
    pub exposure: f32,
    /// `auto` (default): PNG exposure from the image (log-average luminance to middle
    /// grey); `fixed`: exposure 0 + `--exposure`.
    #[arg(long, value_enum, default_value_t)]
    pub exposure_mode: crate::setup::ExposureMode,
    /// Random seed of the renderer and the technique.
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// `--technique reference` only: filter the still's noise with the à-trous
    /// denoiser (`illume_render::denoise`), guided by albedo, normal and position (direct and indirect
    /// light each). For looking at, never ground truth: bench, the agreement checks and
    /// the tests take their references unfiltered.
    #[arg(long)]
    pub denoise: bool,
    /// Anti-alias the still: render it at K times the width and height and average each
    /// K×K block (a box filter, as the reference path tracer's pixels are). An
    /// interactive technique's G-buffer takes one sample at each pixel centre, so its
    /// edges are jagged against the reference; 2 removes most of that (HDR-FLIP 0.066 →
    /// 0.058 for photon_stream's still of `builtin:cornell-spot` at 320×240,
    /// docs/benchmarks/renderer.md). Costs about K² times the time and memory. 1–4,
    /// default 1 (off).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4))]
    pub supersample: u32,
}

/// Loads a scene given on the command line (file or builtin:NAME) with `options`
/// (`--strict`, `--units`), selects its animation and moves it to `time`, optionally
/// relit by [`illume_scene::builtin::spot_from_above`]; prints load warnings.
pub fn load_scene_with(
    path: &Path,
    animation: Option<&str>,
    time: f64,
    spot_from_above: bool,
    options: &illume_scene::LoadOptions,
) -> Result<illume_scene::Scene> {
    let t0 = Instant::now();
    let mut scene = illume_scene::load_scene_with(path, options)?;
    if spot_from_above {
        scene = illume_scene::builtin::spot_from_above(scene);
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(name) = animation {
        scene.select_animation(name).map_err(anyhow::Error::msg)?;
    }
    scene.set_time(time);
    let dt = t0.elapsed().as_secs_f64();
    if dt > 0.5 {
        eprintln!("loaded {} in {dt:.2} s", path.display());
    }
    Ok(scene)
}

/// `path` with `_suffix` added to the file stem.
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("render");
    let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("png");
    path.with_file_name(format!("{stem}_{suffix}.{ext}"))
}

/// True when `path` is written tone-mapped (8-bit), i.e. not as linear EXR.
fn is_png(path: &Path) -> bool {
    path.extension().and_then(|s| s.to_str()) != Some("exr")
}

fn write(img: &RgbImage, path: &Path, tone: &ToneMap) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    }
    img.write(path, tone)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Checks that `-o OUTPUT` is .exr (linear) or .png (tone-mapped) and creates its folder.
pub fn check_output(output: &Path) -> Result<()> {
    match output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("exr") | Some("png") => {}
        _ => anyhow::bail!(
            "-o {}: the output must be .exr (linear) or .png (tone-mapped)",
            output.display()
        ),
    }
    if let Some(parent) = output.parent()
        && !parent.as_os_str().is_empty()
    {
        std::fs::create_dir_all(parent).with_context(|| {
            format!(
                "-o {}: cannot create the folder {}",
                output.display(),
                parent.display()
            )
        })?;
    }
    Ok(())
}

/// Runs `illume render`.
pub fn run(a: RenderArgs) -> Result<()> {
    // A still wants the converged look, not the interactive one, and the same image on
    // every run: the technique's `still` preset, when it has one and neither --preset
    // nor --config says otherwise.
    // The output must be writable as asked before minutes of rendering: a known format
    // in a folder that exists (created here if need be).
    check_output(&a.output)?;
    let mut config = a.setup.config(Some("still"))?;
    if let Some(s) = a.spp
        && !config.technique_settings_mut().set_samples_per_pixel(s)
    {
        eprintln!(
            "warning: --spp {s}: {} has no samples-per-pixel setting; ignored",
            config.technique
        );
    }
    if let Some(s) = a.seed {
        config.set_seed(s);
    }
    let size = (config.render.width, config.render.height);
    let k = a.supersample;
    if k > 1 {
        config.render.width = size.0.saturating_mul(k);
        config.render.height = size.1.saturating_mul(k);
        config
            .check()
            .map_err(|e| anyhow::anyhow!("--supersample {k}: {e}"))?;
        // Said up front: the cost is K² times the pixels, whatever the technique (a path
        // tracer's samples per pixel multiply by K² too).
        eprintln!(
            "--supersample {k}: rendering {}×{} ({} times the pixels), then averaging {k}×{k} blocks",
            config.render.width,
            config.render.height,
            k * k
        );
    }
    let scene = a
        .setup
        .load_scene(&a.scene, a.animation.as_deref(), a.time)?;
    let t0 = Instant::now();
    let mut bars = progress::Bars::with_spinner(&format!("{}: rendering", config.technique));
    let still = if a.denoise {
        illume_engine::render_denoised_still(scene, &config, &mut bars)
    } else {
        render_still(scene, &config, &mut bars)
    }
    .map_err(anyhow::Error::from);
    bars.finish();
    let mut still = still?;
    if k > 1 {
        still.full = still.full.box_downsample(k);
        still.direct = still.direct.box_downsample(k);
        still.indirect = still.indirect.box_downsample(k);
        (config.render.width, config.render.height) = size;
    }
    let secs = t0.elapsed().as_secs_f64();
    let m = still.full.mean();
    eprintln!(
        "{} {}×{} in {secs:.2} s{}; mean radiance ({:.5}, {:.5}, {:.5}) W/(m²·sr)",
        config.technique,
        config.render.width,
        config.render.height,
        if still.precompute_ms > 0.0 {
            format!(" ({:.2} s precompute)", still.precompute_ms / 1e3)
        } else {
            String::new()
        },
        m.x,
        m.y,
        m.z
    );
    // One exposure for the full image and its split parts, so they stay comparable.
    let tone = ToneMap {
        exposure_ev: a
            .exposure_mode
            .stops(auto_exposure_ev(&still.full), a.exposure),
        ..Default::default()
    };
    if is_png(&a.output) {
        eprintln!(
            "exposure {:+.2} EV ({:?}{})",
            tone.exposure_ev,
            a.exposure_mode,
            if a.exposure != 0.0 {
                format!(", {:+} from --exposure", a.exposure)
            } else {
                String::new()
            }
        );
    }
    write(&still.full, &a.output, &tone)?;
    if a.split {
        write(&still.direct, &with_suffix(&a.output, "direct"), &tone)?;
        write(&still.indirect, &with_suffix(&a.output, "indirect"), &tone)?;
    }
    Ok(())
}
