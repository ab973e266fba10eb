//! The contract every global-illumination technique implements: read this file first.
//!
//! The renderer owns direct light (with shadows) and emission; a technique owns the
//! indirect light: radiance leaving each G-buffer point towards the camera after at
//! least two bounces from a light (light → surface → surface → eye and longer paths).
//! A technique whose image holds some direct light as well (precomputed's sky image)
//! says so ([`Technique::supplies_sky_light`]: the renderer skips its own sky term) and
//! hands that share back ([`Technique::direct_share`]: the renderer files it under the
//! frame's direct light), so a frame splits as the reference path tracer splits light.
//!
//! **Life of a technique.** It is built from the world and its settings (a
//! [`TechniqueSettings`] struct, one TOML table). Techniques that need the future
//! (temporal radiance caching, precomputed indirect light) are also handed the
//! [`Timeline`](illume_scene::Timeline) of the sequence at construction; interactive ones
//! never see it. Then the frame loop calls, in order:
//! 1. [`Technique::precompute`] once, before the first frame (with progress);
//! 2. each frame: [`Technique::before_world_write`] before the world changes,
//!    [`Technique::scene_changed`] after it changed, [`Technique::advance`] with the
//!    frame's [`Budget`], [`Technique::indirect`] for the frame's G-buffer (a still's
//!    frame: [`Technique::indirect_with_progress`]), and [`Technique::stats`].
//!
//! Interactive techniques must not look at future scene states.

use crate::gbuffer::GBuffer;
use crate::world::{SharedWorld, World};
use illume_core::image::RgbImage;
use illume_core::{Counters, Progress};
use illume_scene::{Scene, SceneChange, Timeline};

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

    /// [`Technique::indirect`] for a frame that may take long (a still's only frame),
    /// reporting its progress: the same image, bit for bit. A technique whose frame
    /// does its own long work (radiance_cache's records, made where the G-buffer says)
    /// reports it here; `progress` gets whole phases (`begin` … `end`). Default:
    /// [`Technique::indirect`], nothing reported.
    fn indirect_with_progress(
        &mut self,
        world: &World,
        gbuffer: &GBuffer,
        progress: &mut dyn Progress,
    ) -> RgbImage {
        let _ = progress;
        self.indirect(world, gbuffer)
    }

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

    /// The part of the image the last [`Technique::indirect`] returned that is direct
    /// light (light reflected once, as the reference path tracer splits it), one value per
    /// pixel of that image, or None when all of it is indirect. The renderer moves it
    /// from the frame's `indirect` to its `direct` image (`full` unchanged), so that a
    /// technique whose image holds some direct light (precomputed's sky image, which the
    /// renderer's own sky term leaves to it, [`Technique::supplies_sky_light`]) splits a
    /// frame as the reference does. Called once after each [`Technique::indirect`]; the
    /// image is the technique's to hand over (taken, not kept). Default None: the whole
    /// image is indirect light.
    fn direct_share(&mut self) -> Option<RgbImage> {
        None
    }

    /// Whether the renderer will ask for [`Technique::direct_share`] after the next
    /// [`Technique::indirect`] calls: true for a frame split into direct and indirect
    /// light (`illume render --split`, a still, Python's `step(split=True)`), false for
    /// frames shown or written whole (animations, the window, benchmarks), where a
    /// technique may skip the work of its share. Called before every `indirect`.
    /// Default: ignored.
    fn want_direct_share(&mut self, wanted: bool) {
        let _ = wanted;
    }
}

/// A technique's settings: one serde struct, one TOML table named
/// [`TechniqueSettings::NAME`], documented as a tuning guide, with named presets. The
/// shared layers (CLI, engine, bench) reach settings only through this trait and the
/// TOML table, never through a technique's fields.
pub trait TechniqueSettings:
    Clone
    + Default
    + SettingsTable
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

    /// Checks every value against its stated range (and the checks across fields); the
    /// error names the table and the field (`photon_stream.pool_size: …`).
    fn check(&self) -> Result<(), TechniqueError>;

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

    /// Cuts the work of a smoke run (`illume bench --miniature`, which CI runs on every
    /// shipped scenario to check that it still runs): e.g. fewer rays per record, so a
    /// toy-sized image costs seconds. Only what does not scale with the image's pixels
    /// needs cutting; the result must still be valid settings. Default: nothing.
    fn miniature(&mut self) {}
}

/// How a technique's frame depends on the frames before it in one run
/// ([`Registration::FRAME_HISTORY`]): whether `illume animate --shard K/N` (frames apart,
/// on other machines) gives the frames of the unsharded run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameHistory {
    /// Samples accumulate while nothing changes and start afresh at any scene change: a
    /// frame that follows a change (and the first) depends on no earlier frame.
    RestartsOnChange,
    /// State carried from frame to frame (why): a frame depends on all before it.
    Carried(&'static str),
}

