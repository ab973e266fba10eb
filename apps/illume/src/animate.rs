//! `illume animate` and `illume demo`: render an animation frame by frame with a
//! technique, write numbered frames, an animated preview and a per-frame CSV.

use crate::frames::{Frame, FrameWriter};
use crate::progress;
use crate::setup::ExposureMode;
use anyhow::{Context, Result, bail};
use clap::Args;
use illume_core::image::{ToneMap, auto_exposure_ev, to_srgb8};
use illume_engine::{Engine, TechniqueKind};
use illume_scene::Timeline;
use illume_scene::timeline::ping_pong_time;
use illume_transport::Pacing;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `illume animate`.
#[derive(Args, Clone)]
#[command(after_help = crate::setup::techniques_help())]
pub struct AnimateArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME.
    pub scene: PathBuf,
    /// Technique, image size and configuration file.
    #[command(flatten)]
    pub setup: crate::setup::SetupArgs,
    /// Animation to play (default: the scene's first).
    #[arg(long)]
    pub animation: Option<String>,
    /// Length of the sequence [s] (default: the animation's duration, or 2 s); frames at
    /// 0, 1/fps, …, duration, both ends included.
    #[arg(long, allow_negative_numbers = true)]
    pub duration: Option<f64>,
    /// Frames per second of scene time (deterministic mode) and of the preview.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
    pub fps: f64,
    /// Real time: scene time follows the wall clock, frames are rendered as fast as
    /// they come, and the technique runs its interactive mode (photon_stream: photons
    /// stream in a background thread).
    #[arg(long, conflicts_with = "work_per_frame")]
    pub realtime: bool,
    /// Reproducible frames: exactly N units of the technique's work between frames
    /// (photons, samples per pixel…: listed below). Default when --realtime is not
    /// given, with the technique's own amount.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub work_per_frame: Option<u64>,
    /// Play the animation forwards then backwards (ping-pong) when the sequence is
    /// longer than the animation.
    #[arg(long)]
    pub ping_pong: bool,
    /// Output folder: frame_NNNNN.png, frames.csv, preview.gif or preview.mp4.
    #[arg(long, short, default_value = "out/animate")]
    pub output: PathBuf,
    /// Also write linear frame_NNNNN.exr.
    #[arg(long)]
    pub exr: bool,
    /// Exposure for PNG and preview output [stops] added to the automatic one (or to 0
    /// with `--exposure-mode fixed`), within ±64.
    #[arg(long, default_value_t = 0.0, value_parser = crate::setup::exposure_stops, allow_hyphen_values = true)]
    pub exposure: f32,
    /// `auto` (default): one exposure for the whole sequence, from its first frame with
    /// light (log-average luminance to middle grey); `fixed`: 0 + `--exposure`.
    #[arg(long, value_enum, default_value_t)]
    pub exposure_mode: crate::setup::ExposureMode,
}

/// Arguments of `illume demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, short, default_value = "out/demo")]
    pub output: PathBuf,
    /// Length of the demo [s of wall-clock time].
    #[arg(long, default_value_t = 6.0)]
    pub duration: f64,
    /// Image width [pixels].
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height [pixels].
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// Set one photon_stream setting, TABLE.KEY=VALUE (repeatable), e.g.
    /// `photon_stream.vsl_count=200`.
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    pub sets: Vec<String>,
}

