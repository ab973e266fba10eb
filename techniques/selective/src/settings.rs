//! Settings of selective photon tracing (`[selective]` table), written as a tuning guide.
//!
//! Defaults are the paper's values where it gives one (§5.1, §7).

use illume_transport::{Budget, Pacing, TechniqueSettings};
use serde::{Deserialize, Serialize};

/// The order in which stale photon groups are re-traced.
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
pub enum GroupOrder {
    /// §5.3: the stale group with the highest V·P (pilot hits on changed objects, times
    /// pilot hits in the view frustum) first; ties in index order after the last group.
    #[default]
    Priority,
    /// Stale groups in a random order (the baseline of the paper's Figures 5 and 7).
    Random,
    /// Stale groups in index order.
    Index,
}

/// How the simulation is paced.
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
pub enum SelectiveMode {
    /// The paper's parallel thread (§6: "both parts run in parallel"): one long-lived
    /// thread re-traces stale groups, most important first, then continues the
    /// index-order fill, while frames are rendered from whatever state the solution is in
    /// (partly updated). Frames never wait for more than one group. The frame loop's
    /// budget is ignored. Not reproducible frame for frame.
    #[default]
    Streaming,
    /// Groups re-traced between frames within a wall-clock budget per frame
    /// ([`SelectiveSettings::frame_budget_ms`] or the frame loop's `Budget::time_ms`), on
    /// the frame thread and rayon: progressive refinement without a second thread.
    Timed,
    /// Groups re-traced between frames until [`SelectiveSettings::photons_per_frame`]
    /// photons (or the frame loop's `Budget::work`) were traced: the same settings give
    /// the same frames bit for bit.
    Deterministic,
}

