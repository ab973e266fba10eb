//! [`Selective`]: the photon pool's groups, their epochs and priorities, the mesh
//! element accumulators, and the [`Technique`] implementation the renderer drives.

use crate::elements::Elements;
use crate::groups::{GroupLayout, Priority};
use crate::masking::{DEFAULT_PIXELS_HIGH, MaskingView, TextureMasking};
use crate::qmc::GroupFactors;
use crate::retrace::{Snapshot, TraceContext, TraceOutput, UnionWorld};
use crate::settings::{SelectiveMode, SelectiveSettings};
use crate::{SelectiveError, shade};
use illume_core::image::RgbImage;
use illume_core::sampling::{HaltonScramble, Pcg32};
use illume_core::{Counters, Progress};
use illume_scene::SceneChange;
use illume_transport::flux::Quanta;
use illume_transport::{Budget, ChangeResponse, GBuffer, SharedWorld, Technique, World};
use std::sync::Arc;
use std::time::Instant;

/// One photon group's state.
#[derive(Clone, Debug)]
pub(crate) struct Group {
    /// The scene state its photons were last traced in.
    pub(crate) epoch: Arc<Snapshot>,
    /// Its update priority.
    pub(crate) priority: Priority,
}

/// Progress counters.
#[derive(Clone, Copy, Debug, Default)]
pub struct SelectiveCounters {
    /// Photons traced (fill and re-tracing) since construction.
    pub photons_traced: u64,
    /// Photons found invalid and re-traced with negative and positive energy.
    pub photons_invalid: u64,
    /// Rays traced.
    pub rays: u64,
    /// Groups re-traced.
    pub groups_retraced: u64,
    /// Restarts after light changes.
    pub restarts: u64,
    /// Rounds of N_p correctives per group added to the pool (`max_photons`).
    pub growth_rounds: u64,
    /// Emission maps built after the first ([`crate::emission`]: at restarts, when a
    /// directional light turned).
    pub emission_maps_built: u64,
    /// Seconds spent tracing.
    pub trace_s: f64,
}

/// The yield floor grows the pool to at most this many times the pool it would have
/// without it: a scene that stores almost nothing where its elements are (a sun on a
/// roof, 0.001 impacts a photon) would otherwise ask for a billion photons and a
/// warm-up of hours. Dabrovic Sponza under the sun needs 2.3×, Sibenik 1.4×.
pub const YIELD_GROWTH_MAX: u64 = 4;

/// N_p: `pilots_per_group`, raised until the pool N_g·N_p·R holds
/// `min_photons_per_element` photons per element and, at `impacts_per_photon` stored
/// per photon traced (0: unknown), `min_impacts_per_element` impacts per element — the
/// latter within [`YIELD_GROWTH_MAX`] times the pool without it, all within
/// [`crate::settings::MAX_POOL`].
pub fn scaled_pilots(
    settings: &SelectiveSettings,
    groups: u64,
    elements: u64,
    impacts_per_photon: f64,
) -> u64 {
    let asked = settings.pilots_per_group as u64;
    let per_pilot = groups * settings.ratio as u64;
    let mut photons = settings.min_photons_per_element as u64 * elements;
    if impacts_per_photon > 0.0 && settings.min_impacts_per_element > 0 {
        let without = photons.max(asked * per_pilot);
        let by_yield =
            (settings.min_impacts_per_element as f64 * elements as f64 / impacts_per_photon).ceil();
        let bound = without.saturating_mul(YIELD_GROWTH_MAX) as f64;
        photons = photons.max(by_yield.min(bound).min(crate::settings::MAX_POOL as f64) as u64);
    }
    let need = photons.div_ceil(per_pilot.max(1));
    let cap = crate::settings::MAX_POOL / per_pilot.max(1);
    asked.max(need.min(cap))
}

