//! The closed set of techniques, selected by name.

use crate::{Config, EngineError};
use illume_photon_stream::PhotonStream;
use illume_reference::ReferenceTechnique;
use illume_transport::{SharedWorld, Technique};

/// Every technique illume implements; the name is the same everywhere (module, TOML
/// table, CLI value, metric prefix, docs page).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TechniqueKind {
    /// The reference path tracer (ground truth).
    Reference,
    /// Photon streaming with virtual surface lights (Meneveaux & Bridault 2008),
    /// illume's default technique.
    #[default]
    PhotonStream,
}

impl TechniqueKind {
    /// All techniques.
    pub const ALL: &'static [TechniqueKind] =
        &[TechniqueKind::Reference, TechniqueKind::PhotonStream];

    /// The technique's one name.
    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Reference => "reference",
            TechniqueKind::PhotonStream => "photon_stream",
        }
    }

    /// Builds the technique for `world` with its settings from `config`.
    pub fn build(
        self,
        world: &SharedWorld,
        config: &Config,
    ) -> Result<Box<dyn Technique>, EngineError> {
        Ok(match self {
            TechniqueKind::Reference => Box::new(ReferenceTechnique::new(config.reference.clone())),
            TechniqueKind::PhotonStream => Box::new(
                PhotonStream::new(world, config.photon_stream.clone()).map_err(|e| {
                    EngineError::Technique {
                        technique: self.name(),
                        message: e.to_string(),
                    }
                })?,
            ),
        })
    }
}

impl std::str::FromStr for TechniqueKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown technique '{s}' (have: {})",
                    Self::ALL
                        .iter()
                        .map(|k| k.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }
}

impl std::fmt::Display for TechniqueKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
