//! `illume animate` and `illume demo`: render an animation frame by frame with a
//! technique, write numbered frames, an animated preview and a per-frame CSV.

use crate::frames::{Frame, FrameWriter, WriterPriority};
use crate::progress;
use crate::setup::ExposureMode;
use anyhow::{Context, Result, bail};
use clap::Args;
use illume_core::Shard;
use illume_core::image::{ToneMap, auto_exposure_ev, to_srgb8};
use illume_engine::{Config, Engine, FrameHistory, FramesCsv, StepRecord, TechniqueKind};
use illume_scene::timeline::ping_pong_time;
use illume_scene::{Scene, Timeline};
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
    /// Render only the frames with index mod N = K, as linear frame_NNNNN.exr and
    /// frames_K_of_N.csv in the output folder (which the N shards share), for
    /// `--collect N`. Only for techniques whose frames do not build on the frames before:
    /// `reference`, when every frame moves something (it restarts its average at each
    /// change); others are refused.
    #[arg(long, value_name = "K/N", conflicts_with_all = ["realtime", "collect"])]
    pub shard: Option<Shard>,
    /// Gather the frames of N shards (`--shard K/N`, run with the same flags) in the
    /// output folder: tone-map them with one exposure as the unsharded run does, write
    /// the PNG frames, frames.csv and the preview; the EXR frames stay with --exr.
    #[arg(long, value_name = "N", conflicts_with = "realtime")]
    pub collect: Option<u32>,
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
    config
        .pace(if a.realtime {
            Pacing::RealTime
        } else {
            Pacing::FixedWork {
                work_per_frame: a.work_per_frame,
            }
        })
        .map_err(anyhow::Error::msg)?;
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
    if let Some(n) = a.collect {
        return collect(&a, n, planned, w, h);
    }
    if let Some(shard) = a.shard {
        return run_shard(&a, &config, scene, times, shard);
    }
    let out_dir = crate::frames::prepare_output(&a.output)?;
    // Fixed: known now. Auto: from the first frame with light, then kept for the sequence.
    let mut exposure_ev = match a.exposure_mode {
        ExposureMode::Fixed => Some(a.exposure),
        ExposureMode::Auto => None,
    };
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
    let mut csv = FramesCsv::default();
    let priority = if a.realtime {
        WriterPriority::Idle
    } else {
        WriterPriority::Low
    };
    let mut writer = FrameWriter::start(&out_dir, w, h, priority)?;
    let start = Instant::now();
    let mut render_s = 0.0;
    let mut index = 0u64;
    // Wall time at each frame's record (frames.csv's `wall_s`): the median interval
    // between consecutive frames is the rate a viewer sees, robust to the first frame's
    // start-up and to a stall.
    let mut walls: Vec<f64> = Vec::new();
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
        // Precompute is its own column: frame 0 carries the phase before the first
        // frame, any frame a rebuild's.
        let earlier_ms = if index == 0 { precompute_ms } else { 0.0 };
        walls.push(start.elapsed().as_secs_f64());
        csv.push(&StepRecord {
            frame: index,
            wall_s: *walls.last().expect("pushed above"),
            ..StepRecord::from_step(t, &out, earlier_ms)
        });
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
    out_dir.write_file("frames.csv", csv.text())?;
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
    if let Some(ms) = median_interval_ms(&walls) {
        eprintln!(
            "median frame {ms:.2} ms ({:.2} frames per second) over {} frame intervals",
            1e3 / ms,
            walls.len().saturating_sub(1).max(1)
        );
    }
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

/// The median of the intervals between consecutive frames' wall times, in ms (the
/// first frame's own time when there is only one); `None` without frames.
fn median_interval_ms(walls: &[f64]) -> Option<f64> {
    let mut d: Vec<f64> = match walls {
        [] => return None,
        [only] => vec![*only],
        _ => walls.windows(2).map(|w| w[1] - w[0]).collect(),
    };
    d.sort_by(f64::total_cmp);
    let m = d.len() / 2;
    let median = if d.len() % 2 == 1 {
        d[m]
    } else {
        0.5 * (d[m - 1] + d[m])
    };
    Some(median * 1e3)
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
        shard: None,
        collect: None,
    })
}