/// Selective photon tracing settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, illume_settings_derive::Settings)]
#[serde(deny_unknown_fields, default)]
pub struct SelectiveSettings {
    /// N_g as `[base, exponent]` pairs, N_g = Π base^exponent (§4.2 Eq. 5): corrective
    /// photons of one group agree to within base^−exponent in the Halton dimension of
    /// that base (Eq. 3). Bases are the primes of the dimensions photons read, in order:
    /// 2 light choice (remapped into the first emission coordinate), 3 the second
    /// emission coordinate, 5 and 7 the first bounce's roulette-and-direction, … (§4.1).
    /// Higher exponents: more, smaller, more coherent groups (a change is found in fewer
    /// photons), at the cost of more groups to cycle through after a change (N_g groups
    /// until every photon is current). Empty (default): 2^(3+⌈log₂ L⌉)·3² for L lights,
    /// an emissive object counting as one (§7: 4 lights → 288, 2 → 144). `[[2, 5], [3,
    /// 2], [5, 1], [7, 1]]` (10 080) also keeps the first bounce coherent (Fig. 5).
    #[setting(default = Vec::new())]
    pub group_factors: Vec<[u32; 2]>,
    /// N_p, pilot photons per group (§5.1). Pilots sample the whole photon space and
    /// find the groups a change concerns; higher: a more reliable priority, at the cost
    /// of photons shot in no particular order. ≥ 2, default 250 (§7, ROOM).
    #[setting(default = 250, range = "≥ 2")]
    pub pilots_per_group: u32,
    /// R, photons per group over pilots per group (§5.1): pool size N = N_g·N_p·R,
    /// 1/R of it pilots. The paper finds 16 (6.25 % pilots) near optimal and 32 not
    /// robust (Fig. 7). ≥ 2, default 16.
    #[setting(default = 16, range = "≥ 2")]
    pub ratio: u32,
    /// Mesh elements to bucket photons in, about (§1, §3): each triangle is split into
    /// a k×k barycentric grid of equal sub-triangles, k chosen by its area, at least one
    /// element per triangle. Higher: sharper indirect light, at the cost of more noise
    /// per element (photons are shared among more buckets) and memory (48 B per
    /// element side pair). Default 12 400 (§7, ROOM).
    #[setting(default = 12_400, range = "1–50 000 000", max = MAX_ELEMENTS)]
    pub element_count: u32,
    /// Largest element side as a fraction of the scene's bounding-box diagonal (beyond
    /// the paper, issue 34): a triangle is split until its elements are no larger than this, whatever
    /// element_count says, so the large triangles of a model are split even when
    /// element_count is small for its area. Grid sides are powers of two either way,
    /// which keeps the display free of T-junction seams. 0 (default) turns the bound
    /// off: elements from element_count alone, as before (tests and scenarios of other
    /// crates size their pools by it). 1/64 = 0.015625 splits 568 of Dabrovic Sponza's
    /// triangles instead of 409 (79 518 elements instead of 75 213).
    #[setting(default = 0.0, range = "[0, 1]")]
    pub element_max_side: f32,
    /// Fewest photons per element, on average: when the pool N_g·N_p·R holds fewer
    /// than this many per element, N_p is raised until it does (the pool scaled with
    /// the element mesh; beyond the paper, issue 34). Higher: less noise and boiling per element, at the
    /// cost of tracing time after a change. 0 turns it off: the pool is N_g·N_p·R as
    /// set. Default 16: Dabrovic Sponza's 75 213 elements get 1.2 M photons instead of
    /// the paper's pool's 3.8 per element, while the Cornell boxes keep the paper's pool
    /// (288 000 over `builtin:cornell-spot`'s 14 752 elements is 19.5; the paper's ROOM:
    /// 1 152 000 over 12 400 is 93).
    #[setting(default = 16, range = "0–100 000")]
    pub min_photons_per_element: u32,
    /// Fewest stored impacts per element, on average (beyond the paper, issue 34 goal
    /// 2): the pool also grows until `min_impacts_per_element` × elements ÷ the yield
    /// holds, the yield being the impacts stored per photon, measured at the start on
    /// [`crate::fill::YIELD_PROBE`] photons of the pool's own emission. A box stores
    /// about one impact per photon (`builtin:cornell-spot`: 0.91) and keeps its pool; an
    /// open model under the sun stores far fewer (Dabrovic Sponza at 13:00, with the
    /// emission map: 0.32; Sibenik's spot: 0.54), and `min_photons_per_element` alone
    /// would leave Sponza's elements with ≈ 5 impacts each.
    /// The growth is bounded at [`crate::state::YIELD_GROWTH_MAX`] (4) times the pool
    /// without it, so a scene that stores almost nothing does not ask for hours of
    /// tracing. Higher: less noise, at the cost of tracing time after a change (the pool
    /// is fixed at the start: a sun that rises later does not resize it). 0 turns it off.
    /// Default 12 (measured on Sponza: docs/benchmarks/selective.md, "Creases and the
    /// yield").
    #[setting(default = 12, range = "0–100 000")]
    pub min_impacts_per_element: u32,
    /// Beyond the paper (issue 34, goal 2): photon impacts a display vertex's irradiance
    /// should rest on. A vertex whose own elements hold fewer gathers flux and area from
    /// the rings of display vertices around it (on the same object, across edges within
    /// `smoothing_angle_deg`), one ring at a time up to `gather_rings`, until they hold
    /// this many, counted with the gather's weights ([`crate::elements`]): a density
    /// estimate over neighbouring elements whose support adapts to the photon density.
    /// It matters where elements hold few photons: a finely tessellated object whose
    /// triangles are each an element (a 2 304-triangle sphere in Dabrovic Sponza holds
    /// ≈ 0.5 photons per element), and dim regions. Higher: smoother indirect light, at
    /// the cost of blurring it over a wider area (up to `gather_rings` element rings)
    /// and of display time (one pass over the display vertices per ring). 0 turns it
    /// off: each vertex shows the mean of its own elements, the paper's Gouraud display.
    /// Default 256.
    #[setting(default = 256, range = "0–1 000 000 000")]
    pub gather_impacts: u32,
    /// Most rings of neighbouring display vertices `gather_impacts` gathers over
    /// (beyond the paper). Higher: enough impacts also where elements are tiny or dim,
    /// at the cost of a blur up to this many elements wide and a pass over the display
    /// vertices per ring in every frame's display. 0 turns the gather off. Default 6.
    #[setting(default = 6, range = "0–64")]
    pub gather_rings: u32,
    /// Beyond the paper: while groups are stale, each display vertex moves only this fraction of the way
    /// from what the last frame showed towards the solution when the change lies within
    /// `temporal_sigmas` of its impact noise ([`crate::temporal`], issue 34: re-traced
    /// photons move whole impacts between elements, and the static parts of an animated
    /// scene boiled). Lower: steadier static parts, at the cost of a lag of small real
    /// changes (≈ 1/alpha frames) while objects move; once nothing is stale frames show
    /// the solution exactly. In (0, 1]; 1 turns the filter off. Default 0.1 (with
    /// `temporal_sigmas` 16: under a light that keeps moving, frame-to-frame flicker at
    /// photon_stream's, 0.96–0.98e-3 against 0.99–1.02e-3 in
    /// `scenarios/selective_moving.toml`, where 0.2 and 2 gave 2.4e-3; the cost is the
    /// lag: back at its own image 0.38 s after the sphere's push in
    /// `scenarios/selective_sphere.toml` against 0.25 s, 0.48 s against 0.34 s in
    /// `selective_cube.toml`).
    #[setting(default = 0.1, range = "(0, 1]")]
    pub temporal_alpha: f32,
    /// Changes of a display vertex up to this many standard deviations of its impact
    /// noise count as noise for `temporal_alpha`; beyond, the vertex follows with gain
    /// 1 − (kσ/δ)². Higher: steadier, at the cost of lagging real changes of that size.
    /// The noise is Poisson's, whose tail a few impacts an element reach often (a vertex
    /// of one or two impacts jumps 3σ at no change at all), hence a wide band. ≥ 0,
    /// default 16.
    #[setting(default = 16.0, range = "[0, inf)")]
    pub temporal_sigmas: f32,
    /// Beyond the paper (issue 34 goal 4): indirect light leaves a glossy receiver by
    /// the BRDF's directional albedo towards the camera, A(wo)/π · E, exact when the
    /// light arrives uniformly over the hemisphere (`illume_transport::directional_albedo`).
    /// Off: ρ/π · E on every surface, the paper's display, too bright on rough metals (a
    /// white metal of roughness 0.6 reflects ≈ 0.82 of uniform light, not 1) and blind to
    /// a dielectric's specular layer. Lambertian surfaces show the same bits either way;
    /// the cost is a table lookup per glossy pixel. Default true.
    #[setting(default = true)]
    pub directional_albedo: bool,
    /// Element-grid vertices of one object within this angle of each other's face
    /// normal \[degrees\] are one display vertex (Gouraud smoothing across triangles,
    /// §6). Higher: smoother across creases, at the cost of light bleeding around
    /// corners. 0–180, default 40: below 45° so the faces of an octagonal column (45°
    /// apart, Dabrovic Sponza's pillars) stay apart — their irradiance differs up to 4×
    /// from face to face, and a welded vertex showed the face the camera sees at 0.6 of
    /// its own light (docs/benchmarks/selective.md, "Creases and the sun's map").
    #[setting(default = 40.0, unit = "degrees", range = "[0, 180]")]
    pub smoothing_angle_deg: f32,
    /// Order of re-tracing stale groups (§5.3).
    #[setting(default = GroupOrder::Priority)]
    pub order: GroupOrder,
    /// Pilot photons shot since the last camera move before the view-frustum factor V
    /// counts (§5.3, "sufficient for its robust estimate"); until then V = 1. Higher:
    /// a steadier V, at the cost of a longer time blind to the view.
    #[setting(default = 2000)]
    pub visibility_min_pilots: u32,
    /// Priority given to the view frustum (§5.3): a stale group's V is 1 + this ×
    /// (its pilot hits in the frustum) / (its pilots shot). 0 ignores the view.
    #[setting(default = 4.0, range = "[0, inf)")]
    pub visibility_weight: f32,
    /// Fraction of the scene's power carried by changed lights above which a light
    /// change restarts the solution (photons in index order, shown normalised by the
    /// photons traced) instead of re-tracing every photon of those lights with negative
    /// and positive energy, which costs twice a fresh trace (beyond the paper, which
    /// supports no light changes). In [0, 1]; 0 restarts on any light change, 1 never
    /// restarts. Default 0.5: moving the only light restarts.
    #[setting(default = 0.5, range = "[0, 1]")]
    pub restart_fraction: f32,
    /// Beyond the paper (issue 34 goal 2): a directional light's photons start where
    /// pilot photons found they are stored ([`crate::emission`]: 32² cells over the
    /// light's disk, 16 pilots each before the first photon; a cell's density ∝ the
    /// energy its pilots stored + 10 % of the mean; flux divided by the density, so the
    /// estimate stays unbiased; rebuilt only at a restart after the light turned by
    /// more than 2°). In an open model under the sun most of the disk lies over roofs
    /// whose photons are never stored. Cost: 16 384 pilot photons per directional light
    /// at construction and at such restarts; photons then bounce inside instead of
    /// leaving (about half the photons a second in Dabrovic Sponza); photons from cells
    /// that stored nothing are rarer and heavier. Off: the sun's photons start uniformly over its disk, as
    /// photon_stream's do. Default true.
    #[setting(default = true)]
    pub emission_map: bool,
    /// Pacing: a background thread, a wall-clock budget per frame, or photons per
    /// frame. Default [`SelectiveMode::Streaming`] (`animate --realtime` also picks it;
    /// `--work-per-frame` picks [`SelectiveMode::Deterministic`]).
    #[setting(default = SelectiveMode::Streaming)]
    pub mode: SelectiveMode,
    /// Threads of the streaming thread's own pool, on which it traces a group's photons
    /// in parallel ([`SelectiveMode::Streaming`]; issue 34, goal 6). 0: the process's
    /// global pool, which the renderer's frames keep busy, so a group's photons wait
    /// behind a frame's pixels. Higher: faster updates while frames render, at the cost
    /// of the frame rate while groups are stale. Default 1.
    #[setting(default = 1, range = "0–1 024")]
    pub stream_threads: u32,
    /// Wall-clock budget for re-tracing between two frames in [`SelectiveMode::Timed`]
    /// (and in [`SelectiveMode::Streaming`] when no thread runs the solution, e.g.
    /// [`Selective::for_world`](crate::Selective::for_world)) when the frame loop gives
    /// none \[ms\]. Higher: faster recovery after a change, at
    /// the cost of frame rate. Groups are atomic, so a frame may overrun by one group.
    #[setting(default = 25.0, unit = "ms", range = "(0, 3 600 000]", per_frame)]
    pub frame_budget_ms: f64,
    /// Photons traced between two frames in [`SelectiveMode::Deterministic`] when the
    /// frame loop's budget does not say (whole groups, so a frame may overrun by one
    /// group).
    #[setting(default = 100_000, range = "≥ 1", per_frame)]
    pub photons_per_frame: u64,
    /// Beyond the paper: while nothing is stale (a static scene), the pool grows by
    /// rounds of N_p correctives per group (R + 1 each round, so groups keep their
    /// shape) up to this many photons, and the image keeps converging; the display
    /// normalises by the photons traced. Higher: less element noise in still scenes, at
    /// the cost of a longer update after the next change (every group holds more
    /// photons to re-trace) and a slower restart. 0 (default) or at most N_g·N_p·R:
    /// the pool stays at N_g·N_p·R, as in the paper.
    #[setting(default = 0, range = "≤ 4 294 967 296", max = MAX_POOL)]
    pub max_photons: u64,
    /// Trace the whole pool before the first frame. False: frames start dark and
    /// brighten as photons are traced in index order (shown normalised by the photons
    /// traced).
    #[setting(default = true)]
    pub warm_up: bool,
    /// Longest photon path in bounces, a safety net behind Russian roulette.
    #[setting(default = 32)]
    pub max_bounces: u32,
    /// Photons read base-colour textures through box-filtered copies (see
    /// `photon_stream.filtered_textures`; beyond the paper): element buckets are far
    /// larger than a filtered texel.
    #[setting(default = true)]
    pub filtered_textures: bool,
    /// Visual masking of lighting patterns by textures (§5.3): a pilot hit on a textured
    /// surface raises its group's P by Δp/T_e instead of Δp = 1, T_e ≥ 1 the threshold
    /// elevation of the texture (frequencies finer than an element removed) at the MIP
    /// level the camera sees the hit at ([`crate::masking`]). True: changes on busy
    /// textures, where artefacts are harder to see, are re-traced after changes on plain
    /// surfaces, at the cost of a masking table per texture built at construction (a few
    /// passes over each base-colour texture's texels) and a table lookup per pilot hit.
    /// False: every pilot hit counts Δp = 1. Only the order of re-tracing depends on
    /// it, never the converged solution.
    #[setting(default = true)]
    pub texture_masking: bool,
    /// Luminance contrast of a lighting artefact just visible on an untextured surface
    /// (the inverse of contrast sensitivity), for `texture_masking` (§5.3): texture
    /// contrast is counted in multiples of it before Daly's masking function, so a
    /// texture whose contrast stays below it masks little (T_e < 1.2). Lower: a more sensitive
    /// observer against whom textures mask more, so changes on textured surfaces wait
    /// longer behind those on plain ones; higher: less masking. Unitless, in (0, 1];
    /// default 0.01 (1 %, about the Weber fraction of photopic vision).
    #[setting(default = 0.01, range = "(0, 1]")]
    pub masking_contrast_threshold: f32,
    /// Seed of the Halton digit scrambling (scrambling keeps Eq. 3).
    #[setting(default = 0)]
    pub seed: u64,
}

