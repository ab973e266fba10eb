//! The closed set of techniques, selected by name, generated from the one list in the
//! crate root ([`techniques!`](crate::techniques)): each line names a technique's
//! [`Registration`] (in its own crate), and this module turns it into a
//! [`TechniqueKind`] variant, a table of [`Config`] and an arm of every dispatch.
//! Adding a technique is its folder and one line in that list.

pub use crate::TechniqueKind;
use crate::{Config, EngineError};
use illume_scene::{Scene, Timeline};
use illume_transport::{
    Agreement, FrameHistory, Registration, SharedWorld, StillImages, Technique, TechniqueError,
    TechniqueSettings,
};
use std::any::Any;
use std::marker::PhantomData;

/// Generates [`TechniqueKind`] (a variant per line), [`Config`] (a table per line) and
/// the dispatch from a technique to its registration, from one list of lines
/// `Variant(table): registration,` (the table is the technique's `NAME`; a line may be
/// `#[cfg(…)]`, e.g. a technique only the engine's own tests know).
#[macro_export]
#[doc(hidden)]
macro_rules! techniques {
    ($( $(#[cfg($cfg:meta)])? $variant:ident ($field:ident): $reg:ty, )+) => {
        /// Every technique illume implements; the name is the same everywhere (module,
        /// TOML table, CLI value, counter prefix, docs page). The default is
        /// `photon_stream`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
        #[serde(rename_all = "snake_case")]
        pub enum TechniqueKind {
            $(
                $(#[cfg($cfg)])?
                #[doc = concat!("`", stringify!($field), "`: see `", stringify!($reg), "`.")]
                $variant,
            )+
        }

        impl TechniqueKind {
            /// All techniques, in the list's order.
            pub const ALL: &'static [TechniqueKind] = &[
                $( $(#[cfg($cfg)])? TechniqueKind::$variant, )+
            ];

            /// The technique's registration.
            fn registration(self) -> &'static dyn $crate::technique_kind::Registered {
                match self {
                    $(
                        $(#[cfg($cfg)])?
                        TechniqueKind::$variant => &$crate::technique_kind::Entry::<$reg>(
                            std::marker::PhantomData,
                        ),
                    )+
                }
            }
        }

        /// A whole run's configuration: the technique, the renderer, and a table per
        /// technique (`[photon_stream]`…, each typed by the technique's settings).
        #[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields, default)]
        pub struct Config {
            /// The technique supplying indirect light. Default `photon_stream`.
            pub technique: TechniqueKind,
            /// The renderer (`[render]`).
            pub render: illume_render::RenderSettings,
            $(
                $(#[cfg($cfg)])?
                #[doc = concat!("The `[", stringify!($field), "]` table.")]
                pub $field: <$reg as illume_transport::Registration>::Settings,
            )+
        }

        impl Config {
            /// The settings of technique `kind` (chosen or not).
            pub fn settings_of(&self, kind: TechniqueKind) -> &dyn $crate::AnySettings {
                match kind {
                    $( $(#[cfg($cfg)])? TechniqueKind::$variant => &self.$field, )+
                }
            }

            /// The settings of technique `kind`, to change.
            pub fn settings_of_mut(&mut self, kind: TechniqueKind) -> &mut dyn $crate::AnySettings {
                match kind {
                    $( $(#[cfg($cfg)])? TechniqueKind::$variant => &mut self.$field, )+
                }
            }

            /// The settings of technique `kind`, taken out of the configuration (a
            /// `Box` of its registration's settings type, as an
            /// [`illume_transport::OfflineHost`] hands them over).
            pub fn into_settings(self, kind: TechniqueKind) -> Box<dyn std::any::Any> {
                match kind {
                    $( $(#[cfg($cfg)])? TechniqueKind::$variant => Box::new(self.$field), )+
                }
            }
        }
    };
}

/// `photon_stream`, illume's default technique.
#[allow(
    clippy::derivable_impls,
    reason = "the variants are generated from the list; the default is chosen here"
)]
impl Default for TechniqueKind {
    fn default() -> Self {
        TechniqueKind::PhotonStream
    }
}

/// A registration seen through an object: what [`TechniqueKind`] dispatches to.
#[doc(hidden)]
pub trait Registered: Sync {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn presets(&self) -> &'static [(&'static str, &'static str)];
    fn preset_table(&self, name: &str) -> Option<toml::Table>;
    fn work_unit(&self) -> &'static str;
    fn frame_history(&self) -> FrameHistory;
    fn needs_timeline(&self) -> bool;
    fn agreement(&self) -> Agreement;
    fn build(
        &self,
        world: &SharedWorld,
        settings: &dyn Any,
        timeline: &Timeline,
    ) -> Result<Box<dyn Technique>, TechniqueError>;
    fn prepare_scene(&self, scene: &mut Scene, settings: &dyn Any) -> Result<(), TechniqueError>;
    fn has_still(&self) -> bool;
    fn has_denoised_still(&self) -> bool;
    fn setting_fields(&self) -> &'static [illume_transport::SettingField];
    fn data_key(&self) -> Option<&'static str>;
    fn offline(&self) -> Option<illume_transport::OfflineCommand>;
    fn still(
        &self,
        scene: Scene,
        settings: &dyn Any,
        size: (u32, u32),
        denoised: bool,
        progress: &mut dyn illume_core::Progress,
    ) -> Result<StillImages, TechniqueError>;
}

/// The object for registration `R`.
#[doc(hidden)]
pub struct Entry<R>(pub PhantomData<fn() -> R>);

impl<R: Registration> Entry<R> {
    fn settings(settings: &dyn Any) -> &R::Settings {
        settings
            .downcast_ref()
            .expect("the configuration's table of this technique")
    }
}

impl<R: Registration> Registered for Entry<R> {
    fn name(&self) -> &'static str {
        R::Settings::NAME
    }
    fn summary(&self) -> &'static str {
        R::SUMMARY
    }
    fn presets(&self) -> &'static [(&'static str, &'static str)] {
        R::Settings::presets()
    }
    fn preset_table(&self, name: &str) -> Option<toml::Table> {
        let settings = R::Settings::preset(name)?;
        Some(toml::Table::try_from(settings).expect("settings serialize to a table"))
    }
    fn work_unit(&self) -> &'static str {
        R::Settings::WORK_UNIT
    }
    fn frame_history(&self) -> FrameHistory {
        R::FRAME_HISTORY
    }
    fn needs_timeline(&self) -> bool {
        R::NEEDS_TIMELINE
    }
    fn agreement(&self) -> Agreement {
        R::AGREEMENT
    }
    fn build(
        &self,
        world: &SharedWorld,
        settings: &dyn Any,
        timeline: &Timeline,
    ) -> Result<Box<dyn Technique>, TechniqueError> {
        R::build(world, Self::settings(settings), timeline)
    }
    fn prepare_scene(&self, scene: &mut Scene, settings: &dyn Any) -> Result<(), TechniqueError> {
        R::prepare_scene(scene, Self::settings(settings))
    }
    fn has_still(&self) -> bool {
        R::STILL.is_some()
    }
    fn has_denoised_still(&self) -> bool {
        R::DENOISED_STILL.is_some()
    }
    fn setting_fields(&self) -> &'static [illume_transport::SettingField] {
        <R::Settings as illume_transport::SettingsTable>::FIELDS
    }
    fn data_key(&self) -> Option<&'static str> {
        R::DATA_KEY
    }
    fn offline(&self) -> Option<illume_transport::OfflineCommand> {
        R::OFFLINE
    }
    fn still(
        &self,
        scene: Scene,
        settings: &dyn Any,
        size: (u32, u32),
        denoised: bool,
        progress: &mut dyn illume_core::Progress,
    ) -> Result<StillImages, TechniqueError> {
        let still = match denoised {
            false => R::STILL.expect("asked only where has_still"),
            true => R::DENOISED_STILL.expect("asked only where has_denoised_still"),
        };
        still(scene, Self::settings(settings), size, progress)
    }
}

impl TechniqueKind {
    /// The technique's one name (its settings' `NAME`).
    pub fn name(self) -> &'static str {
        self.registration().name()
    }

    /// One line saying what the technique is, for help texts.
    pub fn summary(self) -> &'static str {
        self.registration().summary()
    }

    /// Named presets with a one-line description each (the first is `default`).
    pub fn presets(self) -> &'static [(&'static str, &'static str)] {
        self.registration().presets()
    }

    /// The preset `name` as the technique's TOML table (None: no such preset).
    pub fn preset_table(self, name: &str) -> Option<toml::Table> {
        self.registration().preset_table(name)
    }

    /// What one unit of [`Budget::work`](illume_transport::Budget) is for this
    /// technique.
    pub fn work_unit(self) -> &'static str {
        self.registration().work_unit()
    }

    /// How a frame depends on the frames rendered before it in one run: whether
    /// `illume animate --shard K/N` (frames apart, on other machines) gives the frames of
    /// the unsharded run.
    pub fn frame_history(self) -> FrameHistory {
        self.registration().frame_history()
    }

    /// True for techniques that need the future: they are built with the
    /// [`Timeline`] of the sequence. Interactive techniques never receive it.
    pub fn needs_timeline(self) -> bool {
        self.registration().needs_timeline()
    }

    /// Where, and within what bounds, the technique agrees with the reference (read by
    /// the shared agreement harness).
    pub fn agreement(self) -> Agreement {
        self.registration().agreement()
    }

    /// Builds the technique for `world` with its settings from `config`; `timeline` is
    /// handed on only where [`TechniqueKind::needs_timeline`].
    pub fn build(
        self,
        world: &SharedWorld,
        config: &Config,
        timeline: &Timeline,
    ) -> Result<Box<dyn Technique>, EngineError> {
        self.registration()
            .build(world, config.settings_of(self).as_any(), timeline)
            .map_err(|source| self.error(source))
    }

    /// What the technique needs of the scene before its world is built (e.g.
    /// `precomputed` with a file gives a scene without a `[sun]` the file's sun).
    pub fn prepare_scene(self, scene: &mut Scene, config: &Config) -> Result<(), EngineError> {
        self.registration()
            .prepare_scene(scene, config.settings_of(self).as_any())
            .map_err(|source| self.error(source))
    }

    /// The key of the technique's table that `--data FILE` sets, when it reads a data
    /// file ([`Registration::DATA_KEY`]).
    pub fn data_key(self) -> Option<&'static str> {
        self.registration().data_key()
    }

    /// Every field of the technique's settings table as declared, in the struct's order
    /// (see [`TechniqueKind::settings_docs`] for the defaults beside them).
    pub fn setting_fields(self) -> &'static [illume_transport::SettingField] {
        self.registration().setting_fields()
    }

    /// The technique's offline command, mounted by the CLI as `illume NAME …`
    /// ([`Registration::OFFLINE`]).
    pub fn offline(self) -> Option<illume_transport::OfflineCommand> {
        self.registration().offline()
    }

    /// True when the technique renders a still by its own route
    /// ([`Registration::STILL`]).
    pub fn has_own_still(self) -> bool {
        self.registration().has_still()
    }

    /// True when the technique renders a denoised still (`illume render --denoise`,
    /// [`Registration::DENOISED_STILL`]).
    pub fn has_denoised_still(self) -> bool {
        self.registration().has_denoised_still()
    }

    /// The still of `scene` by the technique's own route, denoised or not (see
    /// [`TechniqueKind::has_own_still`], [`TechniqueKind::has_denoised_still`]; panics
    /// for a technique without that route).
    pub(crate) fn own_still(
        self,
        scene: Scene,
        config: &Config,
        denoised: bool,
        progress: &mut dyn illume_core::Progress,
    ) -> Result<StillImages, EngineError> {
        let size = (config.render.width, config.render.height);
        self.registration()
            .still(
                scene,
                config.settings_of(self).as_any(),
                size,
                denoised,
                progress,
            )
            .map_err(|source| self.error(source))
    }

    /// `source` as this technique's engine error.
    pub(crate) fn error(self, source: TechniqueError) -> EngineError {
        EngineError::Technique {
            technique: self.name(),
            source,
        }
    }
}

impl std::str::FromStr for TechniqueKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown technique '{s}' (have: {})", Self::names()))
    }
}

impl TechniqueKind {
    /// Every technique's name, comma-separated (for help texts and errors).
    pub fn names() -> String {
        Self::ALL
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl std::fmt::Display for TechniqueKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list's table names are the techniques' `NAME`s (the TOML table, the CLI value
    /// and the serde name of the variant are one name).
    #[test]
    fn every_table_is_named_after_its_technique() {
        let config = toml::Value::try_from(Config::default()).unwrap();
        for &kind in TechniqueKind::ALL {
            assert!(
                config.get(kind.name()).is_some_and(|t| t.is_table()),
                "{kind}"
            );
            let serde_name = toml::Value::try_from(kind).unwrap();
            assert_eq!(serde_name.as_str(), Some(kind.name()));
            assert_eq!(kind.name().parse::<TechniqueKind>(), Ok(kind));
        }
    }
}