/// Runs `illume animate`.
pub fn run(a: AnimateArgs) -> Result<()> {
    let mut config = a.setup.config(None)?;
    config.technique_settings_mut().pace(if a.realtime {
        Pacing::RealTime
    } else {
        Pacing::FixedWork {
            work_per_frame: a.work_per_frame,
        }
    });
    if !(a.fps > 0.0 && a.fps.is_finite()) {
        bail!("--fps must be positive, got {}", a.fps);
    }
    let (w, h) = (config.render.width, config.render.height);
    let scene = a.setup.load_scene(&a.scene, a.animation.as_deref(), 0.0)?;
    let animation_s = scene.animation_duration();
    let duration = a
        .duration
        .unwrap_or(if animation_s > 0.0 { animation_s } else { 2.0 });
    if !(duration >= 0.0 && duration.is_finite()) {
        bail!("--duration must be a non-negative number of seconds");
    }
    crate::frames::prepare_output(&a.output)?;
    // Fixed: known now. Auto: from the first frame with light, then kept for the sequence.
    let mut exposure_ev = match a.exposure_mode {
        ExposureMode::Fixed => Some(a.exposure),
        ExposureMode::Auto => None,
    };
    if (duration * a.fps).round() >= 1e6 {
        bail!(
            "--duration {duration} s at --fps {} gives more than 1000000 frames",
            a.fps
        );
    }
    let planned = (duration * a.fps).round() as u64 + 1;
    // Every frame's scene time, in rendering order: the timeline handed to techniques
    // that need the future (in real time, the frames' nominal times).
    let times: Vec<f64> = (0..planned)
        .map(|i| ping_pong_time(i as f64 / a.fps, animation_s, a.ping_pong))
        .collect();
    let timeline = Timeline::new(scene.clone(), times, w, h)?;
    let mut engine = Engine::with_timeline(scene, &config, timeline)?;
    let mut bars = progress::Bars::default();
    let precompute_ms = engine.precompute(&mut bars)?;
    bars.finish();
    // In real time the bar counts tenths of a second of the sequence (the frame count is
    // not known in advance); otherwise frames.
    let pb = if a.realtime {
        progress::bar((duration * 10.0).ceil().max(1.0) as u64, "0.1 s")
    } else {
        progress::bar(planned, "frames")
    };
    let mut csv_header: Option<Vec<String>> = None;
    let mut csv_rows: Vec<String> = Vec::new();
    let mut writer = FrameWriter::start(&a.output, w, h)?;
    let start = Instant::now();
    let mut render_s = 0.0;
    let mut index = 0u64;
    loop {
        let t = if a.realtime {
            start.elapsed().as_secs_f64().min(duration)
        } else {
            index as f64 / a.fps
        };
        if !a.realtime && t > duration + 1e-9 {
            break;
        }
        let t_frame = Instant::now();
        let out = engine.step(ping_pong_time(t, animation_s, a.ping_pong))?;
        render_s += t_frame.elapsed().as_secs_f64() - out.precompute_ms / 1e3;
        let ft = out.frame.timings;
        let names: Vec<String> = out.stats.names().map(str::to_owned).collect();
        if csv_header.is_none() {
            csv_header = Some(names.clone());
        }
        // Precompute is its own column: frame 0 carries the phase before the first
        // frame, any frame a rebuild's.
        let frame_precompute_ms = out.precompute_ms + if index == 0 { precompute_ms } else { 0.0 };
        let mut row = format!(
            "{index},{t:.6},{:.6},{frame_precompute_ms:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3}",
            start.elapsed().as_secs_f64(),
            out.update_ms,
            out.advance_ms,
            ft.gbuffer_ms,
            ft.direct_ms,
            ft.indirect_ms,
            ft.total_ms
        );
        for (_, v) in out.stats.iter() {
            row += &format!(",{v}");
        }
        csv_rows.push(row);
        // Written on the writer thread while the next frames render (memory stays
        // bounded; before, real-time runs kept every frame until the end).
        writer.push(Frame {
            index,
            shown_s: if a.realtime { t } else { index as f64 / a.fps },
            srgb8: {
                if exposure_ev.is_none() {
                    exposure_ev = auto_exposure_ev(&out.frame.full).map(|ev| ev + a.exposure);
                }
                let tone = ToneMap {
                    exposure_ev: exposure_ev.unwrap_or(a.exposure),
                    ..Default::default()
                };
                to_srgb8(&out.frame.full, &tone)
            },
            hdr: a.exr.then(|| out.frame.full.clone()),
        })?;
        index += 1;
        if a.realtime {
            pb.set_position((t * 10.0) as u64);
        } else {
            pb.set_position(index.min(planned));
        }
        if a.realtime && t >= duration {
            break;
        }
    }
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let csv_path = a.output.join("frames.csv");
    use std::fmt::Write as _;
    let mut csv = String::new();
    let header = csv_header.unwrap_or_default();
    writeln!(
        csv,
        "frame,time_s,wall_s,precompute_ms,update_ms,advance_ms,gbuffer_ms,direct_ms,indirect_ms,render_ms{}",
        header.iter().map(|n| format!(",{n}")).collect::<String>()
    )?;
    for r in &csv_rows {
        writeln!(csv, "{r}")?;
    }
    illume_core::atomic::write_file(&csv_path, csv)
        .with_context(|| format!("{}: cannot write", csv_path.display()))?;
    let preview = writer.finish(if a.realtime {
        index as f64 / wall
    } else {
        a.fps
    })?;
    // A precompute (radiance caching's pass 1, …) is work for these frames: the headline
    // rate counts it.
    let precompute_s = precompute_ms / 1e3;
    eprintln!(
        "{} frames of {}×{} with {} in {wall:.2} s{}: {:.2} frames per second{} (rendering alone {:.2} fps)",
        index,
        w,
        h,
        config.technique,
        if precompute_ms > 0.0 {
            format!(" after {precompute_s:.2} s of precompute")
        } else {
            String::new()
        },
        index as f64 / (wall + precompute_s),
        if precompute_ms > 0.0 {
            format!(" with the precompute, {:.2} without", index as f64 / wall)
        } else {
            String::new()
        },
        index as f64 / render_s
    );
    eprintln!(
        "exposure {:+.2} EV ({:?})",
        exposure_ev.unwrap_or(a.exposure),
        a.exposure_mode
    );
    eprintln!(
        "wrote {}/frame_NNNNN.png{}, {}, {}",
        a.output.display(),
        if a.exr { " (+ .exr)" } else { "" },
        csv_path.display(),
        preview.display()
    );
    Ok(())
}

/// Runs `illume demo`: builtin:cornell-spot, sphere and spot light moving, photon
/// streaming in real time.
pub fn demo(d: DemoArgs) -> Result<()> {
    run(AnimateArgs {
        scene: PathBuf::from("builtin:cornell-spot"),
        setup: crate::setup::SetupArgs {
            technique: Some(TechniqueKind::PhotonStream),
            width: Some(d.width),
            height: Some(d.height),
            sets: d.sets,
            ..Default::default()
        },
        animation: Some("move".into()),
        duration: Some(d.duration),
        fps: 15.0,
        realtime: true,
        work_per_frame: None,
        ping_pong: true,
        output: d.output,
        exr: false,
        exposure: 0.0,
        exposure_mode: ExposureMode::Auto,
    })
}
