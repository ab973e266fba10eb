//! Settings of the ambient term (`[ambient]` table).

use illume_transport::{Budget, Pacing, TechniqueSettings};

/// The ambient term's settings.
#[derive(
    Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, illume_settings_derive::Settings,
)]
#[serde(deny_unknown_fields, default)]
pub struct AmbientSettings {
    /// Radiance arriving at every surface point after at least one bounce, the same from
    /// every direction [W/(m²·sr)], at least 0. Default 1 (exact in the furnace).
    #[setting(default = 1.0, unit = "W/(m²·sr)", range = "[0, inf)")]
    pub radiance: f32,
}

impl AmbientSettings {
    /// Checks every value; the error names the field.
    pub fn validate(&self) -> Result<(), crate::AmbientError> {
        self.validate_ranges()
            .map_err(|(field, reason)| crate::AmbientError::InvalidSetting { field, reason })
    }
}

impl TechniqueSettings for AmbientSettings {
    const NAME: &'static str = crate::NAME;
    const WORK_UNIT: &'static str = "frames";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        &[("default", "1 W/(m²·sr): the furnace's bounced light")]
    }

    fn preset(name: &str) -> Option<Self> {
        (name == "default").then(Self::default)
    }

    fn pace(&mut self, _pacing: Pacing) {}

    fn default_budget(&self) -> Budget {
        Budget::default()
    }

    fn set_seed(&mut self, _seed: u64) {}
}
