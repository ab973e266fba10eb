//! Settings of photon streaming (`[photon_stream]` table), written as a tuning guide.

use illume_transport::{Budget, Pacing, TechniqueSettings};
use serde::{Deserialize, Serialize};

/// How photons are shot.
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
pub enum StreamMode {
    /// §0.7.2: a long-lived simulation thread shoots photons continuously while frames
    /// are rendered; each frame reads a snapshot of the VSL powers. Interactive, not
    /// reproducible frame by frame.
    #[default]
    Streaming,
    /// A fixed number of photons between frames ([`PhotonStreamSettings::photons_per_frame`]
    /// or [`Budget::photons`](illume_transport::Budget)), shot inside
    /// `Technique::advance`: the same settings give the same frames bit for bit.
    Deterministic,
}

/// The streaming thread's share of the CPU when frames are rendered on the same cores.
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
pub enum StreamPriority {
    /// The thread competes with the renderer's threads as an equal (on 2 cores with 2
    /// render threads it takes about a third of the machine while a frame renders, all
    /// of it in between): the highest photon rate, the lowest latency, slower frames.
    Normal,
    /// The thread runs at the lowest OS priority (nice 19 on Linux): frames take the
    /// cores first and photons fill the time the renderer leaves — as in the paper,
    /// where the GPU renders and the CPU streams: faster frames, a lower photon rate and
    /// so a longer latency than `normal` (measured in `BENCHMARKS.md`, photon_stream).
    /// `stream_share` limits what it takes from frames rendered back to back.
    #[default]
    Low,
}

/// What a scene change does to the photon pool (§0.5 and §0.9.1).
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
pub enum ChangePolicy {
    /// The paper's default: new photons see the new scene at once and old photons age
    /// out of the FIFO pool (latency = pool size / impact rate).
    #[default]
    AgeOut,
    /// The paper's alternative (§0.9.1): empty the whole pool on any change. No stale
    /// light, but the image is dark/noisy until the pool refills.
    Flush,
}

/// Whether VSL shading traces shadow rays (beyond the paper, which has none: §0.6,
/// Figure 7's over-illumination).
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
pub enum VisibilityMode {
    /// The paper: no VSL shadows. Fast; over-illuminates points that a VSL cannot see.
    #[default]
    Off,
    /// One shadow ray from every pixel to every VSL that lights it. Removes the
    /// over-illumination; costs pixels × VSLs rays per frame.
    All,
    /// [`PhotonStreamSettings::visibility_rays`] shadow rays per pixel to VSLs chosen
    /// with probability proportional to their unshadowed contribution (an unbiased
    /// estimate of the shadowed sum, with per-pixel noise).
    Stochastic,
}

/// How a VSL's light falls off near it (the shading denominator, §0.6).
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
pub enum VslFalloff {
    /// Beyond the paper: ρ/π · Φ_s·cosθ_i·cosθ'/(π r² + A_s), the on-axis form factor of
    /// a uniformly emitting disk of the VSL's area A_s: irradiance at most Φ_s/A_s next to
    /// the VSL, so no bright spot where a VSL sits close to a lit surface.
    #[default]
    Disk,
    /// The paper's estimator (§0.4.1): ρ/π · Φ_s·cosθ_i·cosθ'/(π r²), a point light,
    /// unbounded as r → 0 (the light spots the paper avoids by keeping VSLs off triangle
    /// edges, Figure 4a).
    InverseSquare,
}

/// Which VSL a photon impact (and a point of the surface, for the VSL's area) belongs to.
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
pub enum VslCells {
    /// Beyond the paper: the nearest VSL of the object whose triangle has the same
    /// orientation class (dominant axis and sign of the normal), so a cell does not
    /// straddle a floor and a wall (the `placement` module doc has the measured reason).
    #[default]
    Oriented,
    /// The paper (§0.5, Algorithm 2): the closest VSL of the object hit (VSLs are
    /// attached to objects, §0.4.2).
    Nearest,
}

