//! The window: winit's event loop, input, egui's panels, screenshots and clips.

use crate::camera::OrbitCamera;
use crate::dropped::{Messages, open_dropped};
use crate::gizmo::{Gizmo, Handle, View};
use crate::present::{Gpu, Viewport, display_bytes};
use crate::renderer::{AnimationCommand, Command, RenderSetup, RenderThread, Selection, Shown};
use crate::{ViewError, ViewOptions, unix_ms};
use egui::{Key, Sense};
use glam::{Quat, Vec2, Vec3};
use illume_core::image::{ToneCurve, ToneMap};
use illume_engine::TechniqueKind;
use illume_engine::settings_doc::Applies;
use illume_scene::{Edit, LightKind};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

/// Width of the side panel \[points\].
const PANEL_WIDTH: f32 = 260.0;
/// The window redraws at least this often (input is handled at every redraw).
const REFRESH: Duration = Duration::from_millis(16);

pub fn run(options: ViewOptions) -> Result<(), ViewError> {
    let event_loop = EventLoop::<()>::with_user_event().build().map_err(|e| {
        ViewError::Window(format!(
            "{e} (is DISPLAY set and an X or Wayland server running?)"
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

/// A clip frame for the writer thread: index, sRGB bytes, width, height.
type ClipFrame = (u64, Vec<u8>, u32, u32);

/// A clip being recorded: PNG frames and the CSV of `animate`, written on a thread.
struct Recorder {
    dir: PathBuf,
    frames: Sender<ClipFrame>,
    csv: String,
    index: u64,
    writer: Option<std::thread::JoinHandle<()>>,
}

impl Recorder {
    fn start(dir: PathBuf) -> Result<Self, String> {
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
                    eprintln!("illume view: {}: {e}", path.display());
                }
            }
        });
        Ok(Self {
            dir,
            frames: tx,
            csv: String::new(),
            index: 0,
            writer: Some(writer),
        })
    }

    fn push(&mut self, shown: &Shown, tone: &ToneMap, wall_s: f64) {
        if self.csv.is_empty() {
            self.csv = format!(
                "frame,time_s,wall_s,precompute_ms,update_ms,advance_ms,gbuffer_ms,direct_ms,indirect_ms,render_ms{}\n",
                shown
                    .stats
                    .iter()
                    .map(|(n, _)| format!(",{n}"))
                    .collect::<String>()
            );
        }
        let row = if shown.csv_row.is_empty() {
            // Reference mode: no technique frame; times and no counters.
            format!(
                "{:.6},0,{:.3},0,0,0,0,{:.3}",
                shown.time_s, shown.times.update_ms, shown.times.total_ms
            )
        } else {
            shown.csv_row.clone()
        };
        // `animate`'s columns: frame,time_s,wall_s then the rest of the row.
        let (time, rest) = row.split_once(',').unwrap_or((&row, ""));
        self.csv += &format!("{},{time},{wall_s:.6},{rest}\n", self.index);
        let bytes = illume_core::image::to_srgb8(&shown.image, tone);
        let _ = self
            .frames
            .send((self.index, bytes, shown.image.width(), shown.image.height()));
        self.index += 1;
    }

    fn finish(mut self) -> Result<PathBuf, String> {
        drop(std::mem::replace(&mut self.frames, channel().0));
        if let Some(w) = self.writer.take() {
            let _ = w.join();
        }
        let path = self.dir.join("frames.csv");
        std::fs::write(&path, &self.csv).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(self.dir)
    }
}

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
        let overlay = !options.hide_stats;
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

    /// Writes the shown frame as `render` would: PNG tone-mapped and EXR linear.
    fn screenshot(&self, png: &Path) -> Result<(), ViewError> {
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

    fn set_camera(&mut self, orbit: OrbitCamera) {
        self.orbit = Some(orbit);
        self.send(Command::Camera(orbit.world_from_camera()));
    }

    /// "27.3 fps", or "idle (settled)" once the renderer waits with nothing to add.
    fn rate_text(&self) -> String {
        match &self.shown {
            Some(s) if s.settled => "idle (settled)".to_owned(),
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

    /// Takes the newest frame from the render thread.
    fn poll_frame(&mut self) {
        let Some(render) = &self.render else { return };
        let Some(latest) = render.slot.latest() else {
            return;
        };
        if self.shown.as_ref().is_some_and(|s| s.index == latest.index) {
            return;
        }
        let now = Instant::now();
        self.frames_received += 1;
        self.new_frames.push(now);
        self.new_frames
            .retain(|t| now.duration_since(*t) < Duration::from_secs(2));
        if self.options.log_input {
            eprintln!(
                "illume view: frame {} technique={} spp={} commands={} render_ms={:.1} pivot={} shown_unix_ms={:.1}",
                latest.index,
                latest.technique,
                latest.reference_spp.map_or("none".to_owned(), |s| format!(
                    "{s}/{}",
                    latest.reference_target
                )),
                latest.commands_applied,
                latest.times.total_ms,
                latest.selection_pivot.map_or("none".into(), |p| format!(
                    "{:.5},{:.5},{:.5}",
                    p.x, p.y, p.z
                )),
                unix_ms()
            );
        }
        // A new scene (dropped file): its camera starts a new orbit.
        if self
            .shown
            .as_ref()
            .is_some_and(|s| s.scene_camera != latest.scene_camera)
        {
            self.orbit = None;
            self.focus_pick = None;
        }
        // The first frame's camera starts the orbit: orbit the point at the centre.
        if self.orbit.is_none() && self.focus_pick.is_none() {
            self.focus_pick = Some(0);
            render.send(Command::Pick {
                uv: Vec2::splat(0.5),
                id: 0,
                select: false,
            });
        }
        if let (Some(id), Some(pick)) = (self.focus_pick, &latest.pick)
            && pick.id == id
        {
            self.focus_pick = None;
            let cam = latest.camera.0;
            let eye = Vec3::from(cam.translation);
            match (id, pick.position) {
                (0, p) => {
                    let d = p.map_or(1.0, |p| (p - eye).length());
                    self.orbit = Some(OrbitCamera::from_transform(cam, d));
                }
                (_, Some(p)) => {
                    let mut o = self.orbit.unwrap_or(OrbitCamera::from_transform(cam, 1.0));
                    o.focus(p);
                    self.set_camera(o);
                }
                (_, None) => {}
            }
        }
        if self
            .rebuilding
            .as_ref()
            .is_some_and(|(n, _)| latest.commands_applied >= *n)
        {
            self.rebuilding = None;
        }
        if let Some(rec) = &mut self.recorder {
            let tone = ToneMap {
                exposure_ev: if self.auto_exposure {
                    latest.auto_exposure_ev + self.exposure_ev
                } else {
                    self.exposure_ev
                },
                curve: self.curve,
            };
            rec.push(&latest, &tone, self.record_start.elapsed().as_secs_f64());
        }
        self.shown = Some(latest);
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        self.last_redraw = Instant::now();
        let redraw_start = self.last_redraw;
        self.poll_frame();
        let (Some(window), Some(state)) = (self.window.clone(), self.egui_state.as_mut()) else {
            return;
        };
        let input = state.take_egui_input(&window);
        let mut actions = Actions::default();
        let ctx = self.ctx.clone();
        let mut full = ctx.run_ui(input, |ui| self.build_ui(ui, &mut actions));
        if let Some(state) = self.egui_state.as_mut() {
            state.handle_platform_output(&window, full.platform_output);
        }
        let ppp = full.pixels_per_point;
        // Input is handled here, before drawing: its commands go to the render thread now.
        let image_rect_px = actions.image_rect_px;
        self.apply(actions, event_loop);
        self.flush_log();
        if let Some(delay) = full
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay)
            && delay < Duration::from_secs(3600)
        {
            let at = Instant::now() + delay;
            self.egui_repaint_at = Some(self.egui_repaint_at.map_or(at, |t| t.min(at)));
        }
        let paint = self.ctx.tessellate(full.shapes, ppp);
        let t0 = Instant::now();
        let tone = self.shown.as_ref().map(|s| (s.index, self.tone(s)));
        if let Some(gpu) = self.gpu.as_mut() {
            // A new frame or a new tone: PNG output's bytes, uploaded once.
            if let (Some(shown), Some((index, tone))) = (&self.shown, tone)
                && self.uploaded != Some((index, tone))
            {
                let tu = Instant::now();
                display_bytes(&shown.image, &tone, &mut self.display);
                self.tonemap_ms_total += tu.elapsed().as_secs_f64() * 1e3;
                gpu.upload(&self.display, shown.image.width(), shown.image.height());
                self.upload_ms_total += tu.elapsed().as_secs_f64() * 1e3;
                self.uploads += 1;
                self.uploaded = Some((index, tone));
            }
            let viewport = Viewport {
                rect: image_rect_px,
            };
            match gpu.draw(
                &viewport,
                &paint,
                &mut full.textures_delta,
                ppp,
                self.options.log_input,
            ) {
                Ok(t) => {
                    self.acquire_ms_total += t.acquire_ms;
                    self.render_ms_total += t.render_ms;
                    self.present_call_ms_total += t.present_ms;
                }
                Err(e) => self.message(e.to_string()),
            }
        }
        full.textures_delta.clear();
        let gpu_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.gpu_ms_total += gpu_ms;
        self.present_ms = 0.9 * self.present_ms + 0.1 * gpu_ms;
        if self.shown.is_some() {
            self.displayed += 1;
        }
        if self.title_at.elapsed() > Duration::from_millis(500) {
            self.title_at = Instant::now();
            if let Some(s) = &self.shown {
                window.set_title(&format!(
                    "illume view — {}{} — {}",
                    s.technique,
                    if s.reference_spp.is_some() && s.split.is_none() {
                        " (reference)"
                    } else {
                        ""
                    },
                    self.rate_text()
                ));
            }
        }
        self.redraws += 1;
        self.redraw_ms_total += redraw_start.elapsed().as_secs_f64() * 1e3;
        self.test_mode(event_loop);
    }

    /// Test mode: screenshot after N displayed frames (and the reference's samples).
    fn test_mode(&mut self, event_loop: &ActiveEventLoop) {
        if self.exit_at.is_some() {
            return;
        }
        let Some(n) = self.options.exit_after_frames else {
            return;
        };
        let Some(shown) = &self.shown else { return };
        let complete = shown
            .reference_spp
            .is_none_or(|s| s >= shown.reference_target);
        if self.displayed < n || !complete || self.uploaded.map(|u| u.0) != Some(shown.index) {
            return;
        }
        if let Some(path) = self.options.screenshot.clone()
            && let Err(e) = self.screenshot(&path)
        {
            self.fatal = Some(e);
            event_loop.exit();
            return;
        }
        self.exit_at = Some(Instant::now() + Duration::from_millis(self.options.linger_ms));
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

    fn panel(&mut self, ui: &mut egui::Ui, actions: &mut Actions) {
        let Some(shown) = self.shown.clone() else {
            ui.label("rendering the first frame…");
            return;
        };
        ui.heading("Technique");
        let mut kind = shown.technique;
        egui::ComboBox::from_id_salt("technique")
            .selected_text(kind.name())
            .show_ui(ui, |ui| {
                for &k in TechniqueKind::ALL {
                    ui.selectable_value(&mut kind, k, k.name());
                }
            })
            .response
            .on_hover_text("T / Shift+T: next / previous technique");
        if kind != shown.technique {
            actions.commands.push(Command::Technique(kind));
        }
        let mut reference = shown.reference_spp.is_some() && shown.split.is_none();
        if ui
            .checkbox(&mut reference, "Reference (R)")
            .on_hover_text("progressive path tracing while nothing moves; restarts on any change")
            .changed()
        {
            actions.commands.push(Command::Reference(reference));
        }
        let mut split = shown.split.is_some();
        if ui.checkbox(&mut split, "Split view (V)").changed() {
            actions.commands.push(Command::Split(split.then_some(0.5)));
        }
        if let Some(spp) = shown.reference_spp {
            ui.label(format!("reference: {spp} / {} spp", shown.reference_target));
        }
        if let Some((flip, spp)) = shown.flip {
            ui.label(format!(
                "FLIP technique vs reference: {flip:.4} (at {spp} spp)"
            ));
        }
        ui.horizontal(|ui| {
            ui.label("Resolution");
            for n in [1u32, 2, 4] {
                if ui
                    .selectable_label(shown.scale == n, format!("1/{n}"))
                    .clicked()
                {
                    actions.commands.push(Command::Scale(n));
                }
            }
        });
        ui.separator();
        ui.heading("Display");
        ui.add(egui::Slider::new(&mut self.exposure_ev, -10.0..=10.0).text("exposure EV"))
            .on_hover_text("stops added to the automatic exposure (render's rule); + / - keys");
        ui.checkbox(&mut self.auto_exposure, "automatic exposure");
        ui.checkbox(&mut self.overlay, "Stats on the image (O)")
            .on_hover_text("frame time by stage, the technique's counters, resolution scale");
        egui::ComboBox::from_id_salt("curve")
            .selected_text(format!("{:?}", self.curve))
            .show_ui(ui, |ui| {
                for c in [ToneCurve::Aces, ToneCurve::Reinhard, ToneCurve::Clamp] {
                    ui.selectable_value(&mut self.curve, c, format!("{c:?}"));
                }
            });
        ui.horizontal(|ui| {
            if ui.button("Screenshot (P)").clicked() {
                actions.screenshot = true;
            }
            let label = if self.recorder.is_some() {
                "Stop clip (K)"
            } else {
                "Record clip (K)"
            };
            if ui.button(label).clicked() {
                actions.record = true;
            }
        });
        ui.separator();
        ui.heading("Camera");
        ui.horizontal(|ui| {
            if ui.button("Reset (Home)").clicked() {
                actions.reset_camera = true;
            }
            ui.checkbox(&mut self.fly, "Fly (F)");
        });
        let mut fov = shown.camera.1.to_degrees();
        if ui
            .add(egui::Slider::new(&mut fov, 5.0..=120.0).text("field of view °"))
            .on_hover_text("vertical field of view [degrees]")
            .changed()
        {
            actions.commands.push(Command::Edit(Edit::SetCameraFov {
                yfov_rad: fov.to_radians(),
            }));
        }
        ui.separator();
        ui.heading("Animation");
        ui.horizontal(|ui| {
            let label = if shown.playing { "Pause" } else { "Play" };
            if ui.button(format!("{label} (Space)")).clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::Play(!shown.playing)));
            }
        });
        let mut t = shown.time_s;
        if ui
            .add(egui::Slider::new(&mut t, 0.0..=shown.duration_s.max(0.001)).text("time s"))
            .changed()
        {
            actions
                .commands
                .push(Command::Animation(AnimationCommand::Seek(t)));
        }
        ui.horizontal(|ui| {
            for s in [0.25, 0.5, 1.0, 2.0] {
                if ui.button(format!("{s}×")).clicked() {
                    actions
                        .commands
                        .push(Command::Animation(AnimationCommand::Speed(s)));
                }
            }
        });
        ui.horizontal(|ui| {
            if ui.button("loop").clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::PingPong(false)));
            }
            if ui.button("ping-pong").clicked() {
                actions
                    .commands
                    .push(Command::Animation(AnimationCommand::PingPong(true)));
            }
        });
        ui.separator();
        ui.heading("Selection");
        ui.horizontal_wrapped(|ui| {
            ui.label("lights:");
            for (i, (name, _)) in shown.lights.iter().enumerate() {
                if ui.small_button(name.as_str()).clicked() {
                    actions
                        .commands
                        .push(Command::Select(Some(Selection::Light(i as u32))));
                }
            }
        });
        match &shown.selection {
            None => {
                ui.label("click an object (or near a light)");
            }
            Some((sel, name)) => {
                ui.label(format!("{sel:?}: {name}"));
                ui.label("arrows/PgUp/PgDn move, Shift+←/→ turn");
                if let Selection::Light(i) = sel
                    && let Some((_, kind)) = shown.lights.get(*i as usize)
                    && let Some(new) = light_editor(ui, *kind)
                {
                    actions.commands.push(Command::Edit(Edit::SetLightKind {
                        light: illume_scene::LightId(*i),
                        kind: new,
                    }));
                }
            }
        }
        if !shown.materials.is_empty() {
            ui.horizontal(|ui| {
                ui.label("material");
                let i = self.selected_material.min(shown.materials.len() - 1);
                egui::ComboBox::from_id_salt("material")
                    .selected_text(shown.materials[i].0.as_str())
                    .show_ui(ui, |ui| {
                        for (j, (name, _)) in shown.materials.iter().enumerate() {
                            ui.selectable_value(&mut self.selected_material, j, name.as_str());
                        }
                    });
            });
            let i = self.selected_material.min(shown.materials.len() - 1);
            let c = shown.materials[i].1;
            let mut rgb = [c.x, c.y, c.z];
            if ui.color_edit_button_rgb(&mut rgb).changed() {
                actions.material = Some((i, Vec3::from(rgb)));
            }
        }
        ui.separator();
        egui::CollapsingHeader::new(format!("Settings: {}", shown.technique))
            .default_open(false)
            .show(ui, |ui| self.settings(ui, &shown, actions));
        egui::CollapsingHeader::new("Stats")
            .default_open(true)
            .show(ui, |ui| {
                let t = shown.times;
                ui.label(self.rate_text());
                ui.label(format!(
                    "update {:.1} · advance {:.1} ms",
                    t.update_ms, t.advance_ms
                ));
                ui.label(format!(
                    "G-buffer {:.1} · direct {:.1} · indirect {:.1} ms",
                    t.gbuffer_ms, t.direct_ms, t.indirect_ms
                ));
                ui.label(format!(
                    "reference {:.1} · frame {:.1} · present {:.2} ms",
                    t.reference_ms, t.total_ms, self.present_ms
                ));
                ui.label(format!(
                    "resolution 1/{} ({}×{})",
                    shown.scale,
                    shown.image.width(),
                    shown.image.height()
                ));
                for (k, v) in &shown.stats {
                    ui.label(format!("{k} {v:.4}"));
                }
            });
        let mut all: Vec<String> = shown.messages.clone();
        all.extend(self.messages.all());
        for m in all.iter().rev().take(6) {
            ui.colored_label(egui::Color32::YELLOW, m);
        }
    }

    /// The technique's settings as editable fields, each with its documentation
    /// (meaning, unit, range, default) as a tooltip. An edited field says what applying
    /// it will do — at the next frame, or a rebuild of the technique — before Enter
    /// applies it as `--set TABLE.KEY=VALUE`.
    fn settings(&mut self, ui: &mut egui::Ui, shown: &Shown, actions: &mut Actions) {
        if self.settings_for != shown.settings_toml {
            self.settings_for = shown.settings_toml.clone();
            self.settings_rows = setting_rows(shown.technique, &shown.settings_toml)
                .into_iter()
                .map(|r| {
                    let v = r.value.clone();
                    (r, v)
                })
                .collect();
        }
        ui.label("Hover a name for its meaning, unit and range; Enter applies.");
        if let Some((_, notice)) = &self.rebuilding {
            ui.colored_label(egui::Color32::from_rgb(255, 170, 60), notice.as_str());
        }
        let table = shown.technique.name();
        for (row, text) in &mut self.settings_rows {
            ui.horizontal(|ui| {
                ui.label(row.label.as_str())
                    .on_hover_text(row.tooltip.as_str());
                if let Some(choices) = &row.choices {
                    // A drop-down applies its choice at once (the notice below says
                    // whether that rebuilt the technique).
                    let before = text.clone();
                    egui::ComboBox::from_id_salt(("setting", row.key.as_str()))
                        .selected_text(text.as_str())
                        .show_ui(ui, |ui| {
                            for c in choices {
                                ui.selectable_value(text, c.clone(), c.as_str());
                            }
                        })
                        .response
                        .on_hover_text(row.tooltip.as_str());
                    if *text != before {
                        actions
                            .commands
                            .push(Command::Set(format!("{table}.{}={}", row.key, text)));
                    }
                    return;
                }
                let r = ui
                    .add(egui::TextEdit::singleline(text).desired_width(f32::INFINITY))
                    .on_hover_text(row.tooltip.as_str());
                if r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter)) {
                    actions.commands.push(Command::Set(format!(
                        "{table}.{}={}",
                        row.key,
                        text.trim()
                    )));
                }
            });
            if let Some(notice) = pending_notice(shown.technique, row, text) {
                let colour = match row.applies {
                    Applies::Rebuild => egui::Color32::from_rgb(255, 170, 60),
                    Applies::PerFrame => egui::Color32::LIGHT_GREEN,
                };
                ui.colored_label(colour, notice);
            }
        }
    }

    /// The frame's area: mouse for camera, picking and the split divider.
    fn viewport(&mut self, ui: &mut egui::Ui, actions: &mut Actions) {
        let avail = ui.available_rect_before_wrap();
        let ppp = ui.ctx().pixels_per_point();
        let (w, h) = (
            self.options.config.render.width as f32,
            self.options.config.render.height as f32,
        );
        let fit = ((avail.width() * ppp) / w).min((avail.height() * ppp) / h);
        let scale = if fit >= 1.0 {
            fit.floor()
        } else {
            fit.max(0.01)
        };
        let size_px = egui::vec2(w * scale, h * scale);
        let rect = egui::Rect::from_min_size(avail.min, size_px / ppp);
        actions.image_rect_px = [rect.min.x * ppp, rect.min.y * ppp, size_px.x, size_px.y];
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let Some(shown) = self.shown.clone() else {
            return;
        };
        let to_uv = |p: egui::Pos2| {
            Vec2::new(
                (p.x - rect.min.x) / rect.width(),
                (p.y - rect.min.y) / rect.height(),
            )
        };
        let view = View {
            world_from_camera: shown.camera.0,
            yfov_rad: shown.camera.1,
            origin: Vec2::new(rect.min.x, rect.min.y),
            size: Vec2::new(rect.width(), rect.height()),
        };
        let gizmo = shown
            .selection_pivot
            .filter(|_| !self.fly)
            .and_then(|p| Gizmo::new(view, p));
        let painter = ui.painter_at(rect);
        if self.overlay {
            self.draw_overlay(&painter, rect, &shown);
        }
        let pointer = |p: egui::Pos2| Vec2::new(p.x, p.y);
        if let Some(g) = &gizmo {
            let hovered = self
                .gizmo_drag
                .or_else(|| response.hover_pos().and_then(|p| g.hit(pointer(p))));
            draw_gizmo(&painter, g, hovered);
            self.log_gizmo(g, ppp);
            if response.drag_started()
                && let Some(origin) = ui.input(|i| i.pointer.press_origin())
            {
                self.gizmo_drag = g.hit(pointer(origin));
            }
            if let Some(handle) = self.gizmo_drag
                && response.dragged()
                && let Some(p) = response.interact_pointer_pos()
            {
                let to = pointer(p);
                let d = response.drag_delta();
                let (translate, rotate) = g.drag(handle, to - Vec2::new(d.x, d.y), to);
                if translate != Vec3::ZERO || rotate != Quat::IDENTITY {
                    self.log(&format!("gizmo {handle:?}"));
                    actions
                        .commands
                        .push(Command::MoveSelected { translate, rotate });
                }
            }
        }
        if response.drag_stopped() || gizmo.is_none() {
            self.gizmo_drag = None;
        }
        if self.gizmo_drag.is_some() {
            return;
        }
        // Split divider: drawn, and dragged when grabbed near it.
        if let Some(split) = shown.split {
            let x = rect.min.x + split * rect.width();
            ui.painter().line_segment(
                [egui::pos2(x, rect.min.y), egui::pos2(x, rect.max.y)],
                egui::Stroke::new(2.0, egui::Color32::WHITE),
            );
            ui.painter().text(
                egui::pos2(x + 4.0, rect.min.y + 4.0),
                egui::Align2::LEFT_TOP,
                format!("reference {} spp", shown.reference_spp.unwrap_or(0)),
                egui::FontId::proportional(12.0),
                egui::Color32::WHITE,
            );
            if response.drag_started()
                && let Some(p) = response.interact_pointer_pos()
            {
                self.split_drag = (p.x - x).abs() < 8.0;
            }
            if self.split_drag
                && response.dragged()
                && let Some(p) = response.interact_pointer_pos()
            {
                actions.commands.push(Command::Split(Some(to_uv(p).x)));
                return;
            }
        }
        if response.drag_stopped() {
            self.split_drag = false;
        }
        if response.double_clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            self.log("double-click");
            let id = self.next_pick;
            self.next_pick += 1;
            self.focus_pick = Some(id);
            actions.commands.push(Command::Pick {
                uv: to_uv(p),
                id,
                select: true,
            });
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
            && gizmo.as_ref().is_none_or(|g| g.hit(pointer(p)).is_none())
        {
            self.log("click");
            let id = self.next_pick;
            self.next_pick += 1;
            actions.commands.push(Command::Pick {
                uv: to_uv(p),
                id,
                select: true,
            });
        }
        let Some(mut orbit) = self.orbit else { return };
        let mut moved = false;
        if response.dragged() && !self.split_drag {
            let d = response.drag_delta();
            let (dx, dy) = (d.x / rect.width().max(1.0), d.y / rect.height().max(1.0));
            let pan = response.dragged_by(egui::PointerButton::Secondary)
                || response.dragged_by(egui::PointerButton::Middle)
                || ui.input(|i| i.modifiers.shift);
            if pan {
                orbit.pan(-dx, dy);
            } else if self.fly {
                orbit.look(dx * 3.0, dy * 3.0);
            } else {
                orbit.orbit(dx * 4.0, dy * 4.0);
            }
            moved = true;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                orbit.dolly((-scroll * 0.002).exp());
                moved = true;
                self.log("wheel");
            }
        }
        if moved {
            self.set_camera(orbit);
        }
    }

    /// `--log-input`: the gizmo's place on the window \[physical pixels\] when it moved.
    fn log_gizmo(&mut self, g: &Gizmo, ppp: f32) {
        let Some(x_end) = g.axes[0] else { return };
        let now = [g.centre.x, g.centre.y, x_end.x, x_end.y].map(|v| v * ppp);
        if !self.options.log_input || self.gizmo_logged == Some(now) {
            return;
        }
        self.gizmo_logged = Some(now);
        let ends: Vec<String> = g
            .axes
            .iter()
            .map(|e| {
                e.map_or("none".into(), |e| {
                    format!("{:.1},{:.1}", e.x * ppp, e.y * ppp)
                })
            })
            .collect();
        eprintln!(
            "illume view: gizmo centre_px={:.1},{:.1} axes_px={} length_m={:.5}",
            now[0],
            now[1],
            ends.join(";"),
            g.length_m
        );
    }

    /// The stats overlay in the image's top-left corner: frame time by stage, the
    /// technique's counters, resolution scale.
    fn draw_overlay(&self, painter: &egui::Painter, rect: egui::Rect, shown: &Shown) {
        let t = shown.times;
        let mut text = format!(
            "{}{} · {} · 1/{} ({}×{})\n",
            shown.technique,
            match shown.reference_spp {
                Some(s) if shown.split.is_none() =>
                    format!(" (reference {s}/{} spp)", shown.reference_target),
                Some(s) => format!(" | reference {s}/{} spp", shown.reference_target),
                None => String::new(),
            },
            self.rate_text(),
            shown.scale,
            shown.image.width(),
            shown.image.height()
        );
        text += &format!(
            "G-buffer {:.1} · direct {:.1} · indirect {:.1} · present {:.2} ms\n",
            t.gbuffer_ms, t.direct_ms, t.indirect_ms, self.present_ms
        );
        text += &format!(
            "frame {:.1} ms: update {:.1} · advance {:.1} · reference {:.1}",
            t.total_ms, t.update_ms, t.advance_ms, t.reference_ms
        );
        let prefix = format!("{}.", shown.technique);
        for (k, v) in &shown.stats {
            text += &format!(
                "\n{} {}",
                k.strip_prefix(&prefix).unwrap_or(k),
                short_number(*v)
            );
        }
        if let Some((_, notice)) = &self.rebuilding {
            text += &format!("\n{notice}");
        }
        let galley = painter.layout_no_wrap(
            text,
            egui::FontId::monospace(11.0),
            egui::Color32::from_gray(235),
        );
        let at = rect.min + egui::vec2(6.0, 6.0);
        painter.rect_filled(
            egui::Rect::from_min_size(at, galley.size() + egui::vec2(8.0, 6.0)),
            3.0,
            egui::Color32::from_black_alpha(170),
        );
        painter.galley(at + egui::vec2(4.0, 3.0), galley, egui::Color32::WHITE);
    }

    fn keys(&mut self, ctx: &egui::Context, actions: &mut Actions) {
        let Some(shown) = self.shown.clone() else {
            return;
        };
        let (pressed, shift, dt): (Vec<Key>, bool, f32) = ctx.input(|i| {
            (
                i.events
                    .iter()
                    .filter_map(|e| match e {
                        egui::Event::Key {
                            key, pressed: true, ..
                        } => Some(*key),
                        _ => None,
                    })
                    .collect(),
                i.modifiers.shift,
                i.stable_dt.min(0.1),
            )
        });
        for key in pressed {
            let mut handled = true;
            match key {
                Key::T => {
                    let all = TechniqueKind::ALL;
                    let i = all.iter().position(|k| *k == shown.technique).unwrap_or(0);
                    let n = all.len();
                    let next = if shift { (i + n - 1) % n } else { (i + 1) % n };
                    actions.commands.push(Command::Technique(all[next]));
                }
                Key::R => {
                    let on = !(shown.reference_spp.is_some() && shown.split.is_none());
                    actions.commands.push(Command::Reference(on));
                }
                Key::V => actions
                    .commands
                    .push(Command::Split(shown.split.is_none().then_some(0.5))),
                Key::Space => actions
                    .commands
                    .push(Command::Animation(AnimationCommand::Play(!shown.playing))),
                Key::Home | Key::C => actions.reset_camera = true,
                Key::F => self.fly = !self.fly,
                Key::O => self.overlay = !self.overlay,
                Key::P => actions.screenshot = true,
                Key::K => actions.record = true,
                Key::Num1 => actions.commands.push(Command::Scale(1)),
                Key::Num2 => actions.commands.push(Command::Scale(2)),
                Key::Num4 => actions.commands.push(Command::Scale(4)),
                Key::Plus | Key::Equals => self.exposure_ev += 0.5,
                Key::Minus => self.exposure_ev -= 0.5,
                Key::Escape => actions.commands.push(Command::Select(None)),
                Key::ArrowLeft
                | Key::ArrowRight
                | Key::ArrowUp
                | Key::ArrowDown
                | Key::PageUp
                | Key::PageDown => {
                    self.move_key(key, shift, actions);
                }
                _ => handled = !self.fly || !matches!(key, Key::W | Key::A | Key::S | Key::D),
            }
            if handled {
                self.log(&format!("key {key:?}"));
            }
        }
        // Fly mode: WASD (Q/E down/up) while held.
        if self.fly
            && let Some(mut orbit) = self.orbit
        {
            let speed = orbit.distance.max(0.1) * dt;
            let (f, r, u) = ctx.input(|i| {
                let axis = |a: Key, b: Key| (i.key_down(a) as i32 - i.key_down(b) as i32) as f32;
                (
                    axis(Key::W, Key::S),
                    axis(Key::D, Key::A),
                    axis(Key::E, Key::Q),
                )
            });
            if f != 0.0 || r != 0.0 || u != 0.0 {
                orbit.fly(f * speed, r * speed, u * speed);
                // Keys held: keep moving at every refresh.
                ctx.request_repaint();
                self.set_camera(orbit);
            }
        }
    }

    /// Arrow keys move the selection across the floor relative to the view; PgUp/PgDn
    /// up and down; Shift+←/→ turn it.
    fn move_key(&self, key: Key, shift: bool, actions: &mut Actions) {
        let Some(orbit) = self.orbit else { return };
        let m = orbit.world_from_camera();
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize_or_zero();
        let right = flat(m.transform_vector3(Vec3::X));
        let forward = flat(m.transform_vector3(-Vec3::Z));
        let step = 0.05 * orbit.distance;
        let (translate, turn_rad) = match (key, shift) {
            (Key::ArrowLeft, true) => (Vec3::ZERO, 15f32.to_radians()),
            (Key::ArrowRight, true) => (Vec3::ZERO, -15f32.to_radians()),
            (Key::ArrowLeft, false) => (-right * step, 0.0),
            (Key::ArrowRight, false) => (right * step, 0.0),
            (Key::ArrowUp, _) => (forward * step, 0.0),
            (Key::ArrowDown, _) => (-forward * step, 0.0),
            (Key::PageUp, _) => (Vec3::Y * step, 0.0),
            (Key::PageDown, _) => (-Vec3::Y * step, 0.0),
            _ => return,
        };
        actions.commands.push(Command::MoveSelected {
            translate,
            rotate: Quat::from_rotation_y(turn_rad),
        });
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

/// Colour, intensity and cone of a light; the new kind when changed.
fn light_editor(ui: &mut egui::Ui, kind: LightKind) -> Option<LightKind> {
    let split = |c: Vec3| {
        let m = c.max_element().max(1e-12);
        ((c / m).to_array(), m)
    };
    let mut changed = false;
    let mut edit_power = |ui: &mut egui::Ui, c: Vec3, unit: &str| -> Vec3 {
        let (mut rgb, mut scale) = split(c);
        let speed = scale * 0.01 + 1e-3;
        ui.horizontal(|ui| {
            changed |= ui.color_edit_button_rgb(&mut rgb).changed();
            changed |= ui
                .add(
                    egui::DragValue::new(&mut scale)
                        .speed(speed)
                        .range(0.0..=1e9),
                )
                .on_hover_text(unit)
                .changed();
        });
        Vec3::from(rgb) * scale
    };
    let new = match kind {
        LightKind::Point { intensity } => LightKind::Point {
            intensity: edit_power(ui, intensity, "intensity [W/sr]"),
        },
        LightKind::Directional { irradiance } => LightKind::Directional {
            irradiance: edit_power(ui, irradiance, "irradiance [W/m²]"),
        },
        LightKind::Spot {
            intensity,
            inner_cone_rad,
            outer_cone_rad,
        } => {
            let intensity = edit_power(ui, intensity, "intensity [W/sr]");
            let mut inner = inner_cone_rad.to_degrees();
            let mut outer = outer_cone_rad.to_degrees();
            changed |= ui
                .add(egui::Slider::new(&mut outer, 1.0..=90.0).text("outer cone °"))
                .changed();
            changed |= ui
                .add(egui::Slider::new(&mut inner, 0.0..=outer).text("inner cone °"))
                .changed();
            LightKind::Spot {
                intensity,
                inner_cone_rad: inner.min(outer).to_radians(),
                outer_cone_rad: outer.to_radians(),
            }
        }
    };
    changed.then_some(new)
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let (w, h) = (
            self.options.config.render.width,
            self.options.config.render.height,
        );
        let attrs = Window::default_attributes()
            .with_title("illume view")
            .with_inner_size(winit::dpi::PhysicalSize::new(
                w + PANEL_WIDTH as u32,
                h.max(520),
            ));
        let window = match event_loop.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.fatal = Some(ViewError::Window(e.to_string()));
                event_loop.exit();
                return;
            }
        };
        let gpu = match Gpu::new(window.clone()) {
            Ok(g) => g,
            Err(e) => {
                self.fatal = Some(e);
                event_loop.exit();
                return;
            }
        };
        eprintln!("illume view: adapter {}", gpu.adapter);
        self.egui_state = Some(egui_winit::State::new(
            self.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.max_texture_side()),
        ));
        self.gpu = Some(gpu);
        self.window = Some(window);
        let proxy = self.proxy.clone();
        self.render = Some(RenderThread::start(RenderSetup {
            scene: self.options.scene.clone(),
            config: self.options.config.clone(),
            reference_spp: self.options.reference_spp,
            reference: self.options.reference,
            play: self.options.play,
            max_fps: self.options.max_fps,
            on_frame: Box::new(move || {
                let _ = proxy.send_event(());
            }),
        }));
    }

    fn user_event(&mut self, _: &ActiveEventLoop, _: ()) {
        // A new frame: shown at the next refresh (at most one redraw per refresh however
        // fast frames come, so the window leaves the CPU to the renderer).
        self.frame_pending = true;
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(window) = self.window.clone() else {
            return;
        };
        if let Some(state) = self.egui_state.as_mut()
            && !matches!(event, WindowEvent::RedrawRequested)
        {
            let r = state.on_window_event(&window, &event);
            if r.repaint {
                self.last_input = Instant::now();
                window.request_redraw();
            }
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = self.gpu.as_mut() {
                    gpu.resize(size.width, size.height);
                }
                window.request_redraw();
            }
            WindowEvent::DroppedFile(path) => {
                self.log("drop");
                self.open_dropped(path);
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // Input events redraw at once (egui-winit asks for it in `window_event`); a new
        // frame or egui's own repaint waits for the next refresh. Nothing else wakes the
        // window: an idle window costs nothing.
        if let Some(d) = self.options.duration_s
            && self.exit_at.is_none()
        {
            self.exit_at = Some(self.started + Duration::from_secs_f64(d.max(0.0)));
        }
        if let Some(at) = self.exit_at
            && Instant::now() >= at
        {
            event_loop.exit();
            return;
        }
        // Test mode counts displayed frames: it redraws at every refresh.
        if self.options.exit_after_frames.is_some() {
            self.frame_pending = true;
        }
        let next_refresh = self.last_redraw + REFRESH;
        let mut wake = self.exit_at;
        let due = [
            self.frame_pending.then_some(next_refresh),
            // egui's animations (hover, menus) follow input: honoured for a second after it.
            self.egui_repaint_at
                .filter(|_| self.last_input.elapsed() < Duration::from_secs(1))
                .map(|t| t.max(next_refresh)),
        ]
        .into_iter()
        .flatten()
        .min();
        if let Some(due) = due {
            if Instant::now() >= due {
                self.frame_pending = false;
                self.egui_repaint_at = None;
                if let Some(w) = &self.window {
                    w.request_redraw();
                }
            } else {
                wake = Some(wake.map_or(due, |w| w.min(due)));
            }
        }
        event_loop.set_control_flow(match wake {
            Some(t) => ControlFlow::WaitUntil(t),
            None => ControlFlow::Wait,
        });
    }

    fn exiting(&mut self, _: &ActiveEventLoop) {
        let secs = self.started.elapsed().as_secs_f64();
        let n = self.redraws.max(1) as f64;
        eprintln!(
            "illume view: summary: {} redraws, {:.3} ms each: egui layout {:.3} ms, upload {:.3} ms, acquire {:.3} ms, frame + egui passes {:.3} ms, present {:.3} ms; {} uploads of {:.3} ms (tone map {:.3} ms + upload of a new frame); {} frames from the renderer in {secs:.2} s ({:.2} fps)",
            self.redraws,
            self.redraw_ms_total / n,
            (self.redraw_ms_total - self.gpu_ms_total) / n,
            self.upload_ms_total / n,
            self.acquire_ms_total / n,
            self.render_ms_total / n,
            self.present_call_ms_total / n,
            self.uploads,
            self.upload_ms_total / self.uploads.max(1) as f64,
            self.tonemap_ms_total / self.uploads.max(1) as f64,
            self.frames_received,
            self.frames_received as f64 / secs.max(1e-9)
        );
        // The technique's counters at the last frame shown (photons shot, …), for runs
        // that compare settings over a fixed `--duration`.
        if let Some(shown) = &self.shown {
            let counters: Vec<String> = shown
                .stats
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            eprintln!("illume view: last frame's counters: {}", counters.join(" "));
        }
        if let Some(r) = self.recorder.take() {
            let _ = r.finish();
        }
        // Stop the render thread before the window goes.
        self.render = None;
    }
}

