//! The closed set of techniques, selected by name. Adding a technique: a variant here, a
//! settings table in [`Config`], one arm in each `match` of this file and of
//! [`Config::technique_settings`]; the compiler lists every place.

use crate::{Config, EngineError};
use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
use illume_precomputed::{Precomputed, PrecomputedSettings};
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings};
use illume_reference::{ReferenceSettings, ReferenceTechnique};
use illume_scene::Timeline;
use illume_selective::SelectiveSettings;
use illume_transport::{SharedWorld, Technique, TechniqueError, TechniqueSettings};

/// How a technique's frame depends on the frames before it in one run
/// ([`TechniqueKind::frame_history`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameHistory {
    /// Samples accumulate while nothing changes and start afresh at any scene change: a
    /// frame that follows a change (and the first) depends on no earlier frame.
    RestartsOnChange,
    /// State carried from frame to frame (why): a frame depends on all before it.
    Carried(&'static str),
}

/// Every technique illume implements; the name is the same everywhere (module, TOML
/// table, CLI value, counter prefix, docs page).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TechniqueKind {
    /// The reference path tracer (ground truth).
    Reference,
    /// Photon streaming with virtual surface lights (Meneveaux & Bridault 2008),
    /// illume's default technique.
    #[default]
    PhotonStream,
    /// Selective photon tracing with Halton pilot and corrective groups (Dmitriev et al.
    /// 2002).
    Selective,
    /// Temporal radiance caching (Gautron et al. 2006), the offline technique for
    /// animations known in advance (in progress: `per_frame` and `reuse` modes).
    RadianceCache,
    /// Precomputed indirect light for a day of sun, PCA-compressed (Bahnsen et al.
    /// 2012): needs a scene with a `[sun]` and a `.illumepc` file (`--data`).
    Precomputed,
}