/// Refuses `--shard` where a shard's frames would differ from the unsharded run's: a
/// technique that carries state from frame to frame, or `reference` on a frame that
/// shows no change from the one before (it would average the frames before it).
fn check_shardable(
    technique: TechniqueKind,
    scene: &Scene,
    times: &[f64],
    shard: Shard,
) -> Result<()> {
    match technique.frame_history() {
        FrameHistory::Carried(why) => bail!(
            "--shard {shard}: {technique} carries state from frame to frame ({why}): a shard, \
             which renders every {}th frame alone, would not give the unsharded frames; render \
             the sequence unsharded",
            shard.count
        ),
        FrameHistory::RestartsOnChange => {
            let mut state = scene.clone();
            state.set_time(times[0]);
            for (i, &t) in times.iter().enumerate().skip(1) {
                if state.set_time(t).is_empty() {
                    bail!(
                        "--shard {shard}: {technique} averages its samples over the frames \
                         while the scene is still, and frame {i} (t = {t:.3} s) shows no \
                         change from frame {}: unsharded it builds on the frames before, a \
                         shard renders it alone. Shard only sequences in which every frame \
                         moves something, or render this one unsharded",
                        i - 1
                    );
                }
            }
            Ok(())
        }
    }
}

/// `animate --shard K/N`: the frames with index mod N = K, each from a technique reset
/// to its state after a scene change (what the unsharded run has at that frame, as
/// [`check_shardable`] ensures) and with the renderer's frame index set to the frame's
/// (its direct-light samples): linear `frame_NNNNN.exr` and `frames_K_of_N.csv`.
fn run_shard(
    a: &AnimateArgs,
    config: &Config,
    scene: Scene,
    times: Vec<f64>,
    shard: Shard,
) -> Result<()> {
    check_shardable(config.technique, &scene, &times, shard)?;
    let out_dir = crate::frames::prepare_shard_output(&a.output, shard)?;
    let (w, h) = (config.render.width, config.render.height);
    let planned = times.len();
    let timeline = Timeline::new(scene.clone(), times.clone(), w, h)?;
    let mut engine = Engine::with_timeline(scene, config, timeline)?;
    let mut bars = progress::Bars::default();
    let precompute_ms = engine.precompute(&mut bars)?;
    bars.finish();
    let mine: Vec<usize> = (0..planned).filter(|&i| shard.owns(i)).collect();
    let pb = progress::bar(mine.len() as u64, "frames");
    let start = Instant::now();
    let mut csv = FramesCsv::default();
    for (done, &i) in mine.iter().enumerate() {
        engine.technique_mut().reset();
        engine.set_frame_index(i as u64);
        let out = engine.step(times[i])?;
        let earlier_ms = if done == 0 { precompute_ms } else { 0.0 };
        csv.push(&StepRecord {
            frame: i as u64,
            wall_s: start.elapsed().as_secs_f64(),
            ..StepRecord::from_step(times[i], &out, earlier_ms)
        });
        crate::frames::write_exr_recorded(&out_dir, &format!("frame_{i:05}.exr"), &out.frame.full)?;
        pb.set_position(done as u64 + 1);
    }
    pb.finish_and_clear();
    out_dir.write_file(&crate::frames::shard_csv_name(shard), csv.text())?;
    eprintln!(
        "shard {shard}: {} of {planned} frames of {w}×{h} with {} in {:.2} s into {} (gather them with --collect {})",
        mine.len(),
        config.technique,
        start.elapsed().as_secs_f64(),
        a.output.display(),
        shard.count
    );
    Ok(())
}

