//! The window: winit's event loop ([`events`]) drives egui's side panel ([`panel`],
//! [`settings`]), the frame's area ([`viewport`]), the keys ([`keys`]) and what the
//! window writes ([`recorder`]). [`App`] holds the window's state; each redraw collects
//! what the UI asked for into [`Actions`] and [`App::apply`]s it.

mod events;
mod keys;
mod panel;
mod recorder;
mod settings;
mod viewport;

use crate::camera::OrbitCamera;
use crate::dropped::{Messages, open_dropped};
use crate::gizmo::Handle;
use crate::present::Gpu;
use crate::renderer::{Command, RenderThread, Shown};
use crate::{ViewError, ViewOptions, unix_ms};
use glam::Vec3;
use illume_core::image::{ToneCurve, ToneMap};
use illume_engine::settings_doc::Applies;
use recorder::Recorder;
use settings::SettingRow;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::event_loop::{ActiveEventLoop, EventLoop, EventLoopProxy};
use winit::window::Window;

/// winit's OS errors read "os error at /…/winit-0.30/src/…/mod.rs:765: MESSAGE": the
/// user gets MESSAGE, not a path into cargo's registry.
fn without_source_location(e: &str) -> &str {
    match e.find(".rs:") {
        Some(i) => e[i..].split_once(": ").map_or(e, |(_, m)| m),
        None => e,
    }
}

/// Width of the side panel \[points\].
const PANEL_WIDTH: f32 = 260.0;
/// The window redraws at least this often (input is handled at every redraw).
const REFRESH: Duration = Duration::from_millis(16);

pub fn run(options: ViewOptions) -> Result<(), ViewError> {
    let event_loop = EventLoop::<()>::with_user_event().build().map_err(|e| {
        ViewError::Window(format!(
            "{} (is DISPLAY set and an X or Wayland server running?)",
            without_source_location(&e.to_string())
        ))
    })?;
    let proxy = event_loop.create_proxy();
    let mut app = App::new(options, proxy);
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewError::Window(e.to_string()))?;
    match app.fatal.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The window's state: the render thread, the frame shown, the display's and the
/// panels' state, and the measurements printed at exit.
struct App {
    options: ViewOptions,
    proxy: EventLoopProxy<()>,
    window: Option<Arc<Window>>,
    gpu: Option<Gpu>,
    egui_state: Option<egui_winit::State>,
    ctx: egui::Context,
    render: Option<RenderThread>,
    shown: Option<Arc<Shown>>,
    /// The frame and tone whose display bytes the GPU has.
    uploaded: Option<(u64, ToneMap)>,
    /// The display bytes (8-bit RGBA) of the shown frame.
    display: Vec<u8>,
    /// Display conversions and uploads so far (a new frame or a tone change each).
    uploads: u64,
    /// Frames presented so far.
    displayed: u64,
    orbit: Option<OrbitCamera>,
    fly: bool,
    next_pick: u64,
    focus_pick: Option<u64>,
    exposure_ev: f32,
    auto_exposure: bool,
    curve: ToneCurve,
    /// Messages shown in the window (errors never crash it).
    messages: Messages,
    recorder: Option<Recorder>,
    record_start: Instant,
    screenshots: u32,
    /// Test mode: when to exit.
    exit_at: Option<Instant>,
    fatal: Option<ViewError>,
    /// Times of recent new frames, for fps.
    new_frames: Vec<Instant>,
    present_ms: f64,
    title_at: Instant,
    last_redraw: Instant,
    split_drag: bool,
    selected_material: usize,
    /// The settings panel's rows and the text being edited in each.
    settings_rows: Vec<(SettingRow, String)>,
    settings_for: String,
    /// A setting sent that rebuilds the technique: the commands sent with it, and the
    /// notice shown until a frame after it arrives.
    rebuilding: Option<(u64, String)>,
    /// The stats overlay on the image is shown (O).
    overlay: bool,
    /// The gizmo handle being dragged.
    gizmo_drag: Option<Handle>,
    /// The gizmo last printed by `--log-input` (centre and X handle's end).
    gizmo_logged: Option<[f32; 4]>,
    commands_sent: u64,
    /// A new frame waits for the next refresh.
    frame_pending: bool,
    /// egui asked to be redrawn at this time.
    egui_repaint_at: Option<Instant>,
    /// The last event egui wanted a repaint for.
    last_input: Instant,
    input_log: Vec<String>,
    /// For the summary at exit: redraws, their total time and the upload's \[ms\].
    redraws: u64,
    redraw_ms_total: f64,
    upload_ms_total: f64,
    /// Of which converting frames to display bytes (`present::display_bytes`).
    tonemap_ms_total: f64,
    gpu_ms_total: f64,
    acquire_ms_total: f64,
    render_ms_total: f64,
    present_call_ms_total: f64,
    started: Instant,
    frames_received: u64,
}