/// One row of the settings panel: a field of the technique's table.
#[derive(Clone, Debug)]
struct SettingRow {
    /// The key in the technique's table.
    key: String,
    /// The current value as TOML text.
    value: String,
    /// The key and its unit.
    label: String,
    /// Meaning, unit, range, default and what a change does.
    tooltip: String,
    /// Whether a change applies at the next frame or rebuilds the technique.
    applies: Applies,
    /// The values a drop-down offers (a boolean's two, an enum's as its doc lists
    /// them); None: edited as text.
    choices: Option<Vec<String>>,
}

/// The settings panel's rows for `technique`, whose table is `settings_toml`: every
/// field but sub-tables, in the settings struct's order, with its documentation
/// (`illume_engine::settings_doc`).
fn setting_rows(technique: TechniqueKind, settings_toml: &str) -> Vec<SettingRow> {
    let Ok(table) = settings_toml.parse::<toml::Table>() else {
        return Vec::new();
    };
    let docs = technique.settings_docs();
    let mut keys: Vec<&String> = docs
        .iter()
        .map(|d| &d.key)
        .filter(|k| table.contains_key(*k))
        .collect();
    keys.extend(table.keys().filter(|k| !docs.iter().any(|d| &d.key == *k)));
    keys.into_iter()
        .filter(|k| !table[*k].is_table())
        .map(|k| {
            let doc = docs.iter().find(|d| &d.key == k);
            let value = match &table[k] {
                toml::Value::String(s) => s.clone(),
                v => v.to_string(),
            };
            let choices = match &table[k] {
                toml::Value::Boolean(_) => Some(vec!["true".to_owned(), "false".to_owned()]),
                toml::Value::String(_) => doc
                    .and_then(|d| d.range.as_deref())
                    .filter(|r| r.contains(" | "))
                    .map(|r| r.split(" | ").map(|v| v.trim().to_owned()).collect()),
                _ => None,
            };
            SettingRow {
                key: k.clone(),
                value,
                label: match doc.and_then(|d| d.unit.as_deref()) {
                    Some(u) => format!("{k} [{u}]"),
                    None => k.clone(),
                },
                tooltip: doc.map_or_else(|| format!("{k}: undocumented"), |d| d.tooltip(technique)),
                applies: doc.map_or(Applies::Rebuild, |d| d.applies),
                choices,
            }
        })
        .collect()
}