impl TechniqueKind {
    /// All techniques.
    pub const ALL: &'static [TechniqueKind] = &[
        TechniqueKind::Reference,
        TechniqueKind::PhotonStream,
        TechniqueKind::Selective,
        TechniqueKind::RadianceCache,
        TechniqueKind::Precomputed,
    ];

    /// The technique's one name (its crate's `NAME`).
    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Reference => illume_reference::NAME,
            TechniqueKind::PhotonStream => illume_photon_stream::NAME,
            TechniqueKind::Selective => illume_selective::NAME,
            TechniqueKind::RadianceCache => illume_radiance_cache::NAME,
            TechniqueKind::Precomputed => illume_precomputed::NAME,
        }
    }

    /// Named presets with a one-line description each (the first is `default`).
    pub fn presets(self) -> &'static [(&'static str, &'static str)] {
        match self {
            TechniqueKind::Reference => ReferenceSettings::presets(),
            TechniqueKind::PhotonStream => PhotonStreamSettings::presets(),
            TechniqueKind::Selective => SelectiveSettings::presets(),
            TechniqueKind::RadianceCache => RadianceCacheSettings::presets(),
            TechniqueKind::Precomputed => PrecomputedSettings::presets(),
        }
    }

    /// The preset `name` as the technique's TOML table (None: no such preset).
    pub fn preset_table(self, name: &str) -> Option<toml::Table> {
        fn table<T: TechniqueSettings>(name: &str) -> Option<toml::Table> {
            let settings = T::preset(name)?;
            Some(toml::Table::try_from(settings).expect("settings serialize to a table"))
        }
        match self {
            TechniqueKind::Reference => table::<ReferenceSettings>(name),
            TechniqueKind::PhotonStream => table::<PhotonStreamSettings>(name),
            TechniqueKind::Selective => table::<SelectiveSettings>(name),
            TechniqueKind::RadianceCache => table::<RadianceCacheSettings>(name),
            TechniqueKind::Precomputed => table::<PrecomputedSettings>(name),
        }
    }

    /// What one unit of [`Budget::work`](illume_transport::Budget) is for this
    /// technique.
    pub fn work_unit(self) -> &'static str {
        match self {
            TechniqueKind::Reference => ReferenceSettings::WORK_UNIT,
            TechniqueKind::PhotonStream => PhotonStreamSettings::WORK_UNIT,
            TechniqueKind::Selective => SelectiveSettings::WORK_UNIT,
            TechniqueKind::RadianceCache => RadianceCacheSettings::WORK_UNIT,
            TechniqueKind::Precomputed => PrecomputedSettings::WORK_UNIT,
        }
    }

    /// How a frame depends on the frames rendered before it in one run: whether
    /// `illume animate --shard K/N` (frames apart, on other machines) gives the frames of
    /// the unsharded run.
    pub fn frame_history(self) -> FrameHistory {
        match self {
            TechniqueKind::Reference => FrameHistory::RestartsOnChange,
            TechniqueKind::PhotonStream => FrameHistory::Carried(
                "its photon pool and virtual surface lights build up over the frames",
            ),
            TechniqueKind::Selective => {
                FrameHistory::Carried("its photons and corrective groups build up over the frames")
            }
            TechniqueKind::RadianceCache => {
                FrameHistory::Carried("its cache records are reused from frame to frame")
            }
            TechniqueKind::Precomputed => FrameHistory::Carried(
                "it is interactive: the renderer picks shadow maps or rays per frame from \
                 costs measured on the frames before",
            ),
        }
    }

    /// True for techniques that need the future: they are built with the
    /// [`Timeline`] of the sequence. Interactive techniques never receive it.
    pub fn needs_timeline(self) -> bool {
        match self {
            TechniqueKind::Reference | TechniqueKind::PhotonStream | TechniqueKind::Selective => {
                false
            }
            // The offline technique (for now it uses only the timeline's image size).
            TechniqueKind::RadianceCache => true,
            TechniqueKind::Precomputed => true,
        }
    }

    /// Builds the technique for `world` with its settings from `config`; `timeline` is
    /// handed on only where [`TechniqueKind::needs_timeline`].
    pub fn build(
        self,
        world: &SharedWorld,
        config: &Config,
        timeline: &Timeline,
    ) -> Result<Box<dyn Technique>, EngineError> {
        let wrap = |source: TechniqueError| EngineError::Technique {
            technique: self.name(),
            source,
        };
        Ok(match self {
            TechniqueKind::Reference => Box::new(
                ReferenceTechnique::new(config.reference.clone()).map_err(|e| wrap(e.into()))?,
            ),
            TechniqueKind::PhotonStream => Box::new(
                PhotonStream::new(world, config.photon_stream.clone())
                    .map_err(|e| wrap(e.into()))?,
            ),
            TechniqueKind::Selective => illume_selective::build(world, config.selective.clone())
                .map_err(|e| wrap(e.into()))?,
            TechniqueKind::RadianceCache => {
                let world = world.read().unwrap_or_else(|e| e.into_inner());
                Box::new(
                    RadianceCache::new(&world, timeline, config.radiance_cache.clone())
                        .map_err(|e| wrap(e.into()))?,
                )
            }
            TechniqueKind::Precomputed => {
                let world = world.read().unwrap_or_else(|e| e.into_inner());
                Box::new(
                    Precomputed::new(
                        &world,
                        config.precomputed.clone(),
                        timeline.width(),
                        timeline.height(),
                    )
                    .map_err(|e| wrap(e.into()))?,
                )
            }
        })
    }
}

impl TechniqueKind {
    /// What the technique needs of the scene before its world is built: `precomputed`
    /// with a file gives a scene without a `[sun]` the file's sun (the direct light must
    /// follow the sun the keys were rendered with).
    pub fn prepare_scene(
        self,
        scene: &mut illume_scene::Scene,
        config: &Config,
    ) -> Result<(), EngineError> {
        if self == TechniqueKind::Precomputed {
            illume_precomputed::state::attach_file_sun(scene, &config.precomputed).map_err(
                |e| EngineError::Technique {
                    technique: self.name(),
                    source: e.into(),
                },
            )?;
        }
        Ok(())
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
