//! Settings of temporal radiance caching (`[radiance_cache]` table), written as a tuning
//! guide.
//!
//! Defaults are the paper's values where it gives one (a^t = 0.05, δt_max = 20 frames,
//! a 64×64 hemisphere grid: §6) and reasoned choices where it gives none (a, the R_k
//! clamps, the hemispherical-harmonics order), each explained at its field and in
//! `docs/techniques/radiance_cache.md`. The struct covers the whole technique; the
//! fields of the radiance records (still to come) say so.

use crate::RadianceCacheError;
use crate::record::RecordSettings;
use illume_transport::{Budget, Pacing, TechniqueSettings};
use serde::{Deserialize, Serialize};

/// How records follow time (§4.2–4.4).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    Default,
    illume_settings_derive::SettingValues,
)]
#[serde(rename_all = "snake_case")]
pub enum TemporalMode {
    /// The paper's baseline ("per-frame computation", §6): a new cache for every frame,
    /// no record outlives its frame. The slowest mode and the one that flickers most
    /// (record positions change from frame to frame, Fig. 2).
    PerFrame,
    /// Records live for their lifespan (Eq. 10, Eq. 12, τ from the §4.3 reprojection)
    /// and are replaced at the same place, with no temporal gradient (Fig. 5c): the value
    /// jumps when a record is replaced.
    Reuse,
    /// One pass: temporal gradients extrapolated from the reprojected next-frame estimate
    /// (Eq. 18–20, Fig. 5d). Smaller jumps at replacement than `reuse`.
    Extrapolated,
    /// Two passes: the first (in the precompute phase) computes every record of the
    /// timeline, the second renders with temporal gradients interpolated towards each
    /// record's replacement (Eq. 21–23, Fig. 5e): no jump at replacement. The paper's
    /// choice for quality, and the default.
    #[default]
    Interpolated,
}

impl TemporalMode {
    /// The mode's name in a settings file (`radiance_cache.temporal`).
    pub fn name(self) -> &'static str {
        match self {
            Self::PerFrame => "per_frame",
            Self::Reuse => "reuse",
            Self::Extrapolated => "extrapolated",
            Self::Interpolated => "interpolated",
        }
    }
}