/// Largest N_g accepted (2²⁰): group bookkeeping is per group, and larger N_g leave
/// too few correctives per group to be worth a pilot pass.
pub const MAX_GROUPS: u64 = 1 << 20;

/// Largest pool accepted (N_g·N_p·R photons): 2³² photons take hours to trace once.
pub const MAX_POOL: u64 = 1 << 32;

/// Most mesh elements accepted (`element_count`): 48 B each plus the display grid.
pub const MAX_ELEMENTS: u32 = 50_000_000;

impl SelectiveSettings {
    /// Preset for tests and reproducible animations: photons per frame instead of a
    /// wall-clock budget.
    pub fn deterministic() -> Self {
        Self {
            mode: SelectiveMode::Deterministic,
            ..Self::default()
        }
    }

    /// The paper: the defaults' §7 values with every addition of this implementation
    /// off — no photon floor per element (the pool is N_g·N_p·R), no temporal filter of
    /// the display, no element-size bound, no pool growth in still scenes, photons on
    /// full-resolution textures, and light changes re-traced with negative and positive
    /// energy (the paper's mechanism) rather than restarted. The test
    /// `presets::the_paper_preset_switches_every_deviation_off` pins this list.
    pub fn paper() -> Self {
        Self {
            min_photons_per_element: 0,
            min_impacts_per_element: 0,
            gather_impacts: 0,
            temporal_alpha: 1.0,
            element_max_side: 0.0,
            max_photons: 0,
            filtered_textures: false,
            restart_fraction: 1.0,
            directional_albedo: false,
            emission_map: false,
            ..Self::default()
        }
    }

