//! Frames of `animate` and `demo` written to disk while the sequence renders, on a
//! background thread, with the preview GIF encoded as frames arrive: memory stays bounded
//! however long the sequence (before, real-time runs kept every frame until the end: 395 MB
//! after 10 s of `illume demo`).
//!
//! The frame loop hands each frame over through a queue bounded in bytes
//! ([`QUEUE_BYTES`]); the writer runs at the lowest OS priority so that it takes the CPU
//! the renderer leaves (in real time below every normal thread: [`WriterPriority`]), and
//! the loop waits only when the queue is full (a disk slower than the renderer for a long
//! stretch).

use anyhow::{Context, Result};
use illume_core::image::RgbImage;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

pub use illume_core::outputs::{Entry, OutputDir, temporary_target};

/// The per-frame CSV of `animate --shard K/N`: `frames_K_of_N.csv`.
pub fn shard_csv_name(shard: illume_core::Shard) -> String {
    format!("frames_{}_of_{}.csv", shard.index, shard.count)
}

/// The frame number of a `frame_NNNNN.png` / `.exr` name.
pub fn frame_number(name: &str) -> Option<u64> {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".png").or_else(|| r.strip_suffix(".exr")))
        .filter(|n| n.len() >= 5 && n.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|n| n.parse().ok())
}

/// Makes `dir` ready for one shard's frames (`animate --shard K/N`), which other shards
/// may be writing into at the same time: created if missing; refused, touching nothing,
/// when it holds anything illume cannot prove it wrote ([`OutputDir`]'s manifest) —
/// except files another shard is writing now; of illume's files, only this shard's
/// earlier frames and CSV are removed.
pub fn prepare_shard_output(dir: &Path, shard: illume_core::Shard) -> Result<OutputDir> {
    let out = OutputDir::create(dir)?;
    let owned = |name: &str| {
        let name = temporary_target(name).unwrap_or(name);
        frame_number(name).is_some_and(|i| shard.owns(i as usize)) || name == shard_csv_name(shard)
    };
    let mut foreign = Vec::new();
    let mut mine = Vec::new();
    for entry in out.survey()? {
        match entry {
            Entry::Foreign(n) => foreign.push(n),
            // Being written by another shard: theirs to finish. Ours: changed since.
            Entry::Pending(n) if owned(&n) => foreign.push(n),
            Entry::Pending(_) => {}
            Entry::Proven(n) if owned(&n) => mine.push(n),
            Entry::Proven(_) => {}
        }
    }
    out.refuse_foreign(foreign)?;
    for name in mine {
        out.remove(&name)?;
    }
    Ok(out)
}

/// Makes `dir` ready for a sequence: created if missing; what an earlier run wrote (and
/// nobody changed since, [`OutputDir`]) is removed, so no stale frame of a longer
/// earlier run survives; a folder holding anything else is refused, naming it, and
/// nothing in it is touched.
pub fn prepare_output(dir: &Path) -> Result<OutputDir> {
    Ok(OutputDir::clear(dir)?)
}

/// Frames waiting to be written may hold at most this many bytes (sRGB and HDR copies);
/// beyond it the frame loop waits for the writer.
pub const QUEUE_BYTES: usize = 256 << 20;

/// One rendered frame: its 8-bit sRGB pixels and, with `--exr`, the linear image.
pub struct Frame {
    /// Frame number (file name `frame_NNNNN`).
    pub index: u64,
    /// Seconds of the sequence at which it was shown: the preview's timing.
    pub shown_s: f64,
    /// Tone-mapped 8-bit RGB, row-major.
    pub srgb8: Vec<u8>,
    /// The linear frame, when EXR frames are asked for.
    pub hdr: Option<RgbImage>,
}

impl Frame {
    fn bytes(&self) -> usize {
        self.srgb8.len() + self.hdr.as_ref().map_or(0, |h| h.pixels().len() * 12)
    }
}

/// How the preview is made once all frames are on disk.
pub enum Preview {
    /// ffmpeg is on PATH: an MP4 from the PNG frames at the end.
    Mp4,
    /// No ffmpeg: an animated GIF at half size, encoded as frames arrive.
    Gif,
}