/// Temporal radiance caching settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, illume_settings_derive::Settings)]
#[serde(deny_unknown_fields, default)]
pub struct RadianceCacheSettings {
    /// a, the spatial accuracy of Ward's weight (§3, Eq. 2–3): a record is used at a
    /// point where w_k ≥ 1/a, i.e. within distance a·R_k of it and with normals at most
    /// acos(1 − a²) apart. Unitless, in (0, 1]. Lower: more records (their number grows
    /// as 1/a² over surfaces) and less interpolation error, at a cost linear in the
    /// records. The paper gives no value; default 0.2: 1/w estimates the relative change
    /// of irradiance between the record and the point (WRC88), so a = 0.2 admits points
    /// where that first-order change is at most 20 %, which the gradients of Eq. 4 then
    /// correct to first order; normals up to 11.5° apart; spheres of influence of R_k/5.
    #[setting(default = 0.2, range = "(0, 1]")]
    pub accuracy: f32,
    /// Smallest R_k (harmonic mean distance, §3), as a fraction of the scene's
    /// bounding-box diagonal. Near corners and contacts R_k tends to zero and Ward's
    /// weight would place records without bound; this clamp caps the record density at
    /// about one per π(a·R_min)². It also bounds the distances used by the translation
    /// gradient. Lower: finer indirect detail in corners, at the cost of more records
    /// there. In (0, 1], at most `r_max_fraction`; default 0.01 (3.5 cm in the 2 m
    /// cube-in-box).
    #[setting(default = 0.01, range = "(0, 1]")]
    pub r_min_fraction: f32,
    /// Largest R_k, as a fraction of the scene's bounding-box diagonal. Where most
    /// gather rays escape (open scenes) R_k is unbounded and one record would serve a
    /// whole plane; this clamp keeps spheres of influence below a·R_max. Higher: fewer
    /// records in open regions, at the cost of extrapolating further. In (0, 10];
    /// default 0.5: the harmonic mean distance inside a closed room is of the order of
    /// its smaller dimensions, below half its diagonal (tested at the floor centre of
    /// the cube-in-box), so the clamp binds mostly where rays escape.
    #[setting(default = 0.5, range = "(0, 10]")]
    pub r_max_fraction: f32,
    /// Beyond the paper: the smallest sphere of use on the image, as a fraction of the
    /// image height (Tabellion & Lamorlette 2004 clamp R_k in screen space). R_k is
    /// raised until a·R_k spans at least this fraction of the image height at the
    /// record's distance from the camera. Where irradiance caching would place records
    /// closer than the image needs (near corners and contacts, where the harmonic mean
    /// distance is small), the gradients extrapolate over the sphere instead. A fraction
    /// rather than pixels keeps a frame's record count, hence its cost, from growing with
    /// the resolution. Higher: fewer records and cheaper frames, at the cost of
    /// smoothing indirect detail smaller than the sphere. Unitless, 0–0.5; 0 turns it
    /// off. Default 0.04 (1/25: 10 pixels at 240 rows, 19 at 480): on
    /// `builtin:cornell-spot` it cuts a 640×480 still's records 5 499 → 1 457 and its
    /// time 10.5 → 2.7 s, for HDR-FLIP 0.059 → 0.064 against the path tracer
    /// (docs/benchmarks/radiance_cache.md, "a smallest sphere of use on the image");
    /// `--preset paper`: 0.
    #[setting(default = 0.04, range = "[0, 0.5]")]
    pub min_sphere_fraction: f32,
    /// Also clamp R_k to E/|∇_p E| (the smallest over channels; Křivánek et al. 2006,
    /// beyond the paper): the translation term of Eq. 4 then changes a record's value by
    /// at most the fraction a within its sphere, so extrapolation stays positive where
    /// indirect light changes fast (indirect shadow edges) although the geometry is far.
    /// True costs more records along such edges.
    #[setting(default = true)]
    pub gradient_limit: bool,
    /// Beyond the paper: records fade out at the edge of their sphere of use. Eq. 1
    /// weights a usable record by Ward's w_k = 1/ε (Eq. 2), which is 1/a at the edge
    /// and zero beyond it: where neighbouring records' values differ (each carries its
    /// own noise), the image jumps along the edge, drawing the record's circle (seen on
    /// the back wall of `builtin:cornell-spot` at 640×480). True weights by 1/ε − 1/a,
    /// zero at the edge, so the image is continuous there; the records used, their
    /// order and the value at a record are unchanged. Default true; `--preset paper`:
    /// false (Ward's weight).
    #[setting(default = true)]
    pub smooth_weights: bool,
    /// Strata of the hemisphere grid in θ (cosine-weighted: each stratum has the same
    /// projected solid angle), §6: 64. Rays per record = `theta_strata × phi_strata`.
    /// Higher: less noise per record and finer gradients, at a cost linear in the rays.
    /// 2–1024, default 64.
    #[setting(default = 64, range = "2–1024", max = MAX_STRATA)]
    pub theta_strata: u32,
    /// Strata of the hemisphere grid in φ, §6: 64. 3–1024, default 64.
    #[setting(default = 64, range = "3–1024", max = MAX_STRATA)]
    pub phi_strata: u32,
    /// a^t, the temporal accuracy (§4.2, Eq. 10): a record made at t₀ stays valid while
    /// |τ − 1|·(t − t₀) ≤ a^t, τ = E₁/E₀ its irradiance's change over one frame. Its
    /// lifespan is 1 + min(⌊a^t/|τ − 1|⌋, δt_max − 1) frames. Unitless, in (0, 1].
    /// Lower: shorter lifespans (more records computed), less lag behind changing light.
    /// Default 0.05 (§6).
    #[setting(default = 0.05, range = "(0, 1]")]
    pub temporal_accuracy: f32,
    /// δt_max, the longest lifespan in frames (§4.2, Eq. 12), even for records whose
    /// irradiance does not change: a change that a record's rays do not yet see (an
    /// object about to enter its hemisphere, Fig. 4) is caught within this many frames.
    /// Lower: fewer ghosts, at the cost of more records. 1–100 000, default 20 (§6).
    /// Beyond the paper, in real time (`--realtime`, the window): records made since the
    /// world last changed (camera moves aside) do not age, so a still world stops
    /// computing records and settles; records made before a change still expire within
    /// δt_max frames of it.
    #[setting(default = 20, range = "1–100 000")]
    pub max_age_frames: u32,
    /// How records follow time. Default [`TemporalMode::Interpolated`] (the paper's
    /// choice). `extrapolated` and `interpolated` need the frames known in advance (a
    /// timeline) and are refused with `--realtime`, whose frame times are known only as
    /// they come; `per_frame` and `reuse` run anywhere (in real time every change is a
    /// surprise, so `reuse` then lives on δt_max, surprise expiry and the ageless records
    /// of a still world, [`max_age_frames`](Self::max_age_frames)).
    #[setting(default = TemporalMode::Interpolated)]
    pub temporal: TemporalMode,
    /// Surfaces that are not exactly Lambertian and whose perceptual roughness is at or
    /// below this are glossy: their specular lobe is shaded from radiance records
    /// (hemispherical harmonics, §3, KGPB05), their diffuse part from irradiance
    /// records (the paper's Japanese Interior). Rougher surfaces are shaded from
    /// irradiance records alone, as if Lambertian with the BRDF's albedo. Lower: fewer
    /// radiance records (n² RGB coefficients each against one RGB value), at the cost of
    /// that approximation, which holds for rough dielectrics (their specular lobe is a
    /// small part of what they reflect) but not for metals at any roughness
    /// (`BENCHMARKS.md`, radiance_cache). In [0, 1], at least `traced_roughness_max`;
    /// default 1: every non-Lambertian surface keeps its lobe.
    #[setting(default = 1.0, range = "[0, 1]")]
    pub glossy_roughness_max: f32,
    /// Order n of the hemispherical harmonics of radiance records (bands 0..n, n²
    /// coefficients per colour channel). The paper gives none. Higher: sharper lobes
    /// served by records (see `traced_roughness_max`), at the cost of memory (n² RGB
    /// coefficients and their gradients per record) and shading time (n² per record
    /// and pixel). 1–16, default 8.
    #[setting(default = 8, range = "1–16", max = crate::hsh::MAX_ORDER)]
    pub hsh_order: u32,
    /// Glossy lobes of surfaces smoother than this are too sharp for `hsh_order`: their
    /// specular part is traced per pixel (with `continue_path`) instead of read from
    /// radiance records. In [0, `glossy_roughness_max`]; default 0.5, the smallest
    /// roughness (in steps of 0.05) whose BRDF×cos lobe order 8 represents within 10 %
    /// (relative L²) for views up to 45° off the normal, for a white metal (the
    /// sharpest lobe at a roughness; tested in `tests/hsh.rs`).
    #[setting(default = 0.5, range = "[0, glossy_roughness_max]")]
    pub traced_roughness_max: f32,
    /// Rays per pixel for the specular part of glossy surfaces smoother than
    /// `traced_roughness_max` (drawn from the BRDF, each bringing back `continue_path`'s
    /// reflected light; the same random numbers for a pixel in every frame, so a still
    /// scene does not flicker). Higher: less noise in sharp glossy reflections, at a cost
    /// linear in it (one path per ray). 1–4096, default 16.
    #[setting(default = 16, range = "1–4096")]
    pub traced_rays: u32,
    /// Largest number of 3×3 averaging passes that fill the holes of a reprojected
    /// next-frame grid (§4.3, Fig. 8); cells still empty after them take the grid's mean.
    /// Higher: holes filled from nearer cells only, at a cost per pass. 1–4096,
    /// default 64 (the grid's side).
    #[setting(default = 64, range = "1–4096")]
    pub hole_fill_max_passes: u32,
    /// Beyond the paper: an expired record is replaced only where a surface facing its
    /// normal still lies at its position (else it is deleted), so records on objects
    /// that moved away do not float in the air.
    #[setting(default = true)]
    pub replace_only_on_surface: bool,
    /// Beyond the paper: a replacement traces its predecessor's directions with its
    /// random numbers, so E_l − E_k (Eq. 21) measures change, not noise.
    #[setting(default = true)]
    pub reuse_directions: bool,
    /// Beyond the paper: a change not on the timeline (an edit, a frame off the
    /// timeline) expires the records on the changed instance and those whose rays hit
    /// it (a moved, added or removed instance), or every record (a light, sky or
    /// material change). False: such records live out their lifespan (ghosts). Default
    /// true. Changes on the timeline expire nothing: τ and the lifespans handle them.
    #[setting(default = true)]
    pub expire_on_surprise: bool,
    /// §7's future work, beyond the paper: a new record (or replacement) whose lifespan
    /// is shorter than `max_age_frames` ends the lives of the records usable at its
    /// position (w ≥ 1/a there) no later than its own, so a change seen by one record
    /// ages its neighbours too. True: fewer ghosts next to changes a record's own rays
    /// did not see, at the cost of more replacements. Default false (the paper's
    /// behaviour).
    #[setting(default = false)]
    pub neighbour_aging: bool,
    /// §5, Fig. 9: an expired record that no pixel of its last frame used is deleted
    /// instead of replaced (the paper reports −25–30 % storage, −20–30 % time). False:
    /// every expired record is replaced.
    #[setting(default = true)]
    pub deletion: bool,
    /// Most records a frame computes (new records and replacements; pass 1 of
    /// `interpolated` and the planned records pass 2 admits are not counted), the
    /// technique's `Budget::work` in records when the frame loop sets none
    /// (`--work-per-frame N` sets this). Not in the paper, whose frames compute every
    /// record they need. 0: no limit (the default). When a frame needs more, the
    /// replacements come first (in record order), the rest wait a frame (their
    /// records live one frame longer); new records go to the coarsest placement grids
    /// first, spread evenly over a grid's pixels, and pixels no record reaches take the
    /// irradiance of neighbouring pixels on the same surface (image-space fill). Lower:
    /// bounded frame times, at the cost of coarser indirect light for as many frames as
    /// the backlog takes to clear. Records per frame.
    #[setting(default = 0, per_frame)]
    pub records_per_frame_max: u64,
    /// A diagnostic view, not a tuning setting (the paper's Fig. 1c): the indirect image
    /// also shows each live record the camera sees as one pixel at its position,
    /// coloured by its lifespan from red (1 frame) to green (`max_age_frames`), at 8 ×
    /// the image's mean luminance. `--set radiance_cache.show_records=true`. Default
    /// false.
    #[setting(default = false)]
    pub show_records: bool,
    /// Reflections after which Russian roulette may end a gather ray's path
    /// (`continue_path`). Lower: faster, noisier records (still unbiased).
    #[setting(default = 3)]
    pub rr_start_depth: u32,
    /// Hard limit on a gather ray's reflections: 1 caches one bounce of indirect light
    /// (the light each gather ray's hit reflects straight from the emitters), more caches
    /// every bounce. Beyond the paper: its records are made by rasterizing the scene over
    /// the record with each visible point's own lighting ("the position and incoming
    /// lighting … of each point visible to p_k", §5, after GKBP05; "the outgoing radiance
    /// of reprojected visible points … accounting for … light sources", §4.3), one
    /// bounce, which `--preset paper` sets. One bounce changes faster when a light moves
    /// (records live shorter: the Moving Light's 0.95×) and misses the light of later
    /// bounces (a white box's indirect light is largely multiply reflected). At least 1;
    /// default 1024, a safety net behind Russian roulette (every bounce).
    #[setting(default = 1024, range = "≥ 1")]
    pub max_depth: u32,
    /// Seed of the gather rays' jitter and paths: the same seed gives the same records,
    /// whatever the thread count.
    #[setting(default = 0)]
    pub seed: u64,
    /// Set by `--realtime` pacing ([`TechniqueSettings::pace`]), not a setting.
    #[serde(skip)]
    #[setting(default = false)]
    pub paced_real_time: bool,
}

