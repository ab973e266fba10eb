//! The engine: one frame is one function that reads top to bottom —
//! advance time → scene changes → tracer/light refresh → technique update → render →
//! stats ([`Engine::step`]).
//!
//! Techniques are a closed set selected by [`TechniqueKind`] (the CLI's `--technique`
//! value and the TOML table name), generated from one list below: each line names a
//! technique's registration (`illume_transport::Registration`, in its own crate). Configuration is one TOML file ([`Config`]) with a
//! table per technique; unknown keys are rejected with the file and key named.
//!
//! ```
//! use illume_engine::{Config, Engine, TechniqueKind};
//! let scene = illume_scene::builtin::load("cornell-spot").unwrap();
//! let mut config = Config::default();
//! config.technique = TechniqueKind::Reference;
//! config.render.width = 16;
//! config.render.height = 12;
//! let mut engine = Engine::new(scene, &config).unwrap();
//! let frame = engine.step(0.5).unwrap();
//! assert_eq!(frame.frame.full.width(), 16);
//! assert!(frame.stats.get("reference.spp").is_some()); // counters filed by technique
//! ```

pub mod config;
pub mod settings_doc;
pub mod step_record;
pub mod still;
#[macro_use]
pub mod technique_kind;

pub use config::{AnySettings, ConfigError, ConfigLayers};
pub use illume_transport::{Agreement, AgreementSpec, FrameHistory};
pub use step_record::{FRAMES_CSV_COLUMNS, FramesCsv, StepRecord};
pub use still::{Still, render_denoised_still, render_still};

// The one list of techniques: `Variant(table): registration`. Everything the engine, the
// CLI and the window know of a technique comes from its registration, in its own crate.
techniques! {
    Reference(reference): illume_reference::Descriptor,
    PhotonStream(photon_stream): illume_photon_stream::Descriptor,
    Selective(selective): illume_selective::Descriptor,
    RadianceCache(radiance_cache): illume_radiance_cache::Descriptor,
    Precomputed(precomputed): illume_precomputed::Descriptor,
    #[cfg(test)]
    Ambient(ambient): illume_ambient::Descriptor,
}

use illume_core::{Counters, Progress, Silent};
use illume_render::{Frame, Renderer};
use illume_scene::{Edit, Scene, SceneChange, Timeline};
use illume_transport::{Budget, ChangeResponse, SharedWorld, Technique, TechniqueError, World};
use std::time::Instant;

/// What one [`Engine::step`] produced.
pub struct StepOutput {
    /// The rendered frame.
    pub frame: Frame,
    /// The scene changes this step applied.
    pub changes: Vec<SceneChange>,
    /// The technique's counters after the frame, filed under its name
    /// (`photon_stream.photons_per_s`), then the renderer's choice of shadows for the
    /// frame's analytic lights (`RenderSettings::shadows`): `render.shadow_lights_maps`
    /// and `render.shadow_lights_rays` (lights shadowed each way) and
    /// `render.shadow_maps_rendered` (depth maps rendered, a cube map counting six).
    pub stats: Counters,
    /// Time spent updating the world and the technique \[ms\].
    pub update_ms: f64,
    /// Time spent in the technique's `advance` \[ms\].
    pub advance_ms: f64,
    /// Time spent in the technique's precompute during this step \[ms\]: the first
    /// step when [`Engine::precompute`] was not called, or a step whose changes made the
    /// technique rebuild; 0 otherwise.
    pub precompute_ms: f64,
    /// Why the technique was rebuilt during this step, if it was.
    pub rebuilt: Option<&'static str>,
}

/// A scene, a technique and a renderer, stepped frame by frame.
pub struct Engine {
    world: SharedWorld,
    kind: TechniqueKind,
    config: Config,
    timeline: Timeline,
    technique: Box<dyn Technique>,
    precomputed: bool,
    renderer: Renderer,
    budget: Budget,
    frame_index: u64,
}