/// Photon streaming settings. Defaults follow the paper where it gives a value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, illume_settings_derive::Settings)]
#[serde(deny_unknown_fields, default)]
pub struct PhotonStreamSettings {
    /// N_v, the number of virtual surface lights (§0.4.2, a user parameter). Higher:
    /// smoother, more detailed indirect light, at a shading cost linear in the count
    /// (pixels × VSLs). Never fewer than one per object. Default 100 (Tables 2–3 use
    /// 10–200).
    #[setting(default = 100, range = "1–1 000 000", max = MAX_VSLS)]
    pub vsl_count: u32,
    /// Extra candidates placed before Algorithm 1 removes the closest ones, as a
    /// fraction of `vsl_count` (§0.4.2: "an increase of 10 % provides interesting
    /// results"). Higher: more even spacing, at a placement cost growing with the
    /// candidates.
    #[setting(default = 0.10, range = "[0, 10]")]
    pub oversampling: f32,
    /// Scale applied to each triangle about its centroid before a VSL is placed on it
    /// (§0.4.2, Figure 4a), in (0, 1]. Lower: VSLs further from edges and corners (fewer
    /// light spots), at the cost of leaving triangle borders uncovered.
    #[setting(default = 0.8, range = "(0, 1]")]
    pub triangle_scale: f32,
    /// Beyond the paper (issue 34 goal 4): indirect light leaves a glossy receiver by
    /// the BRDF's directional albedo towards the camera, A(wo)/π · E, exact when the
    /// light arrives uniformly over the hemisphere (`illume_transport::directional_albedo`).
    /// Off: ρ/π · E on every surface, the paper's display, too bright on rough metals (a
    /// white metal of roughness 0.6 reflects ≈ 0.82 of uniform light, not 1) and blind to
    /// a dielectric's specular layer. Lambertian surfaces show the same bits either way;
    /// the cost is a table lookup per glossy pixel. Default true.
    #[setting(default = true)]
    pub directional_albedo: bool,
    /// The shading denominator: `disk` (π r² + A_s, bounded next to a VSL; beyond the
    /// paper) or `inverse_square` (the paper's π r²).
    #[setting(default = VslFalloff::Disk)]
    pub falloff: VslFalloff,
    /// Which VSL an impact feeds: `oriented` (the nearest of the impact's orientation
    /// class; beyond the paper) or `nearest` (the paper's nearest VSL of the object).
    #[setting(default = VslCells::Oriented)]
    pub cells: VslCells,
    /// Photon impacts the FIFO pool holds (§0.3, §0.5). Higher: less noise in VSL powers,
    /// at the cost of latency after a change (latency = pool size / impact rate) and
    /// 32 bytes per impact.
    #[setting(default = 100_000, range = "1–100 000 000", max = MAX_POOL_IMPACTS)]
    pub pool_size: u32,
    /// Streaming ([`StreamMode::Streaming`]: a thread shoots photons while frames render)
    /// or reproducible shooting ([`StreamMode::Deterministic`]: a fixed number between
    /// frames).
    #[setting(default = StreamMode::Streaming)]
    pub mode: StreamMode,
    /// OS priority of the streaming thread: `low` (default: frames first, photons in the
    /// time left) or `normal` (more photons, lower latency, slower frames; `BENCHMARKS.md`
    /// has the trade-off). Where the OS refuses, the thread keeps normal priority and
    /// says so once on stderr.
    #[setting(default = StreamPriority::Low)]
    pub stream_priority: StreamPriority,
    /// With `stream_priority = "low"`: the share of a core the streaming thread keeps
    /// while render threads want both cores, in [0, 1] (a fraction of one core); 1 sets
    /// no limit (the thread takes what nice 19 gives it, ≈ 45 % of a core beside frames
    /// rendered back to back). Below 1, above its share the thread hands its core back
    /// within microseconds; on an idle machine (paced frames, a paused view) it takes
    /// what is free whatever the share. Lower: faster frames, fewer photons while frames
    /// render and so a longer latency and more error in motion (Cornell box at 800×600,
    /// moving camera: 29–31 fps and 2.6–3.0 M impacts/s at 1, 35–36 fps and 2.2 M at
    /// 0.25, 52–53 fps and 0.1–0.3 M at 0). Default 1: the frame rate is not bought with
    /// the light's latency (`BENCHMARKS.md`, photon_stream, has the sweep).
    #[setting(default = 1.0, range = "[0, 1]")]
    pub stream_share: f32,
    /// Streaming mode: let the streaming thread rest once the pool has turned over since
    /// the last change that affects lighting (every pooled photon traced in the current
    /// world, the pool full), until the next such change wakes it. More photons would only
    /// swap the pool's photons for equally distributed ones — the VSL powers' variance is
    /// set by `pool_size`, not by how long the thread runs — so resting loses no accuracy;
    /// it stops the indirect light's frame-to-frame flicker in a still world and gives the
    /// frames both cores while only the camera moves (the paper notes that streaming may
    /// pause then, §0.9.1). False: stream without end, as the paper does (for measuring
    /// photon rates).
    #[setting(default = true)]
    pub rest_when_settled: bool,
    /// Streaming mode: the most frames a change that affects lighting takes to reach the
    /// whole pool when the streaming thread falls behind (beyond the paper, issue 33 goal
    /// 5). Before each frame, while photons from before the last change remain pooled,
    /// the frame loop checks the impacts that entered the pool since the previous frame;
    /// below `pool_size / turnover_frames` it traces the rest itself, on every core. The
    /// thread at low priority beside frames rendered back to back can fall to a few tens
    /// of thousands of impacts a second (latency 2.3 s in `illume demo`, issue 33), and
    /// when it then gets the cores, the indirect light jumps. Lower: lower latency and
    /// smoother changes, at up to `pool_size / turnover_frames` impacts of tracing per
    /// frame (≈ 1–3 ms at the default pool on 2 cores); it costs nothing while the thread
    /// keeps up. 0: off (the paper: latency = pool size / the thread's rate). Default 15:
    /// 0.5 s at 30 fps.
    #[setting(default = 15, unit = "frames")]
    pub turnover_frames: u32,
    /// Streaming mode: the most the displayed VSL powers change in one frame, as
    /// 1/`smooth_frames` of their total (relative L1 over every VSL side; beyond the
    /// paper, issue 33 goal 5). When the thread replaces much of the pool between two
    /// frames — it catches up in a burst after starving beside the frames — the powers
    /// shown move from the last frame's towards the pool's by that much a frame, so the
    /// indirect light ramps over frames instead of jumping (`illume demo`'s back wall: a
    /// mean 8-bit change of 11.6 in one frame against a median of 0.9). A frame whose
    /// pool changed less shows it as it is: small per-frame changes (a light moving a
    /// little, the pool's noise), a still world and deterministic mode are untouched.
    /// Lower: faster, jumpier; higher: smoother, later. 0: off (the paper shows the pool
    /// as it is). Default 15: a complete change of the lighting (relative L1 ≤ 2) over
    /// at most 30 frames, 1 s at 30 fps.
    #[setting(default = 15, unit = "frames")]
    pub smooth_frames: u32,
    /// Photons shot between two frames in [`StreamMode::Deterministic`] when the frame
    /// loop's budget does not say. Higher: faster convergence per frame, at a per-frame
    /// cost linear in the count.
    #[setting(default = 20_000, per_frame)]
    pub photons_per_frame: u64,
    /// Photons the streaming thread traces per batch (one pool update under the pool's
    /// mutex, about a millisecond of work). Higher: less locking overhead, at the cost
    /// of coarser pool updates; a batch ends early when the scene changes.
    #[setting(default = 256, range = "≥ 1")]
    pub batch_photons: u32,
    /// What a scene change does to the pool.
    #[setting(default = ChangePolicy::AgeOut)]
    pub on_change: ChangePolicy,
    /// ε of §0.7.3 [W/(m²·sr)]: a VSL is ignored where its unoccluded contribution bound
    /// Φ_s·R/(π r²) falls below ε, i.e. beyond r_ε = sqrt(Φ_s·R/(π ε)). Higher: more
    /// culling (faster), at the cost of cutting off faint light. Default 1e-6 (paper).
    #[setting(default = 1e-6, unit = "W/(m²·sr)", range = "[0, inf)")]
    pub epsilon: f32,
    /// Side of the square screen tiles VSLs are culled against \[pixels\]. Smaller:
    /// tighter culling, at a per-tile overhead.
    #[setting(default = 16, unit = "pixels", range = "≥ 1")]
    pub tile_size: u32,
    /// Shade one pixel in `shading_stride²` (a grid `shading_stride` pixels apart) and
    /// interpolate the pixels between from the shaded ones on the same surface (normals
    /// within ≈ 25°, points within `shading_stride` pixel footprints of the tangent
    /// plane); a pixel with no such neighbour is shaded exactly, and albedo (textures)
    /// is always applied per pixel. Indirect light is smooth, so 2 costs ≈ 1/4 of the VSL
    /// evaluations for a sub-percent change (`BENCHMARKS.md`); 1 shades every pixel
    /// (the paper's deferred shading). Higher strides blur small indirect features
    /// (contact shadows under the visibility mode, the bright spot next to a strong VSL).
    /// 1–8, default 2.
    #[setting(default = 2, range = "1–8")]
    pub shading_stride: u32,
    /// VSL shadow rays (beyond the paper).
    #[setting(default = VisibilityMode::Off)]
    pub visibility: VisibilityMode,
    /// Shadow rays per pixel in [`VisibilityMode::Stochastic`]. Higher: less noise, at a
    /// cost linear in the count.
    #[setting(default = 8)]
    pub visibility_rays: u32,
    /// Gather rays per shaded pixel for the near field (beyond the paper; 0 = off, the
    /// paper's estimator). A VSL stands for its whole Voronoi cell at one point, which is
    /// wrong close to the cell: a wall point next to the floor sees the floor's cells at
    /// grazing angles and receives almost nothing from their centres, so every edge and
    /// corner of a room comes out dark (the Cornell box's indirect mean −12…−16 %,
    /// `BENCHMARKS.md`). With rays > 0, a VSL at distance r lights a point with weight
    /// w(r) (0 inside `near_field_scale`/2 cell sizes, 1 beyond `near_field_scale`,
    /// smooth between) and the rest, 1 − w, is gathered: cosine-distributed rays (a
    /// rank-1 lattice, shifted per pixel) find the surfaces around the point and read
    /// their exitance Φ_s/A_s from the hit's nearest VSL on the side facing the point.
    /// Higher: less gather noise, at one closest-hit ray each per shaded pixel (pixels
    /// between shaded ones are interpolated, `shading_stride`, so 576 rays at stride 3
    /// cost 64 a pixel). Default 0; the `quality` and `still` presets use 576.
    #[setting(default = 0, range = "≤ 4096")]
    pub near_field_rays: u32,
    /// Radius of the near field in cell sizes √A_s of the VSL involved (the VSL whose
    /// weight is taken, or the gather hit's nearest VSL), at least 0.5. Larger: the
    /// gathered share grows (less VSL discretisation error, no shadow rays for the VSLs
    /// inside it, more gather noise). `inf`: everything is gathered — a final gather
    /// over the VSL cells' exitance, in which the VSLs light nothing directly, need no
    /// visibility, and their count only sets the cells' size (the `quality` and `still`
    /// presets: 3200 cells).
    #[setting(default = 3.0, range = "≥ 0.5 (or inf)")]
    pub near_field_scale: f32,
    /// With everything gathered (`near_field_scale` = ∞; beyond the paper): a gather
    /// ray's hit takes the light that reached it straight from the lights and the sky
    /// by next-event estimation (a light sample and a shadow ray at the hit) instead of
    /// from its cell, and photons deposit only from their second impact on, so a
    /// cell's mean stands for light already scattered once. A cell averages its
    /// exitance over its whole area, across shadow boundaries and through walls; where
    /// the view sees the dark side of such cells (a gallery beside a sunlit court) the
    /// mean reads too bright: on Dabrovic Sponza under the noon sun (99 % of the frame
    /// indirect) the `still` preset's image mean against a 2048-spp reference goes from
    /// +6.7 % to +1.1 % with it (HDR-FLIP 0.171 → 0.144), `balanced` from +7.0 % to
    /// +2.8 % (`docs/benchmarks/photon_stream.md`). Costs a texture lookup, a light
    /// sample and a shadow ray per gather ray: 1.5–1.9× the frame of a gathering
    /// preset. Default false (no gather by default); the `balanced`, `quality` and
    /// `still` presets turn it on.
    #[setting(default = false)]
    pub gather_direct: bool,
    /// Longest photon path in bounces, a safety net behind Russian roulette (§0.7.1).
    #[setting(default = 32)]
    pub max_bounces: u32,
    /// Photons read base-colour textures through copies box-filtered to at most
    /// [`PHOTON_TEXTURE_SIDE`](illume_transport::hit_tables::PHOTON_TEXTURE_SIDE) (128)
    /// texels a side. A VSL sums photons over a surface element far larger than a
    /// filtered texel and the filter keeps every region's mean albedo, so VSL powers
    /// are unchanged in expectation (tested on Sponza); large textures stop costing a
    /// cache miss per impact (Sponza: 1.3× the impacts/s). False: full-resolution
    /// albedo for photons too. Rendering always uses full resolution.
    #[setting(default = true)]
    pub filtered_textures: bool,
    /// Fill the pool synchronously (on the calling thread and rayon) before the first
    /// frame, so the first frame is already converged (the paper renders at once and
    /// lets the stream fill in). False: frames start dark and brighten as the pool
    /// fills.
    #[setting(default = true)]
    pub warm_up: bool,
    /// Start with the simulation thread paused ([`StreamMode::Streaming`]).
    #[setting(default = false)]
    pub start_paused: bool,
    /// Seed of VSL placement and photon paths: the same seed gives the same VSLs and,
    /// in deterministic mode, the same frames.
    #[setting(default = 0)]
    pub seed: u64,
}