impl App {
    fn new(options: ViewOptions, proxy: EventLoopProxy<()>) -> Self {
        let exposure_ev = options.exposure_ev;
        let overlay = options.stats;
        Self {
            options,
            proxy,
            window: None,
            gpu: None,
            egui_state: None,
            ctx: egui::Context::default(),
            render: None,
            shown: None,
            uploaded: None,
            display: Vec::new(),
            uploads: 0,
            displayed: 0,
            orbit: None,
            fly: false,
            next_pick: 1,
            focus_pick: None,
            exposure_ev,
            auto_exposure: true,
            curve: ToneCurve::Aces,
            messages: Messages::default(),
            recorder: None,
            record_start: Instant::now(),
            screenshots: 0,
            exit_at: None,
            fatal: None,
            new_frames: Vec::new(),
            present_ms: 0.0,
            title_at: Instant::now(),
            last_redraw: Instant::now(),
            split_drag: false,
            selected_material: 0,
            settings_rows: Vec::new(),
            settings_for: String::new(),
            rebuilding: None,
            overlay,
            gizmo_drag: None,
            gizmo_logged: None,
            commands_sent: 0,
            frame_pending: false,
            egui_repaint_at: None,
            last_input: Instant::now(),
            input_log: Vec::new(),
            redraws: 0,
            redraw_ms_total: 0.0,
            upload_ms_total: 0.0,
            tonemap_ms_total: 0.0,
            gpu_ms_total: 0.0,
            acquire_ms_total: 0.0,
            render_ms_total: 0.0,
            present_call_ms_total: 0.0,
            started: Instant::now(),
            frames_received: 0,
        }
    }

    fn send(&mut self, c: Command) {
        if let Some(r) = &self.render {
            r.send(c);
            self.commands_sent += 1;
        }
    }

    fn message(&self, m: String) {
        self.messages.push(m);
    }

    /// Notes an input event for `--log-input`; printed once its commands are sent.
    fn log(&mut self, what: &str) {
        if self.options.log_input {
            self.input_log.push(what.to_owned());
        }
    }

    fn flush_log(&mut self) {
        for what in std::mem::take(&mut self.input_log) {
            eprintln!(
                "illume view: input {what} handled_unix_ms={:.1} sent={}",
                unix_ms(),
                self.commands_sent
            );
        }
    }

    fn tone(&self, shown: &Shown) -> ToneMap {
        ToneMap {
            exposure_ev: if self.auto_exposure {
                shown.auto_exposure_ev + self.exposure_ev
            } else {
                self.exposure_ev
            },
            curve: self.curve,
        }
    }

    fn set_camera(&mut self, orbit: OrbitCamera) {
        self.orbit = Some(orbit);
        self.send(Command::Camera(orbit.world_from_camera()));
    }

    /// "27.3 fps", "refining 5/64" while still refinement adds frames, or "idle
    /// (settled)" once the renderer waits with nothing to add.
    fn rate_text(&self) -> String {
        match &self.shown {
            Some(s) if s.settled && s.refined_frames > 1 => {
                format!("idle (settled, {} frames averaged)", s.refined_frames)
            }
            Some(s) if s.settled => "idle (settled)".to_owned(),
            Some(s) if s.refined_frames > 1 && self.options.refine_frames > 0 => format!(
                "refining {}/{}",
                s.refined_frames, self.options.refine_frames
            ),
            _ => format!("{:.1} fps", self.fps()),
        }
    }