/// The largest grid side accepted (`theta_strata`, `phi_strata`): 1024² rays per record.
pub const MAX_STRATA: u32 = 1024;

impl TechniqueSettings for RadianceCacheSettings {
    const NAME: &'static str = crate::NAME;
    /// Records computed in a frame (new records and replacements); [`Budget::work`]
    /// caps them (see [`RadianceCacheSettings::records_per_frame_max`]).
    const WORK_UNIT: &'static str = "records";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        RadianceCacheSettings::presets()
    }

    fn preset(name: &str) -> Option<Self> {
        RadianceCacheSettings::preset(name)
    }

    /// `work_per_frame` sets `records_per_frame_max`. Real-time pacing is remembered:
    /// the modes that need the frames known in advance (`extrapolated`,
    /// `interpolated`) are then refused at construction.
    fn pace(&mut self, pacing: Pacing) {
        self.paced_real_time = matches!(pacing, Pacing::RealTime);
        if let Pacing::FixedWork {
            work_per_frame: Some(n),
        } = pacing
        {
            self.records_per_frame_max = n;
        }
    }

    /// `records_per_frame_max` records per frame (none when it is 0: a frame computes
    /// every record its G-buffer needs).
    fn default_budget(&self) -> Budget {
        Budget {
            work: (self.records_per_frame_max > 0).then_some(self.records_per_frame_max),
            time_ms: None,
        }
    }

    fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
    }

    /// `extrapolated` and `interpolated` reproject records into frames known in advance:
    /// records are reused in their place (`reuse`, the same lifespans without temporal
    /// gradients).
    /// 8×8 rays per record and 2 traced glossy rays: a record's cost does not fall with
    /// the image size, and a toy image still places hundreds of them.
    fn miniature(&mut self) {
        self.theta_strata = self.theta_strata.min(8);
        self.phi_strata = self.phi_strata.min(8);
        self.traced_rays = self.traced_rays.min(2);
    }

    fn adapt_to_interactive(&mut self) -> Option<String> {
        matches!(
            self.temporal,
            TemporalMode::Extrapolated | TemporalMode::Interpolated
        )
        .then(|| {
            let asked = self.temporal.name();
            self.temporal = TemporalMode::Reuse;
            format!(
                "radiance_cache: temporal = \"{asked}\" needs the frames known in advance; \
                 the window uses \"reuse\""
            )
        })
    }
}

