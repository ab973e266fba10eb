//! [`Selective`]: the photon pool's groups, their epochs and priorities, the mesh
//! element accumulators, and the [`Technique`] implementation the renderer drives.

use crate::elements::Elements;
use crate::groups::{GroupLayout, Priority};
use crate::masking::{DEFAULT_PIXELS_HIGH, MaskingView, TextureMasking};
use crate::qmc::GroupFactors;
use crate::retrace::{Met, PilotHit, Snapshot, TraceContext, TraceOutput, UnionWorld};
use crate::settings::{GroupOrder, SelectiveMode, SelectiveSettings};
use crate::update::{Invalidation, changed_light_fraction, classify};
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
struct Group {
    /// The scene state its photons were last traced in.
    epoch: Arc<Snapshot>,
    /// Its update priority.
    priority: Priority,
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
    /// Seconds spent tracing.
    pub trace_s: f64,
}

/// Selective photon tracing (technique name `selective`).
pub struct Selective {
    settings: SelectiveSettings,
    factors: GroupFactors,
    layout: GroupLayout,
    scramble: HaltonScramble,
    elements: Arc<Elements>,
    accumulators: Vec<[Quanta; 2]>,
    quantum_w: f64,
    current: Arc<Snapshot>,
    next_snapshot: u64,
    groups: Vec<Group>,
    stale: u64,
    filled: u64,
    union: Option<UnionWorld>,
    cursor: u64,
    rng: Pcg32,
    pilots_since_camera: u64,
    aspect: f32,
    pixels_high: u32,
    masking: TextureMasking,
    warmed_up: bool,
    counters: SelectiveCounters,
    last_shade_ms: f64,
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
        let elements = Elements::new(
            &world.scene,
            settings.element_count,
            settings.smoothing_angle_deg,
        );
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
        let layout = GroupLayout {
            groups: factors.groups(),
            pilots: settings.pilots_per_group as u64,
            ratio: settings.ratio as u64,
        };
        let current = Arc::new(Snapshot::of(world, 0, factors.exponent(2)));
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
            scramble: HaltonScramble::new(settings.seed),
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
            masking,
            warmed_up: false,
            counters: SelectiveCounters::default(),
            last_shade_ms: 0.0,
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