/// Why an engine could not be built or run.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The scene failed validation.
    #[error("{0}")]
    InvalidScene(String),
    /// An interactive edit was refused (the world is unchanged).
    #[error("edit refused: {0}")]
    Edit(#[from] illume_scene::change::EditError),
    /// The technique could not be constructed or failed in its precompute. Shown as
    /// the technique's own message, prefixed with its name unless the message already
    /// starts with it (`photon_stream.vsl_count: …`).
    #[error("{}", prefixed(technique, source))]
    Technique {
        /// Which technique.
        technique: &'static str,
        /// The technique's own error.
        source: TechniqueError,
    },
    /// `illume render --denoise` with a technique that has no denoised still.
    #[error("--denoise: {technique} has no denoised still (techniques with one: {have})")]
    NoDenoisedStill {
        /// The technique asked for.
        technique: &'static str,
        /// The techniques that have one, comma-separated.
        have: String,
    },
}

/// `source`'s message under `technique`'s name, once.
fn prefixed(technique: &str, source: &TechniqueError) -> String {
    let message = source.to_string();
    let named = message
        .strip_prefix(technique)
        .is_some_and(|rest| rest.starts_with(['.', ':']));
    if named {
        message
    } else {
        format!("{technique}: {message}")
    }
}

impl Engine {
    /// An engine for `scene` with the technique and settings of `config`, for a
    /// one-frame timeline at the scene's current time (a still, or frames whose times
    /// are not known in advance).
    pub fn new(scene: Scene, config: &Config) -> Result<Self, EngineError> {
        let timeline = Timeline::single(
            scene.clone(),
            scene.time,
            config.render.width,
            config.render.height,
        );
        Self::with_timeline(scene, config, timeline)
    }

    /// An engine for `scene` that will render the frames of `timeline` (techniques that
    /// need the future receive it; frames off the timeline are surprises to them).
    pub fn with_timeline(
        scene: Scene,
        config: &Config,
        timeline: Timeline,
    ) -> Result<Self, EngineError> {
        let mut scene = scene;
        config.technique.prepare_scene(&mut scene, config)?;
        scene
            .validate()
            .map_err(|e| EngineError::InvalidScene(format!("{}: {e}", scene.source)))?;
        let world = World::new(scene).shared();
        let technique = config.technique.build(&world, config, &timeline)?;
        Ok(Self {
            world,
            kind: config.technique,
            config: config.clone(),
            timeline,
            technique,
            precomputed: false,
            renderer: Renderer::new(config.render.clone()),
            budget: config.budget(),
            frame_index: 0,
        })
    }

    /// The shared world (for reading the scene, or for tools that trace rays).
    pub fn world(&self) -> &SharedWorld {
        &self.world
    }

    /// The technique.
    pub fn technique(&self) -> &dyn Technique {
        self.technique.as_ref()
    }

    /// Mutable access to the technique.
    pub fn technique_mut(&mut self) -> &mut dyn Technique {
        self.technique.as_mut()
    }

    /// The timeline the engine was built for.
    pub fn timeline(&self) -> &Timeline {
        &self.timeline
    }

    /// Sets the per-frame work budget of the technique.
    pub fn set_budget(&mut self, budget: Budget) {
        self.budget = budget;
    }

    /// Sets the index the next [`Engine::step`] renders its frame as (later steps count
    /// up from it; a new engine starts at 0). The index seeds the renderer's random
    /// numbers (area-light samples of the direct light), so an engine that renders the
    /// same state as frame `index` of another gets the same direct light.
    pub fn set_frame_index(&mut self, index: u64) {
        self.frame_index = index;
    }

    /// Runs the technique's precompute phase now, reporting to `progress`; returns its
    /// wall-clock time \[ms\]. Does nothing (0 ms) when it already ran. Without this
    /// call the first [`Engine::step`] runs it silently.
    pub fn precompute(&mut self, progress: &mut dyn Progress) -> Result<f64, EngineError> {
        if self.precomputed {
            return Ok(0.0);
        }
        let start = Instant::now();
        let world = read_world(&self.world);
        self.technique
            .precompute(&world, progress)
            .map_err(|source| self.kind.error(source))?;
        self.precomputed = true;
        Ok(start.elapsed().as_secs_f64() * 1e3)
    }

