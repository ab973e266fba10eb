//! `illume view`: the interactive window (crate `illume-view`).

use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `illume view`.
#[derive(Args)]
#[command(after_help = crate::setup::techniques_help())]
pub struct ViewArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME.
    pub scene: PathBuf,
    /// Technique, image size and configuration file.
    #[command(flatten)]
    pub setup: crate::setup::SetupArgs,
    /// Animation to play (default: the scene's first).
    #[arg(long)]
    pub animation: Option<String>,
    /// Scene time [s] to start at.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::finite_f64, allow_hyphen_values = true)]
    pub time: f64,
    /// Start with the animation playing.
    #[arg(long)]
    pub play: bool,
    /// Start in reference mode (progressive path tracing).
    #[arg(long)]
    pub reference: bool,
    /// Samples per pixel the reference accumulates before it stops (at least 1)
    /// [default: the reference's `spp` setting].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Exposure [stops] added to the automatic one, within ±64.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::exposure_stops, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Start with the stats overlay on the image shown (O toggles it; off by default: at
    /// 640×480 it covers half the image).
    #[arg(long)]
    pub stats: bool,
    /// The overlay is hidden by default now; kept so older command lines still run.
    #[arg(long, hide = true)]
    pub hide_stats: bool,
    /// Random seed of the renderer and the technique.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Folder for screenshots (P) and clips (K).
    #[arg(long, default_value = "out/view")]
    pub output: PathBuf,
    /// Test mode: write this PNG (and the EXR beside it), tone-mapped as `render` writes
    /// it, once --exit-after-frames frames were shown and the reference has --spp
    /// samples; then exit.
    #[arg(long, requires = "exit_after_frames")]
    pub screenshot: Option<PathBuf>,
    /// Test mode: frames to display before the screenshot and exit.
    #[arg(long)]
    pub exit_after_frames: Option<u64>,
    /// Test mode: keep the window open this long after the screenshot [ms].
    #[arg(long, default_value_t = 0)]
    pub linger_ms: u64,
    /// Close the window after this many seconds [s] (benchmarks).
    #[arg(long, value_parser = crate::setup::finite_f64)]
    pub duration: Option<f64>,
    /// Print a timestamped line for each input event handled and each frame shown.
    #[arg(long)]
    pub log_input: bool,
    /// Most technique frames a second; 0: no limit. The window shows at most one frame
    /// per refresh (≈ 60 a second): faster frames are never seen, and their cores go to
    /// the technique's own threads (more photons a second for photon_stream).
    #[arg(long, default_value_t = 60.0, value_parser = max_fps, allow_negative_numbers = true)]
    pub max_fps: f64,
    /// Frames the window averages once the view rests (the technique settled): the frame
    /// at pixel centres and N − 1 more, each sampling its pixels at another point of the
    /// pixel; edges and fine texture converge to the box filter of a supersampled image.
    /// 0 or 1: off. A command or any change starts again from one centre-sampled frame.
    #[arg(long, default_value_t = 64)]
    pub refine: u32,
}

/// `--max-fps`: a finite number ≥ 0.
fn max_fps(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        Ok(v) => Err(format!(
            "{v} is not a number of frames a second ≥ 0 (0: no limit)"
        )),
        Err(e) => Err(format!("{s:?}: {e}")),
    }
}

/// Runs `illume view`.
pub fn run(a: ViewArgs) -> Result<()> {
    if let Some(p) = &a.screenshot
        && p.extension().and_then(|e| e.to_str()) != Some("png")
    {
        anyhow::bail!("--screenshot {}: must be a .png file", p.display());
    }
    let mut config = a.setup.config(None)?;
    if let Some(s) = a.seed {
        config.set_seed(s);
    }
    let scene = a
        .setup
        .load_scene(&a.scene, a.animation.as_deref(), a.time)?;
    illume_view::run(illume_view::ViewOptions {
        scene,
        config,
        reference_spp: a.spp,
        reference: a.reference,
        play: a.play,
        exposure_ev: a.exposure,
        stats: a.stats && !a.hide_stats,
        screenshot: a.screenshot,
        exit_after_frames: a.exit_after_frames,
        linger_ms: a.linger_ms,
        log_input: a.log_input,
        duration_s: a.duration,
        output_dir: a.output,
        max_fps: a.max_fps,
        refine_frames: a.refine,
    })?;
    Ok(())
}