/// `animate --collect N`: the N shards' frames in the output folder become the unsharded
/// run's outputs: PNG frames tone-mapped with the exposure the unsharded run picks (the
/// first frame with light, in frame order), frames.csv (the shards' rows in frame order;
/// `wall_s` is each shard's own clock), the preview. The shards' CSVs are removed, and
/// their EXR frames unless `--exr`.
fn collect(a: &AnimateArgs, n: u32, planned: u64, w: u32, h: u32) -> Result<()> {
    if n == 0 {
        bail!("--collect 0: give the number of shards N (≥ 1)");
    }
    let dir = &a.output;
    // Nothing is removed or overwritten unless every file in the folder is illume's.
    let out_dir = crate::frames::OutputDir::create(dir)?;
    let foreign: Vec<String> = out_dir
        .survey()?
        .into_iter()
        .filter_map(|e| match e {
            crate::frames::Entry::Proven(_) => None,
            crate::frames::Entry::Pending(n) | crate::frames::Entry::Foreign(n) => Some(n),
        })
        .collect();
    out_dir.refuse_foreign(foreign)?;
    // Every frame first: a missing one names its shard before anything is written.
    let exr = |i: u64| dir.join(format!("frame_{i:05}.exr"));
    for i in 0..planned {
        if !exr(i).is_file() {
            bail!(
                "{}: missing: frame {i} is shard {}/{n}'s (its job failed, or ran with other flags)",
                exr(i).display(),
                i % u64::from(n)
            );
        }
    }
    let mut header: Option<(String, std::path::PathBuf)> = None;
    let mut rows: Vec<(u64, String)> = Vec::new();
    for k in 0..n {
        let path = dir.join(crate::frames::shard_csv_name(Shard { index: k, count: n }));
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "{}: cannot read shard {k}/{n}'s frame table",
                path.display()
            )
        })?;
        let mut lines = text.lines();
        let first = lines.next().unwrap_or_default().to_owned();
        match &header {
            Some((h0, p0)) if *h0 != first => bail!(
                "{}: its columns differ from {}'s: shards of different runs?",
                path.display(),
                p0.display()
            ),
            Some(_) => {}
            None => header = Some((first, path.clone())),
        }
        for line in lines.filter(|l| !l.is_empty()) {
            let index: u64 = line
                .split(',')
                .next()
                .and_then(|f| f.parse().ok())
                .with_context(|| format!("{}: bad row {line:?}", path.display()))?;
            rows.push((index, line.to_owned()));
        }
    }
    rows.sort_by_key(|r| r.0);
    let indices: Vec<u64> = rows.iter().map(|r| r.0).collect();
    if indices != (0..planned).collect::<Vec<_>>() {
        bail!(
            "{}: the shards' frame tables list {} rows, not frames 0–{}: shards of different runs?",
            dir.display(),
            rows.len(),
            planned.saturating_sub(1)
        );
    }
    // Stale frames of a longer earlier run.
    for entry in
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?
    {
        let entry = entry.with_context(|| format!("{}: cannot list", dir.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if crate::frames::frame_number(&name).is_some_and(|i| i >= planned) {
            out_dir.remove(&name)?;
        }
    }
    let mut exposure_ev = match a.exposure_mode {
        ExposureMode::Fixed => Some(a.exposure),
        ExposureMode::Auto => None,
    };
    let mut writer = FrameWriter::start(&out_dir, w, h, WriterPriority::Low)?;
    let pb = progress::bar(planned, "frames");
    for i in 0..planned {
        let frame = illume_core::image::RgbImage::read(&exr(i))?;
        if (frame.width(), frame.height()) != (w, h) {
            bail!(
                "{}: {}×{}, not {w}×{h}: shards of another run?",
                exr(i).display(),
                frame.width(),
                frame.height()
            );
        }
        if exposure_ev.is_none() {
            exposure_ev = auto_exposure_ev(&frame).map(|ev| ev + a.exposure);
        }
        let tone = ToneMap {
            exposure_ev: exposure_ev.unwrap_or(a.exposure),
            ..Default::default()
        };
        writer.push(Frame {
            index: i,
            shown_s: i as f64 / a.fps,
            srgb8: to_srgb8(&frame, &tone),
            hdr: None,
        })?;
        pb.set_position(i + 1);
    }
    pb.finish_and_clear();
    let preview = writer.finish(a.fps)?;
    let csv_path = dir.join("frames.csv");
    let mut csv = header.map(|h| h.0).unwrap_or_default();
    for (_, r) in &rows {
        csv.push('\n');
        csv.push_str(r);
    }
    csv.push('\n');
    out_dir.write_file("frames.csv", csv)?;
    for k in 0..n {
        out_dir.remove(&crate::frames::shard_csv_name(Shard { index: k, count: n }))?;
    }
    if !a.exr {
        for i in 0..planned {
            out_dir.remove(&format!("frame_{i:05}.exr"))?;
        }
    }
    eprintln!(
        "collected {planned} frames of {n} shards: exposure {:+.2} EV ({:?}); wrote {}/frame_NNNNN.png{}, {}, {}",
        exposure_ev.unwrap_or(a.exposure),
        a.exposure_mode,
        dir.display(),
        if a.exr { " (+ .exr)" } else { "" },
        csv_path.display(),
        preview.display()
    );
    Ok(())
}
