//! `illume view`: an interactive window on the engine — the same renderer and
//! techniques as `illume render` and `illume animate`, shown as frames finish.
//!
//! * winit owns the window and input; wgpu presents the HDR frame through a tone-map
//!   shader with the curve of PNG output (`tonemap.wgsl`); egui draws the panels.
//! * The engine runs on its own thread ([`renderer`]); the window shows the newest
//!   finished frame and never waits for the renderer.
//! * Edits (camera, objects, lights, materials; keys or the [`gizmo`]) go to the render
//!   thread as commands and through [`illume_engine::Engine::apply_edit`], the
//!   scene-change path of animations.
//! * Files dropped on the window open through [`dropped::open_dropped`].
//!
//! Controls are listed in `docs/viewer.md`.

mod app;
pub mod camera;
pub mod dropped;
pub mod gizmo;
mod present;
pub mod renderer;

use illume_engine::Config;
use illume_scene::Scene;
use std::path::PathBuf;

/// Why the viewer could not run.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// No display, or the window could not be created.
    #[error("window: {0}")]
    Window(String),
    /// No adapter could present to the window, or the device failed.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A screenshot or clip could not be written.
    #[error("{path}: {message}")]
    Output {
        /// The file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}

/// What `illume view` was asked for.
pub struct ViewOptions {
    /// The scene (camera already placed).
    pub scene: Scene,
    /// Technique, its settings, render size (the window's image size).
    pub config: Config,
    /// Reference samples per pixel before the reference stops (and before the test
    /// screenshot).
    pub reference_spp: Option<u32>,
    /// Start in reference mode.
    pub reference: bool,
    /// Start with the animation playing.
    pub play: bool,
    /// Exposure added to the automatic one \[stops\].
    pub exposure_ev: f32,
    /// Start with the stats overlay on the image shown (O toggles it).
    pub stats: bool,
    /// Test mode: write this screenshot (PNG, tone-mapped as `render` writes it; an EXR
    /// beside it) once [`ViewOptions::exit_after_frames`] frames were displayed and the
    /// reference has its samples, then exit.
    pub screenshot: Option<PathBuf>,
    /// Test mode: frames to display before the screenshot and exit.
    pub exit_after_frames: Option<u64>,
    /// Test mode: keep the window open this long after the screenshot \[ms\].
    pub linger_ms: u64,
    /// Print a line with a timestamp for every input event handled (tests measure
    /// latency with it) and for every new frame shown.
    pub log_input: bool,
    /// Close the window after this many seconds (benchmarks; unlike the test mode it
    /// redraws only for new frames and input, as an interactive session does).
    pub duration_s: Option<f64>,
    /// Folder that screenshots (P) and clips (K) go to.
    pub output_dir: PathBuf,
    /// Most technique frames a second (0: no limit). The window shows at most one frame
    /// per refresh (≈ 60 a second), so faster frames are never seen; the time they would
    /// take goes to the technique's own threads, and the cores idle otherwise. A command
    /// (input) starts a frame at once. The reference and the split view are not paced.
    pub max_fps: f64,
    /// Still refinement: once the view rests (no command, no animation playing, the
    /// technique [settled](illume_transport::Technique::settled)), this many frames are
    /// averaged into the image shown — the one at pixel centres and the others at jittered
    /// offsets in each pixel — which then converges to the box filter of a supersampled
    /// image (anti-aliased edges, minified textures averaged); 0 or 1: off. Any command
    /// starts over. Each such frame costs about a moving-camera frame (the G-buffer
    /// rasterized at the offset); nothing is spent while anything moves.
    pub refine_frames: u32,
}

/// Opens the window and runs until it is closed (or the test mode exits).
pub fn run(options: ViewOptions) -> Result<(), ViewError> {
    app::run(options)
}

/// Milliseconds since the Unix epoch (the timestamps of `--log-input` lines).
pub fn unix_ms() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64() * 1e3)
}