/// Most VSLs accepted (`vsl_count`): placement is O(n log n) in memory and shading
/// O(n) per pixel, so far more would not finish; a larger value is an error.
pub const MAX_VSLS: u32 = 1_000_000;

/// Most pooled impacts accepted (`pool_size`): 32 bytes each, 3.2 GB at this limit.
pub const MAX_POOL_IMPACTS: u32 = 100_000_000;

impl PhotonStreamSettings {
    /// Preset for tests and reproducible animations: deterministic shooting, the
    /// paper's other defaults.
    pub fn deterministic() -> Self {
        Self {
            mode: StreamMode::Deterministic,
            ..Self::default()
        }
    }

    /// The paper's estimator and pipeline, every deviation of this implementation
    /// switched off: VSLs as point lights (`falloff = inverse_square`), impacts to the
    /// nearest VSL (`cells = nearest`), every pixel shaded (`shading_stride = 1`), no
    /// near-field gather, no VSL shadows, the base colour on glossy receivers
    /// (`directional_albedo = false`), photons on full-resolution textures and a stream
    /// that never rests nor is topped up by the frame loop. 100 VSLs as Tables 2–3; the pool keeps the default's 100 000
    /// impacts, a size the paper does not give. The synchronous warm-up stays on: it
    /// changes no estimate, only fills the pool before the first frame (the state the
    /// paper's stream reaches a moment after it starts; without it a still is dark). The
    /// test
    /// `presets::the_paper_preset_switches_every_deviation_off` pins this list.
    pub fn paper() -> Self {
        Self {
            falloff: VslFalloff::InverseSquare,
            cells: VslCells::Nearest,
            shading_stride: 1,
            near_field_rays: 0,
            visibility: VisibilityMode::Off,
            filtered_textures: false,
            rest_when_settled: false,
            turnover_frames: 0,
            smooth_frames: 0,
            directional_albedo: false,
            ..Self::default()
        }
    }