/// What "agrees with the reference" means for one technique on `builtin:cornell-spot`
/// (96×72, spot light, with and without a sky): the engine's shared agreement harness
/// renders the technique's indirect light with `sets` and compares it with the reference
/// path tracer's. Plain data, so that any harness can read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AgreementSpec {
    /// Settings (`--set TABLE.KEY=VALUE` form) that make the technique converge.
    pub sets: &'static [&'static str],
    /// Frames stepped at t = 0 before the indirect image is taken.
    pub frames: u32,
    /// |mean(test) / mean(reference) − 1| must stay below this (energy).
    pub max_energy_error: f64,
    /// Relative L1 error of 8×8-pixel block means must stay below this (shape).
    pub max_block_error: f64,
    /// Why these bounds: the technique's known bias and noise, with measured values.
    pub why: &'static str,
}

/// Where a technique is checked against the reference ([`Registration::AGREEMENT`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Agreement {
    /// By the shared harness on `builtin:cornell-spot`, within these bounds.
    CornellSpot(AgreementSpec),
    /// Elsewhere (the scene lacks what the technique needs): where, and why.
    Elsewhere(&'static str),
}

/// A still image split as the reference splits light ([`Registration::still`]).
pub struct StillImages {
    /// direct + indirect.
    pub full: RgbImage,
    /// Emission seen directly plus light reflected once.
    pub direct: RgbImage,
    /// Light reflected two or more times.
    pub indirect: RgbImage,
}

/// A technique's registration: everything the shared layers (engine, CLI, window, bench,
/// agreement harness) know about it, in its own crate. The engine's list of techniques
/// names each registration once (`illume_engine::techniques!`); nothing else outside the
/// technique's folder names its types.
pub trait Registration: 'static {
    /// The settings table (its [`TechniqueSettings::NAME`] is the technique's name).
    type Settings: TechniqueSettings;

    /// One line saying what the technique is (paper, use), for help texts.
    const SUMMARY: &'static str;

    /// How a frame depends on the frames before it.
    const FRAME_HISTORY: FrameHistory;

    /// True for techniques that need the future: they are built with the [`Timeline`] of
    /// the sequence. Interactive techniques never receive it.
    const NEEDS_TIMELINE: bool;

    /// Where and within what bounds the technique agrees with the reference.
    const AGREEMENT: Agreement;

    /// Builds the technique for `world` with `settings`; `timeline` is the sequence's
    /// (a one-frame timeline for techniques that do not [`Registration::NEEDS_TIMELINE`]:
    /// they must not look at it).
    fn build(
        world: &SharedWorld,
        settings: &Self::Settings,
        timeline: &Timeline,
    ) -> Result<Box<dyn Technique>, TechniqueError>;

    /// What the technique needs of the scene before its world is built (e.g. a sun taken
    /// from a data file). Default: nothing.
    fn prepare_scene(scene: &mut Scene, settings: &Self::Settings) -> Result<(), TechniqueError> {
        let _ = (scene, settings);
        Ok(())
    }

    /// The setting that the CLI's `--data FILE` sets (the technique's data file, e.g.
    /// precomputed's `.illumepc`), when it reads one. Default: none (`--data` refused).
    const DATA_KEY: Option<&'static str> = None;

    /// How the technique renders a still by its own route, when it has one (the
    /// reference renders the whole image by path tracing); None: the engine runs the
    /// technique's precompute and one frame.
    const STILL: Option<StillFn<Self::Settings>> = None;

    /// A denoised still by the technique's own route (`illume render --denoise`), when it
    /// has one (the reference: its path-traced still through
    /// `illume_render::denoise`). Never ground truth: benches and tests take their
    /// references from [`Registration::STILL`]. Default: none (`--denoise` refused).
    const DENOISED_STILL: Option<StillFn<Self::Settings>> = None;

    /// The technique's offline command, which the CLI mounts as `illume NAME …`
    /// (precomputed's `illume precompute`). Default: none.
    const OFFLINE: Option<OfflineCommand> = None;
}

/// An error of an offline command, shown to the user with its causes.
pub type OfflineError = Box<dyn std::error::Error + Send + Sync>;

/// A technique's command-line subcommand for offline work ([`Registration::OFFLINE`]).
/// The CLI mounts [`OfflineCommand::command`] under its own command and, when the user
/// chose it, calls [`OfflineCommand::run`] with its matches; what the command needs of
/// the app comes through the [`OfflineHost`].
#[derive(Clone, Copy)]
pub struct OfflineCommand {
    /// The subcommand's name, as typed (`precompute`).
    pub name: &'static str,
    /// The subcommand: its arguments, help texts and nested subcommands.
    pub command: fn() -> clap::Command,
    /// Runs the subcommand given the matches of [`OfflineCommand::command`]. An error
    /// ends the process with status 1 after its message and causes.
    pub run: fn(&clap::ArgMatches, &dyn OfflineHost) -> Result<(), OfflineError>,
}

