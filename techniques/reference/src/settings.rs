//! Settings of the reference path tracer (`[reference]` table), as a tuning guide.

use illume_transport::{Budget, Pacing, TechniqueSettings};

/// Reference path tracer settings (`[reference]` table). The image size is the
/// renderer's (`[render]`), not the technique's.
#[derive(
    Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, illume_settings_derive::Settings,
)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceSettings {
    /// Samples per pixel of a full-image render ([`ReferenceRenderer`](crate::ReferenceRenderer),
    /// `illume render --technique reference`). Noise falls as 1/√spp, time grows
    /// linearly.
    #[setting(default = 256, range = "≥ 1")]
    pub spp: u32,
    /// Samples per pixel a [`ReferenceTechnique`](crate::ReferenceTechnique) adds each
    /// frame when the frame loop's budget does not say (indirect-only, progressive while
    /// the scene is static). Higher: faster convergence per frame, slower frames.
    #[setting(default = 4, range = "≥ 1", per_frame)]
    pub spp_per_frame: u32,
    /// Bounces before Russian roulette may end a path. Lower: faster, noisier deep
    /// paths (still unbiased).
    #[setting(default = 3)]
    pub rr_start_depth: u32,
    /// Hard limit on bounces, a safety net (Russian roulette ends paths long before in
    /// any scene with albedo < 1).
    #[setting(default = 1024, range = "≥ 1")]
    pub max_depth: u32,
    /// Seed; the same seed gives the same image, bit for bit.
    #[setting(default = 0)]
    pub seed: u64,
}

impl ReferenceSettings {
    /// Checks every value; the error names the field.
    pub fn validate(&self) -> Result<(), crate::ReferenceError> {
        self.validate_ranges()
            .map_err(|(field, reason)| crate::ReferenceError::InvalidSetting { field, reason })
    }
}

impl TechniqueSettings for ReferenceSettings {
    const NAME: &'static str = crate::NAME;
    const WORK_UNIT: &'static str = "samples per pixel";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        &[
            ("default", "256 spp stills, 4 spp per frame"),
            (
                "preview",
                "16 spp stills, 1 spp per frame: a quick, noisy look",
            ),
            (
                "converged",
                "4096 spp stills, 16 spp per frame: ground truth for comparisons",
            ),
        ]
    }

    fn preset(name: &str) -> Option<Self> {
        let d = Self::default();
        match name {
            "default" => Some(d),
            "preview" => Some(Self {
                spp: 16,
                spp_per_frame: 1,
                ..d
            }),
            "converged" => Some(Self {
                spp: 4096,
                spp_per_frame: 16,
                ..d
            }),
            _ => None,
        }
    }

    /// Real time keeps `spp_per_frame`; a fixed amount of work sets it: 0 stays 0 (which
    /// [`TechniqueSettings::check`] refuses, as in a settings file) and more than a u32
    /// holds saturates (its budget then differs from the amount asked for, which the
    /// CLI refuses: `Config::pace`).
    fn pace(&mut self, pacing: Pacing) {
        if let Pacing::FixedWork {
            work_per_frame: Some(n),
        } = pacing
        {
            self.spp_per_frame = u32::try_from(n).unwrap_or(u32::MAX);
        }
    }

    fn default_budget(&self) -> Budget {
        Budget {
            work: Some(self.spp_per_frame as u64),
            time_ms: None,
        }
    }

    fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
    }

    fn set_samples_per_pixel(&mut self, spp: u32) -> bool {
        self.spp = spp;
        true
    }
}

impl ReferenceSettings {
    /// The path kernel's settings.
    pub fn path(&self) -> illume_transport::path::PathSettings {
        illume_transport::path::PathSettings {
            rr_start_depth: self.rr_start_depth,
            max_depth: self.max_depth,
        }
    }
}