/// Selective photon tracing (technique name `selective`).
pub struct Selective {
    pub(crate) settings: SelectiveSettings,
    pub(crate) factors: GroupFactors,
    pub(crate) layout: GroupLayout,
    pub(crate) scramble: Arc<HaltonScramble>,
    pub(crate) elements: Arc<Elements>,
    pub(crate) accumulators: Vec<[Quanta; 2]>,
    /// Impacts per element side (added minus taken back): the display's noise estimate.
    pub(crate) counts: Vec<[i64; 2]>,
    /// The irradiance the last frame showed per display vertex (the temporal filter's
    /// state, [`crate::temporal`]).
    pub(crate) shown: Option<Vec<[illume_core::Rgb; 2]>>,
    pub(crate) quantum_w: f64,
    pub(crate) current: Arc<Snapshot>,
    pub(crate) next_snapshot: u64,
    pub(crate) groups: Vec<Group>,
    pub(crate) stale: u64,
    pub(crate) filled: u64,
    pub(crate) union: Option<UnionWorld>,
    pub(crate) cursor: u64,
    pub(crate) rng: Pcg32,
    pub(crate) pilots_since_camera: u64,
    pub(crate) aspect: f32,
    pub(crate) pixels_high: u32,
    pub(crate) masking: Arc<TextureMasking>,
    pub(crate) warmed_up: bool,
    pub(crate) counters: SelectiveCounters,
    pub(crate) last_shade_ms: f64,
    /// Impacts stored per photon measured at the start (`min_impacts_per_element`; 0
    /// when not measured).
    pub(crate) start_yield: f64,
}

impl Selective {
    /// Lays out the mesh elements and the groups for `world`'s scene (nothing traced
    /// yet: see [`Selective::fill`] and `warm_up`).
    pub fn new(world: &SharedWorld, settings: SelectiveSettings) -> Result<Self, SelectiveError> {
        let w = world.read().map_err(|_| SelectiveError::PoisonedWorld)?;
        Self::for_world(&w, settings)
    }