/// What applying `edited` to `row` will do, said before it is applied (None when the
/// text is the current value).
fn pending_notice(technique: TechniqueKind, row: &SettingRow, edited: &str) -> Option<String> {
    (edited.trim() != row.value).then(|| match row.applies {
        Applies::Rebuild => format!(
            "⟳ Enter rebuilds {technique}: its state (photons, caches, placements) starts again"
        ),
        Applies::PerFrame => "Enter applies it at the next frame (no rebuild)".to_owned(),
    })
}

/// A counter's value, short.
fn short_number(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.3e}")
    } else if v.fract() == 0.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.3}")
    }
}

/// The gizmo's handles: X red, Y green, Z blue, each ring in a paler tint of its axis's
/// colour (the vertical turn's ring yellow); the handle under the pointer (or dragged)
/// drawn thicker.
fn draw_gizmo(painter: &egui::Painter, g: &Gizmo, active: Option<Handle>) {
    let pos = |v: Vec2| egui::pos2(v.x, v.y);
    let width = |h: Handle| if active == Some(h) { 4.0 } else { 2.0 };
    let ring_colours = [
        egui::Color32::from_rgb(240, 140, 140),
        egui::Color32::from_rgb(240, 200, 40),
        egui::Color32::from_rgb(140, 170, 255),
    ];
    for (k, ring) in g.rings.iter().enumerate() {
        let points: Vec<egui::Pos2> = ring.iter().map(|&p| pos(p)).collect();
        painter.add(egui::Shape::line(
            points,
            egui::Stroke::new(width(Handle::Turn(k)), ring_colours[k]),
        ));
    }
    let colours = [
        egui::Color32::from_rgb(235, 60, 60),
        egui::Color32::from_rgb(60, 210, 60),
        egui::Color32::from_rgb(70, 120, 255),
    ];
    for (i, end) in g.axes.iter().enumerate() {
        if let Some(end) = end {
            let h = Handle::Axis(i);
            painter.line_segment(
                [pos(g.centre), pos(*end)],
                egui::Stroke::new(width(h), colours[i]),
            );
            painter.circle_filled(pos(*end), width(h) + 2.0, colours[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default_table(kind: TechniqueKind) -> String {
        let config = illume_engine::Config {
            technique: kind,
            ..Default::default()
        };
        let value = toml::Value::try_from(&config).unwrap();
        toml::to_string(value.get(kind.name()).unwrap()).unwrap()
    }

    /// Every field of every technique's table has a row whose tooltip carries its doc,
    /// default and what a change does; units show in the label.
    #[test]
    fn every_setting_has_a_documented_tooltip() {
        for &kind in TechniqueKind::ALL {
            let text = default_table(kind);
            let table: toml::Table = text.parse().unwrap();
            let rows = setting_rows(kind, &text);
            for key in table.keys() {
                let row = rows
                    .iter()
                    .find(|r| &r.key == key)
                    .unwrap_or_else(|| panic!("{kind}.{key} has no row"));
                assert!(
                    !row.tooltip.contains("undocumented") && row.tooltip.len() > 60,
                    "{kind}.{key}: {}",
                    row.tooltip
                );
                assert!(row.tooltip.contains("default: "), "{}", row.tooltip);
                assert!(row.tooltip.contains("change: "), "{}", row.tooltip);
            }
        }
        let rows = setting_rows(
            TechniqueKind::PhotonStream,
            &default_table(TechniqueKind::PhotonStream),
        );
        let tile = rows.iter().find(|r| r.key == "tile_size").unwrap();
        assert_eq!(tile.label, "tile_size [pixels]");
        let stride = rows.iter().find(|r| r.key == "shading_stride").unwrap();
        assert!(stride.tooltip.contains("range: 1–8"), "{}", stride.tooltip);
    }

    /// Editing `photon_stream.vsl_count` says it rebuilds before it is applied; a
    /// per-frame field says it does not; an unchanged field says nothing.
    #[test]
    fn a_change_that_rebuilds_says_so_before_it_is_applied() {
        let kind = TechniqueKind::PhotonStream;
        let rows = setting_rows(kind, &default_table(kind));
        let row = |k: &str| rows.iter().find(|r| r.key == k).unwrap();
        let vsl = row("vsl_count");
        assert_eq!(vsl.value, "100");
        assert_eq!(pending_notice(kind, vsl, "100"), None);
        let notice = pending_notice(kind, vsl, "200").expect("a notice");
        assert!(notice.contains("rebuilds photon_stream"), "{notice}");
        let per_frame = pending_notice(kind, row("photons_per_frame"), "5000").unwrap();
        assert!(per_frame.contains("no rebuild"), "{per_frame}");
        // The render thread takes the same decision from the same docs.
        use crate::renderer::setting_applies;
        assert_eq!(
            setting_applies(kind, "photon_stream.vsl_count=200"),
            Applies::Rebuild
        );
        assert_eq!(
            setting_applies(kind, "photon_stream.photons_per_frame=5000"),
            Applies::PerFrame
        );
        assert_eq!(
            setting_applies(TechniqueKind::Reference, "reference.spp_per_frame=8"),
            Applies::PerFrame
        );
    }

    /// Enum settings offer their documented values in a drop-down, booleans true and
    /// false, numbers stay text; every enum's current value is one of its choices.
    #[test]
    fn enums_and_booleans_are_chosen_from_a_list() {
        let kind = TechniqueKind::RadianceCache;
        let rows = setting_rows(kind, &default_table(kind));
        let row = |k: &str| rows.iter().find(|r| r.key == k).unwrap();
        assert_eq!(
            row("temporal").choices.as_deref(),
            Some(
                &[
                    "per_frame".to_owned(),
                    "reuse".to_owned(),
                    "extrapolated".to_owned(),
                    "interpolated".to_owned()
                ][..]
            )
        );
        assert_eq!(row("deletion").choices.as_ref().map(Vec::len), Some(2));
        assert_eq!(row("theta_strata").choices, None);
        for &kind in TechniqueKind::ALL {
            for r in setting_rows(kind, &default_table(kind)) {
                if let Some(c) = &r.choices {
                    assert!(
                        c.contains(&r.value),
                        "{kind}.{}: {} not in {c:?}",
                        r.key,
                        r.value
                    );
                }
            }
        }
    }
}