    /// Applies an interactive edit now; the technique sees the changes at once (and is
    /// rebuilt if it asks to be).
    pub fn apply_edit(&mut self, edit: &Edit) -> Result<Vec<SceneChange>, EngineError> {
        self.technique.before_world_write();
        let changes = write_world(&self.world).apply_edit(edit)?;
        self.propagate(&changes)?;
        Ok(changes)
    }

    /// Hands `changes` to the technique; rebuilds it when it asks. Returns the rebuild
    /// reason and the precompute time it took.
    fn propagate(
        &mut self,
        changes: &[SceneChange],
    ) -> Result<(Option<&'static str>, f64), EngineError> {
        if changes.is_empty() {
            return Ok((None, 0.0));
        }
        let response = self
            .technique
            .scene_changed(&read_world(&self.world), changes);
        match response {
            ChangeResponse::Updated => Ok((None, 0.0)),
            ChangeResponse::Rebuild { reason } => {
                self.technique = self.kind.build(&self.world, &self.config, &self.timeline)?;
                self.precomputed = false;
                let ms = self.precompute(&mut Silent)?;
                Ok((Some(reason), ms))
            }
        }
    }

    /// Moves the scene to time `t` \[s\] and hands the changes to the technique (the first
    /// half of [`Engine::step`], without rendering): for viewers that show another image
    /// (the progressive reference) while the animation plays. Returns the changes.
    pub fn set_time(&mut self, t: f64) -> Result<Vec<SceneChange>, EngineError> {
        self.precompute(&mut Silent)?;
        self.technique.before_world_write();
        let changes = write_world(&self.world).set_time(t);
        self.propagate(&changes)?;
        Ok(changes)
    }

    /// The technique this engine runs.
    pub fn kind(&self) -> TechniqueKind {
        self.kind
    }

    /// Whether the next frames are split as the reference splits light (a technique's
    /// direct share moved into `direct`: [`illume_render::Renderer::split`]). Off by
    /// default (frames shown or written whole); stills ([`render_still`]) turn it on.
    pub fn set_split(&mut self, split: bool) {
        self.renderer.split = split;
    }

    /// Where in each pixel the next frames sample ([`illume_render::Renderer::jitter`]):
    /// `Some(offset)` in [0, 1)² takes a BVH ray per pixel through it; `None` (the
    /// default) the pixel centre through the configured primary visibility.
    pub fn set_jitter(&mut self, offset: Option<illume_core::Vec2>) {
        self.renderer.jitter = offset;
    }

    /// One frame at scene time `t` \[s\]: advance time, propagate changes, advance the
    /// technique within its budget, render, collect counters. Fails only when the
    /// technique's precompute (first frame) or a rebuild fails.
    pub fn step(&mut self, t: f64) -> Result<StepOutput, EngineError> {
        self.step_inner(Some(t), &mut Silent)
    }

    /// [`Engine::step`], the frame's long work reported to `progress` (radiance_cache
    /// makes its records inside the frame): a still's one frame ([`render_still`]).
    pub fn step_with_progress(
        &mut self,
        t: f64,
        progress: &mut dyn Progress,
    ) -> Result<StepOutput, EngineError> {
        self.step_inner(Some(t), progress)
    }

    /// One frame at the scene's current time, which is not evaluated again: edits made
    /// since the last step (to animated nodes too) stay as they are. For viewers whose
    /// animation is paused.
    pub fn step_held(&mut self) -> Result<StepOutput, EngineError> {
        self.step_inner(None, &mut Silent)
    }

