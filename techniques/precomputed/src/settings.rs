//! Settings of `precomputed` (the `[precomputed]` table), written as a tuning guide.

use illume_transport::{Budget, Pacing, TechniqueSettings};
use serde::{Deserialize, Serialize};

/// Where key images live (Bahnsen et al. §3.1, Fig. 4).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "lowercase")]
pub enum Domain {
    /// One image from the fixed camera (the paper's implementation). Default.
    Screen,
    /// Six faces around a camera that turns in place (its position is fixed).
    Cube,
    /// A world-space lightmap of static geometry and a probe grid for dynamic objects
    /// (any camera; the paper's choice for the general case).
    Atlas,
}

/// Key times (§3.2).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "lowercase")]
pub enum ScheduleKind {
    /// A key every `step_min` (Eq. 1: 288 a day at 5 min).
    Uniform,
    /// Split intervals while PerceptualDiff sees the interpolation (Fig. 6). Default.
    Adaptive,
}

/// How the k temporal coefficients are interpolated between keys (§4.2).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    /// `(1 − α)·L_N + α·L_{N+1}` (Eq. 2; the paper's). Default.
    Linear,
    /// Catmull–Rom on the coefficients and the mean over the four nearest keys
    /// (beyond the paper; §4.2 found non-linear barely better).
    Cubic,
}

/// How colour channels share the PCA (§3.2 leaves it unstated).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "kebab-case")]
pub enum Colour {
    /// One PCA per channel: k components each. Default.
    PerChannel,
    /// One PCA over all three channels (3P samples): the same k temporal eigenvectors.
    Joint,
}

/// How each key's Monte Carlo noise is removed before the PCA (beyond the paper, whose
/// keys came from Mental Ray's photon map and final gather; issue 36).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "lowercase")]
pub enum Denoise {
    /// Keys as the path tracer made them.
    None,
    /// An edge-aware à-trous wavelet filter guided by each texel's surface (normal,
    /// position, albedo demodulated) and its estimated variance ([`illume_render::denoise`]).
    /// Default.
    Atrous,
}

/// The `[precomputed]` table. Defaults are the paper's where it has one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, illume_settings_derive::Settings)]
#[serde(deny_unknown_fields, default)]
pub struct PrecomputedSettings {
    /// The `.illumepc` file to load at construction (`--data FILE`). Empty: precompute
    /// in memory at the first frame (slow; for tests and tiny scenes).
    #[setting(default = String::new())]
    pub data: String,
    /// Where key images live. Default `screen` (§3.1, the paper's implementation):
    /// `screen` is exact per pixel but fixes the camera; `cube` lets it turn in place
    /// (six faces to render and store); `atlas` frees it, at the lightmap's resolution
    /// (`atlas_density`), with probes for dynamic objects.
    #[setting(default = Domain::Screen)]
    pub domain: Domain,
    /// `cube`: pixels along a face's side. 0 (default): the side that matches the image's
    /// pixel density at its centre (height / tan(yfov/2): 857 for 600 pixels at 70°).
    /// Six faces of that side cost 6·side²/(width·height) times a screen key (9× at
    /// 800×600). At most 3344, asked or automatic (six faces within an atlas's 2²⁶
    /// texels).
    #[setting(default = 0, unit = "pixels", range = "≤ 3344")]
    pub cube_face: u32,
    /// `atlas`: lightmap texels per metre of surface. Higher: sharper indirect light and
    /// sky shadows, more texels to render and store (∝ density²). Default 16 (6 cm
    /// texels: indirect light varies slowly; the sun's own shadows are the renderer's).
    #[setting(default = 16.0, unit = "texels/m", range = "(0, inf)")]
    pub atlas_density: f32,
    /// `atlas`: distance between the probes that light dynamic objects \[m\]. Lower:
    /// finer variation on moving objects, more probes (∝ 1/spacing³, 6 values each).
    #[setting(default = 0.5, unit = "m", range = "(0, inf)")]
    pub probe_spacing: f32,
    /// Key times. Default `adaptive` (§3.2).
    #[setting(default = ScheduleKind::Adaptive)]
    pub schedule: ScheduleKind,
    /// Key interval of `uniform` and the smallest interval of `adaptive` \[minutes\].
    /// Lower: more keys, finer in time, longer precompute and larger file. Default 5 (§3.1).
    #[setting(default = 5.0, unit = "minutes", range = "(0, inf)")]
    pub step_min: f64,
    /// First clock hour of the precomputed span \[hours\].
    #[setting(default = 0.0, unit = "hours")]
    pub from_h: f64,
    /// Last clock hour \[hours\].
    #[setting(default = 24.0, unit = "hours")]
    pub to_h: f64,
    /// Beyond the paper: adaptive splits compare the interpolation with a rendered middle
    /// (more renders, catches non-linear changes the ends' test misses).
    #[setting(default = false)]
    pub verify_midpoint: bool,
    /// Samples per pixel of each key (and the sky image). Noise falls as 1/√spp; PCA
    /// removes some of it.
    #[setting(default = 256, range = "≥ 1")]
    pub spp: u32,
    /// Common random numbers: every key uses the same sample pattern per texel (the same
    /// paths; only the sun differs), so what noise is left changes smoothly with the sun
    /// instead of looking like change between keys. Default true; false seeds each key
    /// from its time (the files before issue 36).
    #[setting(default = true)]
    pub common_samples: bool,
    /// Noise removal on each key before the PCA. Default `atrous`; `none` keeps the path
    /// tracer's keys (noisier: lower variance captured at k, more adaptive keys).
    #[setting(default = Denoise::Atrous)]
    pub denoise: Denoise,
    /// Kept PCA components k. Higher: more variance kept (98.6 % at 10, 99.83 % at 20 in
    /// the paper), larger file and O(k) run time per texel. Default 10 (§3.2).
    #[setting(default = 10, range = "≥ 1")]
    pub components: usize,
    /// If set (0–1), the fewest components (≤ `components`) capturing this fraction of
    /// the variance.
    #[setting(default = None, range = "(0, 1]")]
    pub variance_target: Option<f64>,
    /// PCA colour handling: one PCA per channel ([`Colour::PerChannel`], k components
    /// each) or one over all three channels ([`Colour::Joint`], shared eigenvectors).
    #[setting(default = Colour::PerChannel)]
    pub colour: Colour,
    /// Store the PCA images and the sky images as IEEE half floats (2 bytes, values
    /// rounded to 11 significant bits: relative error ≤ 4.9e-4) instead of f32: the file
    /// halves, the key's restoration moves by less than the keys' own noise (measured:
    /// docs/benchmarks/precomputed.md, "Half-float files"). Beyond the paper, which
    /// counts values; the means and coefficients stay f32. Default false.
    #[setting(default = false)]
    pub half_floats: bool,
    /// Interpolation of coefficients. Default `linear` (§3.1, §4.2).
    #[setting(default = Interpolation::Linear)]
    pub interpolation: Interpolation,
    /// Exposure the Yee metric sees key images at (`to_srgb8` of radiance × exposure);
    /// stored in the file.
    #[setting(default = 1.0, range = "(0, inf)")]
    pub exposure: f32,
    /// Seed of the keys' samples (with `common_samples = false`, of (seed, time)):
    /// reproducible on any machine.
    #[setting(default = 0)]
    pub seed: u64,
}