    /// Preset for interactive previews: 50 VSLs, a smaller pool (lower latency).
    pub fn interactive() -> Self {
        Self {
            vsl_count: 50,
            pool_size: 50_000,
            ..Self::default()
        }
    }

    /// Preset for interactive frames closer to the reference than the paper's: all
    /// indirect light gathered over 1600 VSL cells fed by a 200 000-impact pool, 64 rays
    /// per shaded pixel one pixel in sixteen (stride 4, 4 rays a pixel), the first
    /// bounce taken at each hit ([`PhotonStreamSettings::gather_direct`]). Several times
    /// the default's frame time for a fraction of its error; some fixed-pattern gather
    /// noise (`BENCHMARKS.md`).
    pub fn balanced() -> Self {
        Self {
            vsl_count: 1600,
            pool_size: 200_000,
            near_field_rays: 64,
            near_field_scale: f32::INFINITY,
            shading_stride: 4,
            gather_direct: true,
            ..Self::default()
        }
    }

    /// Preset for stills and slow previews (streaming): the whole indirect light
    /// gathered over 3200 VSL cells fed by a 10⁶-impact pool
    /// ([`near_field_scale`](PhotonStreamSettings::near_field_scale) = ∞), 576 rays
    /// per shaded pixel one pixel in nine (stride 3), the first bounce taken at each hit
    /// ([`PhotonStreamSettings::gather_direct`]). No visibility noise, no dark edges;
    /// about 1–2 s per 320×240 frame on 2 cores (`BENCHMARKS.md`).
    pub fn quality() -> Self {
        Self {
            vsl_count: 3200,
            pool_size: 1_000_000,
            near_field_rays: 576,
            near_field_scale: f32::INFINITY,
            shading_stride: 3,
            gather_direct: true,
            ..Self::default()
        }
    }