impl RadianceCacheSettings {
    /// The paper: its values (§6), the reasoned choices where it gives none (as the
    /// default), records of one bounce (`max_depth` 1, §4.3 and §5), Ward's weight and every
    /// addition of this implementation switched off (`gradient_limit`,
    /// `replace_only_on_surface`, `reuse_directions`, `expire_on_surprise`,
    /// `smooth_weights`, `min_sphere_fraction`; `neighbour_aging` is off by default).
    /// The test `settings::the_paper_preset_switches_every_deviation_off` pins this list.
    pub fn paper() -> Self {
        Self {
            gradient_limit: false,
            replace_only_on_surface: false,
            reuse_directions: false,
            expire_on_surprise: false,
            neighbour_aging: false,
            max_depth: 1,
            smooth_weights: false,
            min_sphere_fraction: 0.0,
            ..Self::default()
        }
    }

    /// The preset for `render`'s stills: the defaults in `per_frame` mode (one frame: the
    /// same image as `reuse`, without keeping the records).
    pub fn still() -> Self {
        Self {
            temporal: TemporalMode::PerFrame,
            ..Self::default()
        }
    }

    /// Previews: a = 0.3 (about half the records), a 32×32 grid (a quarter of the rays
    /// per record), HSH order 6 (36 coefficients) with lobes below roughness 0.6 traced
    /// (the same 10 % criterion as the default's).
    pub fn fast() -> Self {
        Self {
            accuracy: 0.3,
            theta_strata: 32,
            phi_strata: 32,
            hsh_order: 6,
            traced_roughness_max: 0.6,
            hole_fill_max_passes: 32,
            ..Self::default()
        }
    }