/// Bytes queued, and a condition the loop waits on when over [`QUEUE_BYTES`].
#[derive(Default)]
struct Budget {
    queued: Mutex<usize>,
    freed: Condvar,
}

/// How far below the frame loop the writer thread runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriterPriority {
    /// The lowest nice value (19): a small fair share of a busy core, so that an offline
    /// sequence on a node that other jobs fill still drains its queue.
    Low,
    /// Real time (`--realtime`, `demo`): on Linux `SCHED_IDLE`, which any normal thread
    /// preempts at once, so the writer only runs on a core that the renderer, the
    /// photon stream and the frame loop leave idle. At nice 19 the writer, which encodes
    /// a PNG and a GIF frame per frame, took 17 % of both cores during `illume demo`,
    /// whose median frame was 36.3 ms against 32.3 ms (docs/benchmarks/viewer.md, "The
    /// frame writer below every thread"). Elsewhere, or where refused: as
    /// [`WriterPriority::Low`].
    Idle,
}

impl WriterPriority {
    /// Applies this priority to the calling thread. Lowering one's own priority needs no
    /// privilege on Linux; where it is refused the writer simply competes at normal
    /// priority.
    fn apply(self) {
        #[cfg(target_os = "linux")]
        if self == Self::Idle {
            use thread_priority::{
                NormalThreadSchedulePolicy, ThreadPriority, ThreadSchedulePolicy,
                set_thread_priority_and_policy, thread_native_id,
            };
            let idle = ThreadSchedulePolicy::Normal(NormalThreadSchedulePolicy::Idle);
            if set_thread_priority_and_policy(thread_native_id(), ThreadPriority::Min, idle).is_ok()
            {
                return;
            }
        }
        let _ = thread_priority::set_current_thread_priority(thread_priority::ThreadPriority::Min);
    }
}

/// The background writer.
pub struct FrameWriter {
    out: OutputDir,
    dir: PathBuf,
    size: (u32, u32),
    frames: u64,
    tx: Option<SyncSender<Frame>>,
    budget: Arc<Budget>,
    thread: Option<JoinHandle<Result<Option<PathBuf>>>>,
    preview: Preview,
}

impl FrameWriter {
    /// Starts a writer of `w × h` frames into `out` (each file recorded in its
    /// manifest), its thread at `priority`.
    pub fn start(out: &OutputDir, w: u32, h: u32, priority: WriterPriority) -> Result<Self> {
        let dir = out.dir();
        let preview = if ffmpeg_available() {
            Preview::Mp4
        } else {
            Preview::Gif
        };
        // The byte budget bounds the queue; the channel's own bound only has to be large.
        let (tx, rx) = sync_channel::<Frame>(1 << 16);
        let budget = Arc::new(Budget::default());
        let gif = matches!(preview, Preview::Gif);
        let thread = {
            let out = out.clone();
            let budget = Arc::clone(&budget);
            std::thread::Builder::new()
                .name("frame writer".into())
                .spawn(move || {
                    priority.apply();
                    write_all(&out, w, h, gif, rx, &budget)
                })
                .context("cannot start the frame writer thread")?
        };
        Ok(Self {
            out: out.clone(),
            dir: dir.to_owned(),
            size: (w, h),
            frames: 0,
            tx: Some(tx),
            budget,
            thread: Some(thread),
            preview,
        })
    }