    fn step_inner(
        &mut self,
        t: Option<f64>,
        progress: &mut dyn Progress,
    ) -> Result<StepOutput, EngineError> {
        let mut precompute_ms = self.precompute(&mut Silent)?;
        let t0 = Instant::now();
        let changes = match t {
            Some(t) => {
                self.technique.before_world_write();
                write_world(&self.world).set_time(t)
            }
            None => Vec::new(),
        };
        let (rebuilt, rebuild_ms) = self.propagate(&changes)?;
        precompute_ms += rebuild_ms;
        let world = read_world(&self.world);
        let t1 = Instant::now();
        self.technique.advance(&world, &self.budget);
        let t2 = Instant::now();
        let frame = self.renderer.render_with_progress(
            &world,
            self.technique.as_mut(),
            self.frame_index,
            progress,
        );
        drop(world);
        self.frame_index += 1;
        let mut stats = self.technique.stats().prefixed(self.kind.name());
        let shadows = frame.shadows;
        stats.set(
            "render.shadow_lights_maps",
            f64::from(shadows.lights_with_maps),
        );
        stats.set(
            "render.shadow_lights_rays",
            f64::from(shadows.lights_with_rays),
        );
        stats.set(
            "render.shadow_maps_rendered",
            f64::from(shadows.maps_rendered),
        );
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        Ok(StepOutput {
            frame,
            changes,
            stats,
            update_ms: ms(t0, t1) - rebuild_ms,
            advance_ms: ms(t1, t2),
            precompute_ms,
            rebuilt,
        })
    }
}

/// Read access to a shared world; a poisoned lock (a panicked thread) is recovered, since
/// the world is only written whole by the frame loop.
pub fn read_world(world: &SharedWorld) -> std::sync::RwLockReadGuard<'_, World> {
    world.read().unwrap_or_else(|e| e.into_inner())
}

/// Write access to a shared world (see [`read_world`]).
pub fn write_world(world: &SharedWorld) -> std::sync::RwLockWriteGuard<'_, World> {
    world.write().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The test technique `ambient` joined through its folder and one line of the list
    /// alone: by name, with its table, built and stepped by the engine. Inside the furnace
    /// (albedo 0.5, emission 1) the light arriving after a bounce is 1 everywhere, so the
    /// ambient term with radiance 1 is the exact indirect light, ρ²·L_e/(1 − ρ) = 0.5.
    #[test]
    fn a_technique_joins_through_its_registration_alone() {
        let kind: TechniqueKind = "ambient".parse().unwrap();
        assert_eq!(kind, TechniqueKind::Ambient);
        let config = Config::layered(&ConfigLayers {
            technique: Some(kind),
            sets: &["ambient.radiance=1.0".to_owned()],
            ..Default::default()
        })
        .unwrap();
        let mut config = config;
        config.render.width = 8;
        config.render.height = 6;
        let scene = illume_scene::builtin::load("furnace").unwrap();
        let mut engine = Engine::new(scene, &config).unwrap();
        let out = engine.step(0.0).unwrap();
        for p in out.frame.indirect.pixels() {
            for c in p.to_array() {
                assert!((c - 0.5).abs() < 1e-5, "indirect {p:?}, expected 0.5");
            }
        }
        assert_eq!(out.stats.get("ambient.radiance"), Some(1.0));
        let e = Config::layered(&ConfigLayers {
            technique: Some(kind),
            sets: &["ambient.radiance=-1".to_owned()],
            ..Default::default()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("ambient.radiance"), "{e}");
    }

    /// A technique's error is shown under its name once (`photon_stream.…`, not
    /// `photon_stream: photon_stream.…`); an error that does not name the technique gets
    /// its name.
    #[test]
    fn technique_errors_are_prefixed_once() {
        let mut config = Config::default();
        config.photon_stream.triangle_scale = 2.0;
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let e = match Engine::new(scene, &config) {
            Ok(_) => panic!("triangle_scale 2 accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.starts_with("photon_stream.triangle_scale: "), "{e}");
        let e = TechniqueKind::Selective
            .error("no light".into())
            .to_string();
        assert_eq!(e, "selective: no light");
    }
}
