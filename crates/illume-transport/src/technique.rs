//! The contract every global-illumination technique implements: read this file first.
//!
//! The renderer owns direct light (with shadows) and emission; a technique owns the
//! indirect light: radiance leaving each G-buffer point towards the camera after at
//! least two bounces from a light (light → surface → surface → eye and longer paths).
//!
//! **Life of a technique.** It is built from the world and its settings (a
//! [`TechniqueSettings`] struct, one TOML table). Techniques that need the future
//! (temporal radiance caching, precomputed indirect light) are also handed the
//! [`Timeline`](illume_scene::Timeline) of the sequence at construction; interactive ones
//! never see it. Then the frame loop calls, in order:
//! 1. [`Technique::precompute`] once, before the first frame (with progress);
//! 2. each frame: [`Technique::before_world_write`] before the world changes,
//!    [`Technique::scene_changed`] after it changed, [`Technique::advance`] with the
//!    frame's [`Budget`], [`Technique::indirect`] for the frame's G-buffer, and
//!    [`Technique::stats`].
//!
//! Interactive techniques must not look at future scene states.

use crate::gbuffer::GBuffer;
use crate::world::World;
use illume_core::image::RgbImage;
use illume_core::{Counters, Progress};
use illume_scene::SceneChange;

/// How much work [`Technique::advance`] may do in one frame. Unset fields are
/// unlimited. The work unit is the technique's own ([`TechniqueSettings::WORK_UNIT`]:
/// photons, samples per pixel, cache records…); each technique documents which fields
/// it honours.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Work units to do, in the technique's unit.
    pub work: Option<u64>,
    /// Wall-clock limit \[ms\].
    pub time_ms: Option<f64>,
}

/// How frames are paced, as the CLI's `--realtime` / `--work-per-frame N` say it; each
/// technique maps it onto its own settings ([`TechniqueSettings::pace`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pacing {
    /// Scene time follows the wall clock and frames come as fast as they can: the
    /// technique runs its interactive mode (e.g. a background simulation thread).
    RealTime,
    /// Reproducible frames: a fixed amount of work between frames, `work_per_frame`
    /// units of [`TechniqueSettings::WORK_UNIT`] (None: the technique's default amount).
    FixedWork {
        /// Work units per frame.
        work_per_frame: Option<u64>,
    },
}

/// What a technique did with a list of scene changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChangeResponse {
    /// The technique brought its state up to date (or the changes did not concern it).
    Updated,
    /// The technique cannot follow these changes incrementally; the engine builds it
    /// anew from the current world (and runs its precompute again). `reason` says why,
    /// for logs and counters.
    Rebuild {
        /// Why an incremental update is impossible.
        reason: &'static str,
    },
}

/// Why a technique failed (construction or precompute); the engine keeps it as the
/// source of its own error, with the technique's name.
pub type TechniqueError = Box<dyn std::error::Error + Send + Sync>;

/// A global-illumination technique.
pub trait Technique: Send {
    /// The technique's one name (module, settings table, CLI value, counter prefix).
    fn name(&self) -> &'static str;

    /// Work before the first frame (building caches, key frames…), reported through
    /// `progress`; the engine times it separately from frames. Offline techniques use
    /// the timeline they were built with. Default: nothing.
    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), TechniqueError> {
        let _ = (world, progress);
        Ok(())
    }

    /// The world changed (time step or edit); `world` is already up to date. Changes
    /// not on the technique's timeline (edits, frames off the timeline) are surprises
    /// and must be handled like any interactive change.
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse;

    /// Advances the simulation within `budget`.
    fn advance(&mut self, world: &World, budget: &Budget);

    /// Indirect radiance [W/(m²·sr)] leaving each G-buffer point towards the camera
    /// (black where the pixel sees nothing).
    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage;

    /// Current counters, unprefixed (`photons_per_s`, in the unit the name says); the
    /// engine files them under the technique's name.
    fn stats(&self) -> Counters;

    /// Drops all accumulated state, as if just constructed (precomputed data kept).
    fn reset(&mut self);

    /// The frame loop is about to take the shared world's write lock (a time step or an
    /// edit). Techniques whose threads read the world should let go of it promptly, so
    /// the frame loop does not wait for their work in progress. Default: nothing.
    fn before_world_write(&self) {}

    /// True for techniques meant for interactive frame rates: the renderer's automatic
    /// choices then favour speed over exactness (shadow maps instead of shadow rays).
    /// Default false.
    fn interactive(&self) -> bool {
        false
    }

    /// True when the technique has nothing left to add while the world and camera stay
    /// as they are: the next [`Technique::indirect`] would give the last one's image
    /// (up to noise drawn afresh per frame), and no work of its own is under way. A
    /// viewer may stop rendering frames until something changes. Default false (keep
    /// rendering).
    fn settled(&self) -> bool {
        false
    }

    /// True when [`Technique::indirect`] already holds the sky's whole light at surface
    /// points (direct and indirect, e.g. a precomputed sky image scaled in time): the
    /// renderer then skips its own sky term so that nothing is counted twice. Pixels that
    /// see nothing still show the sky. Default false.
    fn supplies_sky_light(&self) -> bool {
        false
    }
}

/// A technique's settings: one serde struct, one TOML table named
/// [`TechniqueSettings::NAME`], documented as a tuning guide, with named presets. The
/// shared layers (CLI, engine, bench) reach settings only through this trait and the
/// TOML table, never through a technique's fields.
pub trait TechniqueSettings:
    Clone
    + Default
    + PartialEq
    + std::fmt::Debug
    + serde::Serialize
    + serde::de::DeserializeOwned
    + Send
    + 'static
{
    /// The technique's one name: CLI value, settings table, counter and error prefix.
    const NAME: &'static str;

    /// What one unit of [`Budget::work`] is (`--work-per-frame`), e.g. "photons".
    const WORK_UNIT: &'static str;

    /// Named presets with a one-line description each; the first is `default`.
    fn presets() -> &'static [(&'static str, &'static str)];

    /// The preset called `name`, if there is one.
    fn preset(name: &str) -> Option<Self>;

    /// Applies the CLI's pacing (`--realtime`, `--work-per-frame`).
    fn pace(&mut self, pacing: Pacing);

    /// The per-frame budget these settings give when the caller sets none.
    fn default_budget(&self) -> Budget;

    /// Sets the technique's random seed (`--seed`).
    fn set_seed(&mut self, seed: u64);

    /// Sets samples per pixel (`--spp`) of a still; returns false when the technique has
    /// no such setting (the CLI then warns that the flag is ignored). Default: false.
    fn set_samples_per_pixel(&mut self, spp: u32) -> bool {
        let _ = spp;
        false
    }

    /// Turns settings that need the frames known in advance into their nearest setting
    /// that does not, for a window whose frames come as the user acts; returns what
    /// changed, for the user, or None. `animate --realtime` does not call it: there the
    /// flag is the user's choice, and such settings are refused. Default: nothing to do.
    fn adapt_to_interactive(&mut self) -> Option<String> {
        None
    }
}
