//! What the window writes: screenshots (P) and clips (K).

use super::App;
use crate::ViewError;
use crate::renderer::Shown;
use illume_core::image::ToneMap;
use illume_engine::{FramesCsv, StepRecord};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, channel};

/// A clip frame for the writer thread: index, sRGB bytes, width, height.
type ClipFrame = (u64, Vec<u8>, u32, u32);

/// A clip being recorded: PNG frames and the CSV of `animate`, written on a thread.
pub(super) struct Recorder {
    dir: PathBuf,
    frames: Sender<ClipFrame>,
    csv: FramesCsv,
    index: u64,
    writer: Option<std::thread::JoinHandle<()>>,
}

impl Recorder {
    pub(super) fn start(dir: PathBuf) -> Result<Self, String> {
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let (tx, rx): (Sender<ClipFrame>, Receiver<ClipFrame>) = channel();
        let d = dir.clone();
        let writer = std::thread::spawn(move || {
            for (i, bytes, w, h) in rx {
                let path = d.join(format!("frame_{i:05}.png"));
                if let Err(e) = image::save_buffer_with_format(
                    &path,
                    &bytes,
                    w,
                    h,
                    image::ColorType::Rgb8,
                    image::ImageFormat::Png,
                ) {
                    log::warn!("illume view: {}: {e}", path.display());
                }
            }
        });
        Ok(Self {
            dir,
            frames: tx,
            csv: FramesCsv::default(),
            index: 0,
            writer: Some(writer),
        })
    }

    pub(super) fn push(&mut self, shown: &Shown, tone: &ToneMap, wall_s: f64) {
        // Reference mode: no technique frame; the update and the whole frame's times
        // and no counters.
        let record = shown.record.clone().unwrap_or_else(|| StepRecord {
            time_s: shown.time_s,
            update_ms: shown.times.update_ms,
            render_ms: shown.times.total_ms,
            ..Default::default()
        });
        self.csv.push(&StepRecord {
            frame: self.index,
            wall_s,
            ..record
        });
        let bytes = illume_core::image::to_srgb8(&shown.image, tone);
        let _ = self
            .frames
            .send((self.index, bytes, shown.image.width(), shown.image.height()));
        self.index += 1;
    }

    pub(super) fn finish(mut self) -> Result<PathBuf, String> {
        drop(std::mem::replace(&mut self.frames, channel().0));
        if let Some(w) = self.writer.take() {
            let _ = w.join();
        }
        let path = self.dir.join("frames.csv");
        std::fs::write(&path, self.csv.text()).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(self.dir)
    }
}

impl App {
    /// Writes the shown frame as `render` would: PNG tone-mapped and EXR linear.
    pub(super) fn screenshot(&self, png: &Path) -> Result<(), ViewError> {
        let Some(shown) = &self.shown else {
            return Err(ViewError::Output {
                path: png.to_owned(),
                message: "no frame yet".into(),
            });
        };
        let tone = self.tone(shown);
        let out = |path: &Path| {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                let _ = std::fs::create_dir_all(dir);
            }
            shown
                .image
                .write(path, &tone)
                .map_err(|e| ViewError::Output {
                    path: path.to_owned(),
                    message: e.to_string(),
                })
        };
        out(png)?;
        out(&png.with_extension("exr"))?;
        eprintln!(
            "illume view: wrote {} (+ .exr), {}×{}, exposure {:+.2} EV{}",
            png.display(),
            shown.image.width(),
            shown.image.height(),
            tone.exposure_ev,
            shown
                .reference_spp
                .map(|s| format!(", reference {s} spp"))
                .unwrap_or_default()
        );
        Ok(())
    }
}