    /// Preset for stills: 4× the pool (R = 16, N_p = 1000) and 4× the elements,
    /// deterministic.
    pub fn quality() -> Self {
        Self {
            pilots_per_group: 1000,
            element_count: 50_000,
            mode: SelectiveMode::Deterministic,
            ..Self::default()
        }
    }

    /// Threads of the streaming thread's own pool (0: the global pool).
    pub fn stream_threads(&self) -> u32 {
        self.stream_threads
    }

    /// The photon paths these settings ask for (roulette remapped, §4.1).
    pub fn photon_path(&self) -> illume_transport::photon::PhotonPathSettings {
        illume_transport::photon::PhotonPathSettings {
            max_bounces: self.max_bounces,
            filtered_textures: self.filtered_textures,
            remap_roulette: true,
            ..Default::default()
        }
    }

    /// Checks every value; the error names the field.
    pub fn validate(&self) -> Result<(), crate::SelectiveError> {
        let bad = |field: &'static str, reason: String| {
            Err(crate::SelectiveError::InvalidSetting { field, reason })
        };
        if let Err((field, reason)) = self.validate_ranges() {
            return bad(field, reason);
        }
        let mut n_g: u64 = 1;
        for &[base, exponent] in &self.group_factors {
            let Some(dim) = illume_core::sampling::PRIMES
                .iter()
                .take(crate::qmc::MAPPED_DIMENSIONS)
                .position(|&p| p == base)
            else {
                return bad(
                    "group_factors",
                    format!(
                        "base {base} is not one of the mapped Halton bases {:?}",
                        &illume_core::sampling::PRIMES[..crate::qmc::MAPPED_DIMENSIONS]
                    ),
                );
            };
            let _ = dim;
            for _ in 0..exponent {
                n_g = n_g.saturating_mul(base as u64);
                if n_g > MAX_GROUPS {
                    return bad(
                        "group_factors",
                        format!("N_g exceeds 2^20 = {MAX_GROUPS} groups"),
                    );
                }
            }
        }
        let mut seen = std::collections::HashSet::new();
        if let Some(&[base, _]) = self.group_factors.iter().find(|f| !seen.insert(f[0])) {
            return bad("group_factors", format!("base {base} appears twice"));
        }
        let pool = n_g
            .saturating_mul(self.pilots_per_group as u64)
            .saturating_mul(self.ratio as u64);
        if pool > MAX_POOL {
            return bad(
                "pilots_per_group",
                format!("N_g·N_p·R = {pool} photons exceeds {MAX_POOL}"),
            );
        }
        Ok(())
    }
}