    fn fps(&self) -> f64 {
        let n = self.new_frames.len();
        if n < 2 {
            return 0.0;
        }
        let span = (self.new_frames[n - 1] - self.new_frames[0]).as_secs_f64();
        if span > 0.0 {
            (n - 1) as f64 / span
        } else {
            0.0
        }
    }

    fn build_ui(&mut self, ui: &mut egui::Ui, actions: &mut Actions) {
        let ctx = ui.ctx().clone();
        egui::Panel::right("panel")
            .exact_size(PANEL_WIDTH)
            .resizable(false)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui, actions));
            });
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| self.viewport(ui, actions));
        if !ctx.egui_wants_keyboard_input() {
            self.keys(&ctx, actions);
        }
    }

    fn apply(&mut self, actions: Actions, event_loop: &ActiveEventLoop) {
        for c in actions.commands {
            let rebuild = match (&c, &self.shown) {
                (Command::Set(kv), Some(shown))
                    if crate::renderer::setting_applies(shown.technique, kv)
                        == Applies::Rebuild =>
                {
                    Some(format!("⟳ rebuilding {} for {kv}…", shown.technique))
                }
                _ => None,
            };
            self.send(c);
            if let Some(notice) = rebuild {
                self.rebuilding = Some((self.commands_sent, notice));
            }
        }
        if let (Some((i, rgb)), Some(render)) = (actions.material, &self.render)
            && let Some(shown) = &self.shown
            && i < shown.materials.len()
        {
            render.send(Command::SetBaseColor {
                material: i as u32,
                base_color: rgb,
            });
        }
        if actions.reset_camera
            && let Some(shown) = &self.shown
        {
            let cam = shown.scene_camera;
            let d = self.orbit.map_or(1.0, |o| o.distance);
            self.send(Command::Camera(cam));
            self.orbit = Some(OrbitCamera::from_transform(cam, d));
            self.focus_pick = None;
            self.log("reset-camera");
        }
        if actions.screenshot {
            self.screenshots += 1;
            let path = self
                .options
                .output_dir
                .join(format!("screenshot_{:03}.png", self.screenshots));
            if let Err(e) = self.screenshot(&path) {
                self.message(e.to_string());
            }
        }
        if actions.record {
            match self.recorder.take() {
                Some(r) => match r.finish() {
                    Ok(dir) => self.message(format!("clip written to {}", dir.display())),
                    Err(e) => self.message(e),
                },
                None => {
                    let dir = self.options.output_dir.join(format!(
                        "clip_{}",
                        std::time::SystemTime::now()
                            .duration_since(std::time::UNIX_EPOCH)
                            .map_or(0, |d| d.as_secs())
                    ));
                    match Recorder::start(dir) {
                        Ok(r) => {
                            self.record_start = Instant::now();
                            self.recorder = Some(r);
                        }
                        Err(e) => self.message(e),
                    }
                }
            }
        }
        let _ = event_loop;
    }

    fn open_dropped(&self, path: PathBuf) {
        let Some(render) = &self.render else { return };
        open_dropped(path, render.commands.clone(), self.messages.clone());
    }
}

/// What the UI asked for during one redraw.
#[derive(Default)]
struct Actions {
    commands: Vec<Command>,
    image_rect_px: [f32; 4],
    screenshot: bool,
    record: bool,
    reset_camera: bool,
    material: Option<(usize, Vec3)>,
}

#[cfg(test)]
mod tests {
    /// The no-display error names the cause, not winit's source file (issue 38).
    #[test]
    fn os_errors_lose_their_source_location() {
        let e = "os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set.";
        assert_eq!(
            super::without_source_location(e),
            "neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set."
        );
        assert_eq!(super::without_source_location("plain"), "plain");
    }
}