    /// Queues `frame`, waiting while the queue holds more than [`QUEUE_BYTES`]. An error
    /// the writer met (a full disk, say) is returned here as soon as it is known.
    pub fn push(&mut self, frame: Frame) -> Result<()> {
        let bytes = frame.bytes();
        {
            let mut queued = self.budget.queued.lock().unwrap_or_else(|e| e.into_inner());
            while *queued > 0 && *queued + bytes > QUEUE_BYTES {
                if self.thread.as_ref().is_none_or(|t| t.is_finished()) {
                    break;
                }
                queued = self
                    .budget
                    .freed
                    .wait_timeout(queued, std::time::Duration::from_millis(50))
                    .unwrap_or_else(|e| e.into_inner())
                    .0;
            }
            *queued += bytes;
        }
        self.frames += 1;
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(frame).is_ok());
        if !sent {
            // The writer stopped: its error says why.
            self.finish_thread()?;
            anyhow::bail!("the frame writer stopped early");
        }
        Ok(())
    }

    fn finish_thread(&mut self) -> Result<Option<PathBuf>> {
        self.tx = None;
        match self.thread.take() {
            Some(t) => t
                .join()
                .map_err(|_| anyhow::anyhow!("the frame writer thread panicked"))?,
            None => Ok(None),
        }
    }

    /// Waits for every frame to be written and makes the preview (`preview.mp4` through
    /// ffmpeg at `fps`, else the GIF encoded along the way; when ffmpeg fails, a GIF read
    /// back from the PNG frames). Returns its path.
    pub fn finish(mut self, fps: f64) -> Result<PathBuf> {
        let partial = self.finish_thread()?;
        let out = self.dir.join("preview.gif");
        if let (Preview::Gif, Some(partial)) = (&self.preview, partial) {
            std::fs::rename(&partial, &out)
                .with_context(|| format!("{}: cannot write", out.display()))?;
            self.out.written("preview.gif")?;
            return Ok(out);
        }
        match mp4(&self.out, fps) {
            Ok(path) => Ok(path),
            Err(e) => {
                eprintln!("warning: {e:#}; writing a GIF instead");
                let gif = gif_from_disk(&self.dir, self.frames, self.size, fps)?;
                self.out.write_file("preview.gif", gif)?;
                Ok(out)
            }
        }
    }
}

/// The half-size GIF of `frames` PNG frames already on disk, at `fps`.
fn gif_from_disk(dir: &Path, frames: u64, (w, h): (u32, u32), fps: f64) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let mut enc = image::codecs::gif::GifEncoder::new_with_speed(&mut bytes, 30);
    enc.set_repeat(image::codecs::gif::Repeat::Infinite)?;
    for index in 0..frames {
        let path = dir.join(format!("frame_{index:05}.png"));
        let rgb = image::open(&path)
            .with_context(|| format!("{}: cannot read back", path.display()))?
            .to_rgb8();
        encode_gif_frame(&mut enc, half_size(&rgb, w, h), 1.0 / fps.max(1.0))?;
    }
    drop(enc);
    Ok(bytes)
}

/// The preview's half-size RGBA copy of a `w × h` frame.
fn half_size(rgb: &image::RgbImage, w: u32, h: u32) -> image::RgbaImage {
    let small = image::imageops::resize(
        rgb,
        (w / 2).max(1),
        (h / 2).max(1),
        image::imageops::FilterType::Triangle,
    );
    image::DynamicImage::ImageRgb8(small).to_rgba8()
}