    /// [`Selective::new`] for an unshared world.
    pub fn for_world(world: &World, settings: SelectiveSettings) -> Result<Self, SelectiveError> {
        settings.validate()?;
        let mut elements = Elements::with_max_side(
            &world.scene,
            settings.element_count,
            settings.smoothing_angle_deg,
            settings.element_max_side,
        );
        elements.set_gather(crate::elements::Gather {
            impacts: settings.gather_impacts,
            max_rings: settings.gather_rings,
        });
        if elements.is_empty() {
            return Err(SelectiveError::NoSurfaces {
                scene: world.scene.source.clone(),
            });
        }
        // Units of light first (an emissive object is one), for the default N_g.
        let probe = crate::qmc::LightCells::new(&world.lights, 0);
        let live_units = probe.units().iter().filter(|u| u.power > 0.0).count();
        let factors = if settings.group_factors.is_empty() {
            GroupFactors::paper_default(live_units)
        } else {
            GroupFactors::new(&settings.group_factors)
        };
        let scramble = HaltonScramble::new(settings.seed);
        let maps = if settings.emission_map {
            crate::emission::build_maps(world, &settings.photon_path(), &scramble)
        } else {
            Default::default()
        };
        let current = Arc::new(Snapshot::with_maps(world, 0, factors.exponent(2), maps));
        let impacts_per_photon = if settings.min_impacts_per_element > 0 {
            crate::fill::impacts_per_photon(
                world,
                &current.cells,
                &settings.photon_path(),
                &scramble,
            )
        } else {
            0.0
        };
        let layout = GroupLayout {
            groups: factors.groups(),
            pilots: scaled_pilots(
                &settings,
                factors.groups(),
                elements.len() as u64,
                impacts_per_photon,
            ),
            ratio: settings.ratio as u64,
        };
        // 2^24 quanta per photon of the scene's whole power (as photon_stream's pool).
        let power = world.lights.total_power().max_element() as f64
            + world.lights.sky_power().max_element() as f64;
        let quantum_w = if power > 0.0 {
            power / (1u64 << 24) as f64
        } else {
            1e-12
        };
        let masking = if settings.texture_masking {
            TextureMasking::new(&world.scene, &elements, settings.masking_contrast_threshold)
        } else {
            TextureMasking::disabled()
        };
        let groups = (0..layout.groups)
            .map(|_| Group {
                epoch: Arc::clone(&current),
                priority: Priority::default(),
            })
            .collect();
        Ok(Self {
            accumulators: vec![[Quanta::ZERO; 2]; elements.len()],
            counts: vec![[0; 2]; elements.len()],
            shown: None,
            scramble: Arc::new(scramble),
            rng: Pcg32::new(settings.seed, 0x5e1ec7),
            settings,
            factors,
            layout,
            elements: Arc::new(elements),
            quantum_w,
            current,
            next_snapshot: 1,
            groups,
            stale: 0,
            filled: 0,
            union: None,
            cursor: 0,
            pilots_since_camera: 0,
            aspect: 4.0 / 3.0,
            pixels_high: DEFAULT_PIXELS_HIGH,
            masking: Arc::new(masking),
            warmed_up: false,
            counters: SelectiveCounters::default(),
            last_shade_ms: 0.0,
            start_yield: impacts_per_photon,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &SelectiveSettings {
        &self.settings
    }

    /// N_g and its factors.
    pub fn factors(&self) -> &GroupFactors {
        &self.factors
    }

    /// The pool's index layout.
    pub fn layout(&self) -> GroupLayout {
        self.layout
    }

    /// The mesh elements.
    pub fn elements(&self) -> &Elements {
        &self.elements
    }

    /// The mesh elements, shared (they never change after construction): the streaming
    /// technique shades with them outside the solution's lock.
    pub fn shared_elements(&self) -> Arc<Elements> {
        Arc::clone(&self.elements)
    }

    /// Front and back accumulators per element, in quanta of [`Selective::quantum_w`].
    pub fn accumulators(&self) -> &[[Quanta; 2]] {
        &self.accumulators
    }

    /// Impacts per element side (front, back), those taken back subtracted: a from-scratch
    /// trace of the same photons leaves the same counts.
    pub fn counts(&self) -> &[[i64; 2]] {
        &self.counts
    }

    /// Watts per quantum.
    pub fn quantum_w(&self) -> f64 {
        self.quantum_w
    }

    /// Photons traced in index order so far (the pool size once filled): the display's
    /// normalisation N.
    pub fn filled(&self) -> u64 {
        self.filled
    }

    /// True while [`Selective::step`] would do something: a stale group, the pool not
    /// yet filled, or room to grow it within `max_photons`.
    pub fn has_work(&self) -> bool {
        self.stale > 0 || self.filled < self.layout.pool() || self.can_grow()
    }

    /// Groups shot in an older scene state than the current one.
    pub fn stale_groups(&self) -> u64 {
        self.stale
    }

    /// True when group `g` was last shot in an older scene state than the current one.
    pub fn is_stale(&self, g: u64) -> bool {
        self.groups[g as usize].epoch.id != self.current.id
    }

    /// The priority of group `g`.
    pub fn priority(&self, g: u64) -> Priority {
        self.groups[g as usize].priority
    }

    /// Progress counters.
    pub fn counters(&self) -> SelectiveCounters {
        self.counters
    }

    pub(crate) fn context<'a>(&'a self, frustum: &'a crate::retrace::Frustum) -> TraceContext<'a> {
        TraceContext {
            elements: &self.elements,
            layout: self.layout,
            scramble: &self.scramble,
            path: self.settings.photon_path(),
            inv_quantum: 1.0 / self.quantum_w,
            frustum,
            masking: &self.masking,
            view: MaskingView::of(frustum, self.pixels_high),
        }
    }

    pub(crate) fn apply(&mut self, out: &TraceOutput) {
        for &(e, side, sign, q) in &out.deposits {
            self.accumulators[e as usize][side as usize] += q;
            self.counts[e as usize][side as usize] += sign as i64;
        }
        self.counters.photons_traced += out.photons;
        self.counters.photons_invalid += out.invalid;
        self.counters.rays += out.rays;
    }

    /// The frames' size: their width over height for the view frustum pilots test
    /// (§5.3's V), their height for the MIP level texture masking reads (§5.3's T_e).
    pub fn set_aspect(&mut self, width: u32, height: u32) {
        if height > 0 && width > 0 {
            self.aspect = width as f32 / height as f32;
            self.pixels_high = height;
        }
    }

    /// Irradiance display for `world`'s transforms (with the density estimate over
    /// neighbouring elements when `gather_impacts` is on).
    pub fn display(&self, world: &World) -> crate::elements::Display {
        self.elements.display_with_noise(
            &world.scene,
            &self.accumulators,
            &self.counts,
            self.quantum_w,
            self.filled,
        )
    }
}

impl Technique for Selective {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), illume_transport::TechniqueError> {
        self.warm_up(world, progress);
        Ok(())
    }

    /// See [`crate::update`].
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        self.on_changes(world, changes)
    }

    /// First call with `warm_up` and no precompute: fills the pool. Then re-traces stale
    /// groups (most important first) and continues an index-order fill, within the
    /// budget: `work` photons ([`SelectiveMode::Deterministic`]) or `time_ms`
    /// ([`SelectiveMode::Timed`], and [`SelectiveMode::Streaming`] when no thread runs
    /// this solution, as for [`Selective::for_world`]); whole groups, so one group may
    /// overrun.
    fn advance(&mut self, world: &World, budget: &Budget) {
        self.warm_up(world, &mut illume_core::progress::Silent);
        let t0 = Instant::now();
        let (work, time_ms) = match self.settings.mode {
            SelectiveMode::Deterministic => (
                Some(budget.work.unwrap_or(self.settings.photons_per_frame)),
                budget.time_ms,
            ),
            SelectiveMode::Timed | SelectiveMode::Streaming => (
                budget.work,
                Some(budget.time_ms.unwrap_or(self.settings.frame_budget_ms)),
            ),
        };
        let mut done = 0u64;
        loop {
            if work.is_some_and(|w| done >= w)
                || time_ms.is_some_and(|t| t0.elapsed().as_secs_f64() * 1e3 >= t)
            {
                break;
            }
            match self.step(world) {
                Some(n) => done += n.max(1),
                None => break,
            }
        }
    }

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let t0 = Instant::now();
        self.set_aspect(gbuffer.width, gbuffer.height);
        let display = self.frame_display(world);
        let img = shade::shade(
            world,
            gbuffer,
            &self.elements,
            &display,
            self.settings.directional_albedo,
        );
        self.last_shade_ms = t0.elapsed().as_secs_f64() * 1e3;
        img
    }