/// What an offline command needs of the app that mounts it.
pub trait OfflineHost {
    /// The technique's settings after the configuration layers (defaults, then each
    /// `--set TABLE.KEY=VALUE` of `sets`) and the `[render]` table's image size.
    fn settings(&self, sets: &[String]) -> Result<OfflineSettings, OfflineError>;

    /// The scene at `path` (a file or `builtin:NAME`) at time 0, loaded as the CLI loads
    /// scenes (its warnings and a slow load reported on stderr).
    fn load_scene(&self, path: &std::path::Path) -> Result<Scene, OfflineError>;

    /// Progress reports for long work: a spinner labelled `what` between phases, a bar
    /// per phase; [`OfflineProgress::finish`] clears them.
    fn progress(&self, what: &str) -> Box<dyn OfflineProgress>;
}

/// What [`OfflineHost::settings`] hands over.
pub struct OfflineSettings {
    /// The technique's settings: a `Box` of its registration's settings type.
    pub settings: Box<dyn std::any::Any>,
    /// The `[render]` table's image size `(width, height)` [pixels].
    pub image_size: (u32, u32),
}

/// Progress reports that are cleared at the end ([`OfflineHost::progress`]).
pub trait OfflineProgress: illume_core::Progress {
    /// Clears whatever is shown.
    fn finish(&mut self);
}

/// A technique's own route to a still ([`Registration::STILL`],
/// [`Registration::DENOISED_STILL`]): the image of `scene`
/// (already validated, at its current time) at `(width, height)` pixels with
/// `settings` (already checked), reporting to `progress`.
pub type StillFn<S> =
    fn(Scene, &S, (u32, u32), &mut dyn Progress) -> Result<StillImages, TechniqueError>;

/// How a change of one setting reaches a running engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applies {
    /// Read through the frame budget ([`TechniqueSettings::default_budget`]): the running
    /// technique takes the new value at its next frame, its state kept.
    PerFrame,
    /// Read when the technique is built: a change rebuilds it, and its state (photon
    /// pool, VSLs, caches, precomputed data) starts again.
    Rebuild,
}

/// One field of a settings table as declared (`#[derive(Settings)]`, crate
/// `illume-settings-derive`): what tools show of it and what a change does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettingField {
    /// The key in the table (`--set TABLE.KEY=VALUE`).
    pub key: &'static str,
    /// The field's `///` documentation as plain text (links and escapes removed).
    pub doc: &'static str,
    /// The unit (`pixels`, `ms`, `W/(m²·sr)`), declared or carried by the name's suffix.
    pub unit: Option<&'static str>,
    /// The accepted values as declared (`(0, 1]`, `1–8`, `≥ 2`), or an enum's values
    /// (`streaming | deterministic`).
    pub range: Option<&'static str>,
    /// The declared range as its generated check reads it (None: no range declared,
    /// e.g. an enum, whose values are the range). A value outside is refused, NaN too.
    pub bounds: Option<SettingBounds>,
    /// Whether a change applies at the next frame or rebuilds the technique.
    pub applies: Applies,
}

/// The bounds of a setting's declared range ([`SettingField::range`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettingBounds {
    /// The lower bound and whether it is accepted itself; None: none.
    pub low: Option<(SettingBound, bool)>,
    /// The upper bound and whether it is accepted itself; None: none.
    pub high: Option<(SettingBound, bool)>,
    /// The setting holds whole numbers (else floating-point ones).
    pub integer: bool,
}

/// One bound of a declared range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingBound {
    /// A number (±infinity for `inf`).
    Value(f64),
    /// The value of another setting of the same table, by key.
    Field(&'static str),
}

/// A settings struct's declared fields, in the struct's order (generated by
/// `#[derive(Settings)]`; fields that are no setting, `#[serde(skip)]`, left out).
pub trait SettingsTable {
    /// Every setting of the table.
    const FIELDS: &'static [SettingField];
}

/// The values a setting of this type takes, shown as its range when none is declared:
/// an enum's values as the table spells them (`#[derive(SettingValues)]`), None for
/// numbers, flags and text.
pub trait SettingValues {
    /// The values, joined with ` | ` (None: not an enumeration).
    const VALUES: Option<&'static str>;
}

macro_rules! no_values {
    ($($t:ty),* $(,)?) => {
        $(impl SettingValues for $t {
            const VALUES: Option<&'static str> = None;
        })*
    };
}
no_values!(bool, u8, u16, u32, u64, usize, i32, i64, f32, f64, String);

impl<T> SettingValues for Option<T> {
    const VALUES: Option<&'static str> = None;
}

impl<T> SettingValues for Vec<T> {
    const VALUES: Option<&'static str> = None;
}

impl<T, const N: usize> SettingValues for [T; N] {
    const VALUES: Option<&'static str> = None;
}