impl Drop for FrameWriter {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn ffmpeg_available() -> bool {
    std::process::Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The writer thread: PNG (+ EXR) per frame; with `gif`, each frame's half-size copy is
/// encoded when the next one arrives (its delay is the time until the next frame was
/// shown, so the preview plays at the speed the sequence was rendered).
fn write_all(
    out_dir: &OutputDir,
    w: u32,
    h: u32,
    gif: bool,
    rx: Receiver<Frame>,
    budget: &Budget,
) -> Result<Option<PathBuf>> {
    // The GIF grows in a temporary file beside the frames, renamed into place at the end.
    let dir = out_dir.dir();
    let partial = dir.join(".preview.gif.partial");
    let mut out = if gif {
        out_dir.intend("preview.gif")?;
        let file = std::fs::File::create(&partial)
            .with_context(|| format!("{}: cannot create", partial.display()))?;
        Some(std::io::BufWriter::new(file))
    } else {
        None
    };
    let mut encoder = out
        .as_mut()
        .map(|w| image::codecs::gif::GifEncoder::new_with_speed(w, 30));
    if let Some(enc) = encoder.as_mut() {
        enc.set_repeat(image::codecs::gif::Repeat::Infinite)?;
    }
    let mut pending: Option<(image::RgbaImage, f64)> = None;
    let mut last_delay_s = 1.0 / 15.0;
    for frame in rx {
        let size = frame.bytes();
        let written = write_frame(out_dir, &frame, w, h);
        let small = encoder.as_ref().map(|_| {
            image::RgbImage::from_raw(w, h, frame.srgb8.clone()).map(|rgb| half_size(&rgb, w, h))
        });
        let shown_s = frame.shown_s;
        drop(frame);
        {
            let mut queued = budget.queued.lock().unwrap_or_else(|e| e.into_inner());
            *queued = queued.saturating_sub(size);
            budget.freed.notify_all();
        }
        written?;
        if let (Some(enc), Some(Some(small))) = (encoder.as_mut(), small) {
            if let Some((prev, prev_s)) = pending.take() {
                last_delay_s = (shown_s - prev_s).max(0.01);
                encode_gif_frame(enc, prev, last_delay_s)?;
            }
            pending = Some((small, shown_s));
        }
    }
    if let (Some(enc), Some((prev, _))) = (encoder.as_mut(), pending.take()) {
        encode_gif_frame(enc, prev, last_delay_s)?;
    }
    // Dropping the encoder writes the GIF trailer.
    drop(encoder);
    if let Some(mut out) = out {
        use std::io::Write as _;
        out.flush()
            .map_err(anyhow::Error::from)
            .and_then(|()| Ok(out.get_ref().sync_all()?))
            .with_context(|| format!("{}: cannot write", partial.display()))?;
        return Ok(Some(partial));
    }
    Ok(None)
}

fn encode_gif_frame<W: std::io::Write>(
    enc: &mut image::codecs::gif::GifEncoder<W>,
    rgba: image::RgbaImage,
    delay_s: f64,
) -> Result<()> {
    let delay = image::Delay::from_numer_denom_ms((delay_s * 1000.0).round() as u32, 1);
    enc.encode_frame(image::Frame::from_parts(rgba, 0, 0, delay))?;
    Ok(())
}

/// Writes `frame_NNNNN.png` (and `.exr`), each through a temporary file renamed into
/// place.
fn write_frame(out: &OutputDir, f: &Frame, w: u32, h: u32) -> Result<()> {
    let name = format!("frame_{:05}.png", f.index);
    let path = out.dir().join(&name);
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut png,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(&f.srgb8, w, h, image::ExtendedColorType::Rgb8)
    .with_context(|| format!("{}: cannot encode", path.display()))?;
    out.write_file(&name, png)?;
    if let Some(hdr) = &f.hdr {
        write_exr_recorded(out, &format!("frame_{:05}.exr", f.index), hdr)?;
    }
    Ok(())
}

/// Writes linear `name` into `out` (temporary file, rename), recorded in its manifest.
pub fn write_exr_recorded(out: &OutputDir, name: &str, image: &RgbImage) -> Result<()> {
    out.intend(name)?;
    illume_core::image::write_exr(image, &out.dir().join(name))?;
    out.written(name)?;
    Ok(())
}

/// `preview.mp4` from the PNG frames at `fps` through ffmpeg, written to a temporary
/// sibling and renamed into place (a failed encode keeps an earlier preview whole).
fn mp4(out_dir: &OutputDir, fps: f64) -> Result<PathBuf> {
    let dir = out_dir.dir();
    let out = dir.join("preview.mp4");
    out_dir.intend("preview.mp4")?;
    let tmp = dir.join(format!(".preview.mp4.{}.tmp", std::process::id()));
    let status = std::process::Command::new("ffmpeg")
        .args([
            "-y",
            "-loglevel",
            "error",
            "-framerate",
            &format!("{fps:.3}"),
            "-i",
        ])
        .arg(dir.join("frame_%05d.png"))
        .args([
            "-pix_fmt",
            "yuv420p",
            "-vf",
            "scale=trunc(iw/2)*2:trunc(ih/2)*2",
            "-f",
            "mp4",
        ])
        .arg(&tmp)
        .status()
        .context("running ffmpeg")?;
    if !status.success() {
        let _ = std::fs::remove_file(&tmp);
        anyhow::bail!("ffmpeg failed ({status})");
    }
    std::fs::rename(&tmp, &out).with_context(|| format!("{}: cannot write", out.display()))?;
    out_dir.written("preview.mp4")?;
    Ok(out)
}

use image::ImageEncoder as _;