impl PrecomputedSettings {
    /// The paper's algorithm (§3): adaptive keys (§3.2), k = 10 per channel, linear
    /// interpolation (Eq. 2), and no rendered middle in the adaptive test
    /// (`verify_midpoint`, beyond the paper). The keys stay denoised with common random
    /// numbers: the paper's keys came from Mental Ray's photon map and final gather,
    /// free of the path tracer's noise that both remove (issue 36), so they are the
    /// closest stand-in for its input rather than a change to its method. The test
    /// `presets::the_paper_preset_switches_every_deviation_off` pins this list.
    pub fn paper() -> Self {
        Self {
            schedule: ScheduleKind::Adaptive,
            components: 10,
            variance_target: None,
            interpolation: Interpolation::Linear,
            colour: Colour::PerChannel,
            verify_midpoint: false,
            half_floats: false,
            ..Self::default()
        }
    }

    /// Checks every value; the error names the field.
    pub fn validate(&self) -> Result<(), crate::PrecomputedError> {
        let bad = |field: &'static str, reason: String| {
            Err(crate::PrecomputedError::InvalidSetting { field, reason })
        };
        if let Err((field, reason)) = self.validate_ranges() {
            return bad(field, reason);
        }
        if !(self.from_h.is_finite() && self.to_h.is_finite() && self.to_h > self.from_h) {
            return bad("to_h", "must be finite and after from_h".to_owned());
        }
        // Every key is rendered and held in memory for the PCA: refuse a step that asks
        // for more than a file may hold before anything is allocated.
        let keys = (self.to_h - self.from_h) * 60.0 / self.step_min;
        if keys.is_nan() || keys >= crate::file::MAX_KEYS as f64 {
            return bad(
                "step_min",
                format!(
                    "{} min over {}–{} h gives {keys:.3e} keys, more than the {} a \
                     precompute may hold (a key a second for a day: every key is rendered \
                     and kept in memory for the PCA)",
                    self.step_min,
                    self.from_h,
                    self.to_h,
                    crate::file::MAX_KEYS
                ),
            );
        }
        Ok(())
    }
}

impl TechniqueSettings for PrecomputedSettings {
    const NAME: &'static str = crate::NAME;
    const WORK_UNIT: &'static str = "frames (run time does no work per frame)";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        &[
            (
                "default",
                "the paper's: adaptive keys ≥ 5 min apart, k = 10, linear",
            ),
            (
                "paper",
                "the paper's algorithm: adaptive keys, k = 10, linear, no rendered middles (keys denoised: they stand in for its noise-free keys)",
            ),
            (
                "k20",
                "k = 20: no perceptual difference from the keys (§4.3)",
            ),
        ]
    }

    fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper()),
            "k20" => Some(Self {
                components: 20,
                ..Self::default()
            }),
            _ => None,
        }
    }

    fn pace(&mut self, _pacing: Pacing) {}

    fn default_budget(&self) -> Budget {
        Budget::default()
    }

    fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
    }

    fn set_samples_per_pixel(&mut self, spp: u32) -> bool {
        self.spp = spp;
        true
    }
}