    /// Preset for stills (`illume render`'s default for this technique): the quality
    /// preset shot deterministically — the same image on every run.
    pub fn still() -> Self {
        Self {
            mode: StreamMode::Deterministic,
            ..Self::quality()
        }
    }

    /// The first impact of a photon path that deposits into the pool: 1 with
    /// [`PhotonStreamSettings::gather_direct`] (the gather computes the first bounce
    /// itself), else 0.
    pub fn first_deposit(&self) -> u32 {
        u32::from(self.gather_direct)
    }

    /// The photon paths these settings ask for.
    pub fn photon_path(&self) -> illume_transport::photon::PhotonPathSettings {
        illume_transport::photon::PhotonPathSettings {
            max_bounces: self.max_bounces,
            filtered_textures: self.filtered_textures,
            ..Default::default()
        }
    }

    /// Checks every value against its declared range, then the checks across fields;
    /// the error names the field.
    pub fn validate(&self) -> Result<(), crate::PhotonStreamError> {
        let bad = |field: &'static str, reason: String| {
            Err(crate::PhotonStreamError::InvalidSetting { field, reason })
        };
        if let Err((field, reason)) = self.validate_ranges() {
            return bad(field, reason);
        }
        if self.gather_direct && !(self.near_field_rays > 0 && self.near_field_scale.is_infinite())
        {
            return bad(
                "gather_direct",
                "needs everything gathered (near_field_rays > 0 and near_field_scale = inf): \
                 the VSLs would lose the light of their first impacts"
                    .into(),
            );
        }
        if (self.pool_size as u64) < self.max_bounces as u64 + 1 {
            return bad(
                "pool_size",
                format!(
                    "{} cannot hold one photon path of max_bounces + 1 impacts",
                    self.pool_size
                ),
            );
        }
        if self.visibility == VisibilityMode::Stochastic && self.visibility_rays == 0 {
            return bad(
                "visibility_rays",
                "stochastic visibility needs at least 1 ray".into(),
            );
        }
        Ok(())
    }
}

