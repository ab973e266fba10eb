//! The closed set of techniques, selected by name.

use crate::{Config, EngineError};
use illume_reference::ReferenceTechnique;
use illume_transport::{SharedWorld, Technique};

/// Every technique illume implements; the name is the same everywhere (module, TOML
/// table, CLI value, metric prefix, docs page).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TechniqueKind {
    /// The reference path tracer (ground truth).
    #[default]
    Reference,
}

impl TechniqueKind {
    /// All techniques.
    pub const ALL: &'static [TechniqueKind] = &[TechniqueKind::Reference];

    /// The technique's one name.
    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Reference => "reference",
        }
    }

    /// Builds the technique for `world` with its settings from `config`.
    pub fn build(self, _world: &SharedWorld, config: &Config) -> Result<Box<dyn Technique>, EngineError> {
        Ok(match self {
            TechniqueKind::Reference => Box::new(ReferenceTechnique::new(config.reference.clone())),
        })
    }
}

impl std::str::FromStr for TechniqueKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL.iter().copied().find(|k| k.name() == s).ok_or_else(|| {
            format!("unknown technique '{s}' (have: {})", Self::ALL.iter().map(|k| k.name()).collect::<Vec<_>>().join(", "))
        })
    }
}

impl std::fmt::Display for TechniqueKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
