//! The engine: one frame is one function that reads top to bottom —
//! advance time → scene changes → tracer/light refresh → technique update → render →
//! stats ([`Engine::step`]).
//!
//! Techniques are a closed set selected by [`TechniqueKind`] (the CLI's `--technique`
//! value and the TOML table name). Configuration is one TOML file ([`Config`]) with a
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
//! let frame = engine.step(0.5);
//! assert_eq!(frame.frame.full.width(), 16);
//! ```

pub mod config;
pub mod technique_kind;

pub use config::{Config, ConfigError};
pub use technique_kind::TechniqueKind;

use illume_render::{Frame, Renderer};
use illume_scene::{Edit, Scene, SceneChange};
use illume_transport::{Budget, SharedWorld, Technique, TechniqueStats, World};
use std::time::Instant;

/// What one [`Engine::step`] produced.
pub struct StepOutput {
    /// The rendered frame.
    pub frame: Frame,
    /// The scene changes this step applied.
    pub changes: Vec<SceneChange>,
    /// The technique's counters after the frame.
    pub stats: TechniqueStats,
    /// Time spent updating the world and the technique \[ms\].
    pub update_ms: f64,
    /// Time spent in the technique's `advance` \[ms\].
    pub advance_ms: f64,
}

/// A scene, a technique and a renderer, stepped frame by frame.
pub struct Engine {
    world: SharedWorld,
    technique: Box<dyn Technique>,
    renderer: Renderer,
    budget: Budget,
    frame_index: u64,
}

/// Why an engine could not be built.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The scene failed validation.
    #[error("{0}")]
    InvalidScene(String),
    /// The technique could not be constructed.
    #[error("technique {technique}: {message}")]
    Technique {
        /// Which technique.
        technique: &'static str,
        /// Why.
        message: String,
    },
}

impl Engine {
    /// An engine for `scene` with the technique and settings of `config`.
    pub fn new(scene: Scene, config: &Config) -> Result<Self, EngineError> {
        scene
            .validate()
            .map_err(|e| EngineError::InvalidScene(format!("{}: {e}", scene.source)))?;
        let world = World::new(scene).shared();
        let technique = config.technique.build(&world, config)?;
        Ok(Self {
            world,
            technique,
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

    /// Sets the per-frame work budget of the technique.
    pub fn set_budget(&mut self, budget: Budget) {
        self.budget = budget;
    }

    /// Applies an interactive edit now; the technique sees the changes at once.
    pub fn apply_edit(
        &mut self,
        edit: &Edit,
    ) -> Result<Vec<SceneChange>, illume_scene::change::EditError> {
        self.technique.before_world_write();
        let changes = write_world(&self.world).apply_edit(edit)?;
        let world = read_world(&self.world);
        self.technique.scene_changed(&world, &changes);
        Ok(changes)
    }

    /// One frame at scene time `t` \[s\]: advance time, propagate changes, advance the
    /// technique within its budget, render, collect counters.
    pub fn step(&mut self, t: f64) -> StepOutput {
        let t0 = Instant::now();
        self.technique.before_world_write();
        let changes = write_world(&self.world).set_time(t);
        let world = read_world(&self.world);
        if !changes.is_empty() {
            self.technique.scene_changed(&world, &changes);
        }
        let t1 = Instant::now();
        self.technique.advance(&world, &self.budget);
        let t2 = Instant::now();
        let frame = self
            .renderer
            .render(&world, self.technique.as_mut(), self.frame_index);
        drop(world);
        self.frame_index += 1;
        let stats = self.technique.stats();
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        StepOutput {
            frame,
            changes,
            stats,
            update_ms: ms(t0, t1),
            advance_ms: ms(t1, t2),
        }
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