impl TechniqueSettings for PhotonStreamSettings {
    const NAME: &'static str = crate::NAME;
    const WORK_UNIT: &'static str = "photons";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        &[
            (
                "default",
                "100 VSLs (Tables 2–3), a 100 000-impact pool (the paper gives none), streaming, with the improvements `paper` turns off",
            ),
            (
                "paper",
                "the paper's estimator: point-light VSLs, nearest-VSL cells, every pixel shaded, no gather, never resting",
            ),
            (
                "deterministic",
                "the defaults, shot between frames: reproducible frames",
            ),
            (
                "interactive",
                "50 VSLs, a 50 000-impact pool: lower latency",
            ),
            (
                "balanced",
                "all indirect light gathered over 1600 VSL cells, 4 rays a pixel, the first bounce at each hit: interactive, closer to the reference",
            ),
            (
                "quality",
                "all indirect light gathered over 3200 VSL cells (10⁶-impact pool), the first bounce at each hit, streaming",
            ),
            ("still", "quality, deterministic: `render`'s default"),
        ]
    }

    fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper()),
            "deterministic" => Some(Self::deterministic()),
            "interactive" => Some(Self::interactive()),
            "balanced" => Some(Self::balanced()),
            "quality" => Some(Self::quality()),
            "still" => Some(Self::still()),
            _ => None,
        }
    }

    /// Real time: the simulation thread streams ([`StreamMode::Streaming`]). A fixed
    /// amount of work: [`StreamMode::Deterministic`], `work_per_frame` photons between
    /// frames (default [`PhotonStreamSettings::photons_per_frame`]).
    fn pace(&mut self, pacing: Pacing) {
        match pacing {
            Pacing::RealTime => self.mode = StreamMode::Streaming,
            Pacing::FixedWork { work_per_frame } => {
                self.mode = StreamMode::Deterministic;
                if let Some(n) = work_per_frame {
                    self.photons_per_frame = n;
                }
            }
        }
    }

    /// Deterministic mode: `photons_per_frame` photons; streaming: no budget (the thread
    /// runs by itself).
    fn default_budget(&self) -> Budget {
        Budget {
            work: (self.mode == StreamMode::Deterministic).then_some(self.photons_per_frame),
            time_ms: None,
        }
    }

    fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
    }
}