    fn stats(&self) -> Counters {
        let c = &self.counters;
        let mut out = Counters::new();
        for (name, x) in [
            ("groups", self.layout.groups as f64),
            ("pool_photons", self.layout.pool() as f64),
            ("impacts_per_photon_at_start", self.start_yield),
            ("elements", self.elements.len() as f64),
            (
                "filled_fraction",
                self.filled as f64 / self.layout.pool() as f64,
            ),
            ("stale_groups", self.stale as f64),
            ("photons_traced", c.photons_traced as f64),
            ("photons_invalid", c.photons_invalid as f64),
            ("groups_retraced", c.groups_retraced as f64),
            ("restarts", c.restarts as f64),
            ("growth_rounds", c.growth_rounds as f64),
            ("emission_maps_built", c.emission_maps_built as f64),
            (
                "photons_per_s",
                if c.trace_s > 0.0 {
                    c.photons_traced as f64 / c.trace_s
                } else {
                    0.0
                },
            ),
            (
                "rays_per_s",
                if c.trace_s > 0.0 {
                    c.rays as f64 / c.trace_s
                } else {
                    0.0
                },
            ),
            ("shading_ms", self.last_shade_ms),
        ] {
            out.set(name, x);
        }
        out
    }

    fn reset(&mut self) {
        self.restart();
        self.counters.restarts -= 1;
        self.warmed_up = false;
    }

    /// Direct light with shadows is the renderer's (the paper's hardware pass, §6.1).
    fn interactive(&self) -> bool {
        true
    }
}
