//! winit's events: the window and the render thread created, each redraw (newest
//! frame, egui, input, present), refresh pacing, the test mode and the summary at exit.

use super::{Actions, App, PANEL_WIDTH, REFRESH};
use crate::camera::OrbitCamera;
use crate::present::{Gpu, Viewport, display_bytes};
use crate::renderer::{Command, RenderSetup, RenderThread};
use crate::{ViewError, unix_ms};
use glam::{Vec2, Vec3};
use illume_core::image::ToneMap;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::window::{Window, WindowId};

impl App {
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
                "illume view: frame {} technique={} spp={} commands={} refined={} render_ms={:.1} pivot={} shown_unix_ms={:.1}",
                latest.index,
                latest.technique,
                latest.reference_spp.map_or("none".to_owned(), |s| format!(
                    "{s}/{}",
                    latest.reference_target
                )),
                latest.commands_applied,
                latest.refined_frames,
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

    /// One redraw: the newest frame, egui's pass, the input's commands sent, the frame
    /// and the panels presented.
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
            refine_frames: self.options.refine_frames,
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