impl TechniqueSettings for SelectiveSettings {
    const NAME: &'static str = crate::NAME;
    const WORK_UNIT: &'static str = "photons";

    fn check(&self) -> Result<(), illume_transport::TechniqueError> {
        Ok(self.validate()?)
    }

    fn presets() -> &'static [(&'static str, &'static str)] {
        &[
            (
                "default",
                "the paper's values (N_p = 250, R = 16, 12 400 elements, re-tracing on a background thread) with the additions `paper` turns off",
            ),
            (
                "paper",
                "the paper: no photon floor per element, no temporal filter, no pool growth, light changes re-traced",
            ),
            (
                "deterministic",
                "the defaults, 100 000 photons per frame: reproducible frames",
            ),
            (
                "quality",
                "N_p = 1000 (4× the pool), 50 000 elements, deterministic",
            ),
            ("still", "quality: `render`'s default"),
        ]
    }

    fn preset(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::default()),
            "paper" => Some(Self::paper()),
            "deterministic" => Some(Self::deterministic()),
            "quality" | "still" => Some(Self::quality()),
            _ => None,
        }
    }

    /// Real time: [`SelectiveMode::Streaming`]. A fixed amount of work:
    /// [`SelectiveMode::Deterministic`], `work_per_frame` photons between frames.
    fn pace(&mut self, pacing: Pacing) {
        match pacing {
            Pacing::RealTime => self.mode = SelectiveMode::Streaming,
            Pacing::FixedWork { work_per_frame } => {
                self.mode = SelectiveMode::Deterministic;
                if let Some(n) = work_per_frame {
                    self.photons_per_frame = n;
                }
            }
        }
    }

    fn default_budget(&self) -> Budget {
        match self.mode {
            SelectiveMode::Timed | SelectiveMode::Streaming => Budget {
                work: None,
                time_ms: Some(self.frame_budget_ms),
            },
            SelectiveMode::Deterministic => Budget {
                work: Some(self.photons_per_frame),
                time_ms: None,
            },
        }
    }

    /// N_p at most 16, one photon per element at least and no yield floor: the pool (≈ 1.2 M photons on
    /// a real model, traced again by every fresh build) does not fall with the image
    /// size.
    fn miniature(&mut self) {
        self.pilots_per_group = self.pilots_per_group.min(16);
        self.min_photons_per_element = self.min_photons_per_element.min(1);
        self.min_impacts_per_element = 0;
    }

    fn set_seed(&mut self, seed: u64) {
        self.seed = seed;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_settings_name_their_key() {
        let cases: Vec<(SelectiveSettings, &str)> = vec![
            (
                SelectiveSettings {
                    pilots_per_group: 1,
                    ..Default::default()
                },
                "selective.pilots_per_group",
            ),
            (
                SelectiveSettings {
                    ratio: 1,
                    ..Default::default()
                },
                "selective.ratio",
            ),
            (
                SelectiveSettings {
                    group_factors: vec![[2, 21]],
                    ..Default::default()
                },
                "selective.group_factors: N_g exceeds 2^20",
            ),
            (
                SelectiveSettings {
                    group_factors: vec![[4, 1]],
                    ..Default::default()
                },
                "selective.group_factors: base 4",
            ),
            (
                SelectiveSettings {
                    group_factors: vec![[331, 1]],
                    ..Default::default()
                },
                "selective.group_factors: base 331",
            ),
            (
                SelectiveSettings {
                    element_count: 0,
                    ..Default::default()
                },
                "selective.element_count",
            ),
            (
                SelectiveSettings {
                    restart_fraction: 1.5,
                    ..Default::default()
                },
                "selective.restart_fraction",
            ),
            (
                SelectiveSettings {
                    restart_fraction: f32::NAN,
                    ..Default::default()
                },
                "selective.restart_fraction",
            ),
            (
                SelectiveSettings {
                    max_photons: u64::MAX,
                    ..Default::default()
                },
                "selective.max_photons",
            ),
            (
                SelectiveSettings {
                    frame_budget_ms: 0.0,
                    ..Default::default()
                },
                "selective.frame_budget_ms",
            ),
            (
                SelectiveSettings {
                    masking_contrast_threshold: 0.0,
                    ..Default::default()
                },
                "selective.masking_contrast_threshold",
            ),
            (
                SelectiveSettings {
                    masking_contrast_threshold: f32::NAN,
                    ..Default::default()
                },
                "selective.masking_contrast_threshold",
            ),
        ];
        for (s, want) in cases {
            let e = s.validate().expect_err(want).to_string();
            assert!(e.starts_with(want), "{e} should start with {want}");
        }
        SelectiveSettings::default().validate().unwrap();
        for (name, _) in SelectiveSettings::presets() {
            SelectiveSettings::preset(name).unwrap().validate().unwrap();
        }
    }
}