    /// Named presets with a one-line description each; the first is `default`
    /// ([`TechniqueSettings::presets`]).
    pub fn presets() -> &'static [(&'static str, &'static str)] {
        &[
            (
                "default",
                "the paper's values (§6: a = 0.2, 64×64 rays per record, a^t = 0.05, δt_max = 20, interpolated) with records of every bounce and six additions (records fading out at their edge and a smallest sphere of use on the image among them), which `paper` turns off",
            ),
            (
                "paper",
                "the paper: its §6 values, records of one bounce (§4.3, §5), Ward's weight, no gradient limit, replacements anywhere with new directions, no expiry on surprises",
            ),
            (
                "still",
                "the defaults in per_frame mode: `render`'s default",
            ),
            (
                "fast",
                "a = 0.3, 32×32 rays per record, HSH order 6 (lobes below roughness 0.6 traced): previews",
            ),
        ]
    }

    /// The preset called `name`, if there is one.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper()),
            "fast" => Some(Self::fast()),
            "still" => Some(Self::still()),
            _ => None,
        }
    }

    /// What a record computation needs from these settings, for a scene whose
    /// bounding-box diagonal is `scene_diagonal_m` (the R_k clamps become metres).
    pub fn record_settings(&self, scene_diagonal_m: f32) -> RecordSettings {
        RecordSettings {
            theta_strata: self.theta_strata,
            phi_strata: self.phi_strata,
            r_min_m: self.r_min_fraction * scene_diagonal_m,
            r_max_m: self.r_max_fraction * scene_diagonal_m,
            gradient_limit: self.gradient_limit,
            path: illume_transport::path::PathSettings {
                rr_start_depth: self.rr_start_depth,
                max_depth: self.max_depth,
            },
            seed: self.seed,
            ..RecordSettings::default()
        }
    }

    /// Checks every value; the error names the field (`radiance_cache.FIELD: …`).
    pub fn validate(&self) -> Result<(), RadianceCacheError> {
        let bad = |field: &'static str, reason: String| {
            Err(RadianceCacheError::InvalidSetting { field, reason })
        };
        if let Err((field, reason)) = self.validate_ranges() {
            return bad(field, reason);
        }
        if self.r_min_fraction > self.r_max_fraction {
            return bad(
                "r_min_fraction",
                format!(
                    "{} is larger than r_max_fraction = {}",
                    self.r_min_fraction, self.r_max_fraction
                ),
            );
        }
        if self.paced_real_time
            && matches!(
                self.temporal,
                TemporalMode::Extrapolated | TemporalMode::Interpolated
            )
        {
            let name = self.temporal.name();
            return bad(
                "temporal",
                format!(
                    "`{name}` needs the frames known in advance (it reprojects records into \
                     the next frame{}), but --realtime frames come at times known only as \
                     they are rendered; drop --realtime (or use --work-per-frame), or set \
                     radiance_cache.temporal = \"reuse\" or \"per_frame\"",
                    if name == "interpolated" {
                        " and plans every record of the timeline first"
                    } else {
                        ""
                    }
                ),
            );
        }
        Ok(())
    }
}