    /// True when one more round of N_p correctives per group stays within `max_photons`.
    fn can_grow(&self) -> bool {
        self.layout.pool() + self.layout.groups * self.layout.pilots <= self.settings.max_photons
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

    fn context<'a>(&'a self, frustum: &'a crate::retrace::Frustum) -> TraceContext<'a> {
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

    fn apply(&mut self, out: &TraceOutput) {
        for &(e, side, q) in &out.deposits {
            self.accumulators[e as usize][side as usize] += q;
        }
        self.counters.photons_traced += out.photons;
        self.counters.photons_invalid += out.invalid;
        self.counters.rays += out.rays;
    }

    /// Traces the next `count` photons of the index-order fill in `world` (clamped to
    /// the pool), after bringing every stale group up to date: fill photons are traced
    /// in the current state, so the photons already traced must be current too (a group
    /// never holds photons of two epochs). Returns the photons traced.
    pub fn fill(&mut self, world: &World, count: u64) -> u64 {
        while let Some(g) = self.next_group() {
            self.retrace_group(world, g);
        }
        let end = (self.filled + count).min(self.layout.pool());
        if end <= self.filled {
            return 0;
        }
        let t0 = Instant::now();
        let indices: Vec<u64> = (self.filled..end).collect();
        let frustum = crate::retrace::Frustum::of(&world.scene, self.aspect);
        let out = self
            .context(&frustum)
            .trace_fresh(world, &self.current.cells, &indices);
        self.apply(&out);
        self.record_pilots(&out);
        self.filled = end;
        self.counters.trace_s += t0.elapsed().as_secs_f64();
        end - indices[0]
    }

    /// Fills the whole pool (index order), reporting progress.
    pub fn fill_all(&mut self, world: &World, progress: &mut dyn Progress) {
        let total = self.layout.pool();
        let chunk = self.layout.per_group().max(4096) * 4;
        progress.begin("selective: tracing the photon pool", total);
        while self.filled < total {
            self.fill(world, chunk);
            progress.set(self.filled);
        }
        progress.end();
    }

    fn record_pilots(&mut self, out: &TraceOutput) {
        for &(i, visible) in &out.pilots {
            let h = &mut self.groups[self.layout.raised_by_pilot(i) as usize].priority;
            h.pilots_seen += 1;
            h.pilots_visible += visible as u64;
            self.pilots_since_camera += 1;
        }
    }

    /// The next stale group by the settings' order.
    fn next_group(&mut self) -> Option<u64> {
        if self.stale == 0 {
            return None;
        }
        let n = self.layout.groups;
        let current = self.current.id;
        let is_stale = |g: &Group| g.epoch.id != current;
        match self.settings.order {
            GroupOrder::Priority => {
                let enough = self.pilots_since_camera >= self.settings.visibility_min_pilots as u64;
                let w = self.settings.visibility_weight as f64;
                let mut best: Option<(f64, u64)> = None;
                for k in 0..n {
                    let g = (self.cursor + k) % n;
                    let grp = &self.groups[g as usize];
                    if !is_stale(grp) {
                        continue;
                    }
                    let s = grp.priority.score(enough, w);
                    if best.is_none_or(|(b, _)| s > b) {
                        best = Some((s, g));
                    }
                }
                best.map(|(_, g)| g)
            }
            GroupOrder::Index => (0..n)
                .map(|k| (self.cursor + k) % n)
                .find(|&g| is_stale(&self.groups[g as usize])),
            GroupOrder::Random => {
                let start = self.rng.next_f64() * n as f64;
                (0..n)
                    .map(|k| (start as u64 + k) % n)
                    .find(|&g| is_stale(&self.groups[g as usize]))
            }
        }
    }

    /// Re-traces stale group `g` in `world` (current state). Returns the photons traced.
    pub fn retrace_group(&mut self, world: &World, g: u64) -> u64 {
        let t0 = Instant::now();
        let epoch = Arc::clone(&self.groups[g as usize].epoch);
        let current = Arc::clone(&self.current);
        let mut traced = 0;
        if epoch.id != current.id {
            let key = (epoch.id, current.id);
            if self.union.as_ref().is_none_or(|u| u.key != key) {
                self.union = Some(UnionWorld::new(world, &epoch, &current));
            }
            let union = self.union.take().expect("built above");
            if !union.changes.none() {
                let indices = self.layout.photons_of(g, self.filled);
                let frustum = crate::retrace::Frustum::of(&world.scene, self.aspect);
                let out = self
                    .context(&frustum)
                    .retrace(&union, &epoch, &current, &indices);
                self.apply(&out);
                self.record_pilots(&out);
                self.raise(&out, &epoch);
                traced = out.photons;
            }
            self.union = Some(union);
            self.groups[g as usize].epoch = current;
            self.stale -= 1;
            self.counters.groups_retraced += 1;
        }
        self.groups[g as usize].priority.p = 0.0;
        self.cursor = (g + 1) % self.layout.groups;
        self.counters.trace_s += t0.elapsed().as_secs_f64();
        traced
    }

    /// Raises P of the groups pilots point at (Eq. 6, §5.3).
    fn raise(&mut self, out: &TraceOutput, epoch: &Snapshot) {
        let current = &self.current;
        for &PilotHit {
            pilot: i,
            met,
            instance: inst,
            delta_p,
        } in &out.pilot_hits
        {
            let h = self.layout.raised_by_pilot(i) as usize;
            let held = &self.groups[h].epoch;
            if held.id == current.id {
                continue;
            }
            let raise = match met {
                Met::Light | Met::Material => true,
                Met::Moved => held.instance_differs(current, inst as usize),
                // A phantom counts only for groups that hold it: shot when the object
                // stood where this group's epoch had it.
                Met::Phantom => {
                    held.instance_differs(current, inst as usize)
                        && !held.instance_differs(epoch, inst as usize)
                }
            };
            if raise {
                self.groups[h].priority.p += delta_p as f64;
            }
        }
    }

    /// Restarts the solution: accumulators cleared, every group current and empty.
    fn restart(&mut self) {
        for a in &mut self.accumulators {
            *a = [Quanta::ZERO; 2];
        }
        for g in &mut self.groups {
            g.epoch = Arc::clone(&self.current);
            g.priority = Priority::default();
        }
        self.stale = 0;
        self.filled = 0;
        self.union = None;
        self.counters.restarts += 1;
    }

    /// One step of work: a stale group, else a fill chunk, else (with
    /// [`SelectiveSettings::max_photons`]) a fill chunk of a new round of N_p correctives
    /// per group. Returns photons traced, or None when everything is current and the pool
    /// is as large as it may grow.
    pub fn step(&mut self, world: &World) -> Option<u64> {
        if let Some(g) = self.next_group() {
            return Some(self.retrace_group(world, g));
        }
        if self.filled >= self.layout.pool() && !self.grow() {
            return None;
        }
        Some(self.fill(world, self.layout.per_group().max(4096)))
    }

    /// Grows the pool by one round of N_p correctives per group (R + 1: the indices
    /// N_g·N_p·R … N_g·N_p·(R + 1) − 1, N_p more per residue, so every group keeps its
    /// shape) if that stays within `max_photons`. Only called with every group current
    /// and the pool full: a static scene.
    fn grow(&mut self) -> bool {
        if !self.can_grow() {
            return false;
        }
        self.layout.ratio += 1;
        self.counters.growth_rounds += 1;
        true
    }

    /// Works until nothing is stale and the pool is full (grown to `max_photons` when
    /// that is set).
    pub fn converge(&mut self, world: &World) {
        while self.step(world).is_some() {}
    }

    /// The frames' size: their width over height for the view frustum pilots test
    /// (§5.3's V), their height for the MIP level texture masking reads (§5.3's T_e).
    pub fn set_aspect(&mut self, width: u32, height: u32) {
        if height > 0 && width > 0 {
            self.aspect = width as f32 / height as f32;
            self.pixels_high = height;
        }
    }

    /// With `warm_up`, fills the whole pool the first time it is called (unless
    /// [`Technique::precompute`] already did); otherwise nothing.
    pub fn warm_up(&mut self, world: &World, progress: &mut dyn Progress) {
        if self.settings.warm_up && !self.warmed_up {
            self.fill_all(world, progress);
            self.warmed_up = true;
        }
    }

    /// Irradiance display for `world`'s transforms.
    pub fn display(&self, world: &World) -> crate::elements::Display {
        self.elements.display(
            &world.scene,
            &self.accumulators,
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

    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        match classify(changes) {
            Invalidation::None => ChangeResponse::Updated,
            Invalidation::Rebuild(reason) => ChangeResponse::Rebuild { reason },
            Invalidation::Camera => {
                for g in &mut self.groups {
                    g.priority.pilots_seen = 0;
                    g.priority.pilots_visible = 0;
                }
                self.pilots_since_camera = 0;
                ChangeResponse::Updated
            }
            Invalidation::Lighting => {
                let next = Arc::new(Snapshot::of(
                    world,
                    self.next_snapshot,
                    self.factors.exponent(2),
                ));
                self.next_snapshot += 1;
                let fraction = changed_light_fraction(&self.current, &next);
                self.current = next;
                if fraction > self.settings.restart_fraction as f64 {
                    self.restart();
                } else {
                    self.stale = self
                        .groups
                        .iter()
                        .filter(|g| g.epoch.id != self.current.id)
                        .count() as u64;
                }
                if changes
                    .iter()
                    .any(|c| matches!(c, SceneChange::CameraMoved { .. }))
                {
                    self.pilots_since_camera = 0;
                }
                ChangeResponse::Updated
            }
        }
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
        let display = self.display(world);
        let img = shade::shade(world, gbuffer, &self.elements, &display);
        self.last_shade_ms = t0.elapsed().as_secs_f64() * 1e3;
        img
    }

    fn stats(&self) -> Counters {
        let c = &self.counters;
        let mut out = Counters::new();
        for (name, x) in [
            ("groups", self.layout.groups as f64),
            ("pool_photons", self.layout.pool() as f64),
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
