//! The selective update (§5.1–§5.3, Algorithm 1): which stale group is re-traced next
//! (by priority P and the view factor V, in index order, or at random), its re-tracing
//! with negative and positive energy in the union of its epoch's world and the current
//! one ([`crate::retrace`]), the priorities its pilots raise (Eq. 6), and the pool's
//! growth by rounds of correctives once everything is current.

use crate::elements::Elements;
use crate::groups::GroupLayout;
use crate::masking::{MaskingView, TextureMasking};
use crate::retrace::{Frustum, Met, PilotHit, Snapshot, TraceContext, TraceOutput, UnionWorld};
use crate::settings::GroupOrder;
use crate::state::{Group, Selective};
use illume_core::sampling::HaltonScramble;
use illume_transport::World;
use illume_transport::photon::PhotonPathSettings;
use std::sync::Arc;
use std::time::Instant;

/// A stale group's re-trace taken out of the solution's lock (the streaming thread,
/// [`crate::stream`]): chosen and set up under the lock ([`Selective::take_work`]),
/// traced without it ([`RetraceJob::trace`]) so that frames copy the display values
/// meanwhile, and applied under it again ([`Selective::finish_retrace`]). Owned handles
/// of everything the trace reads.
pub struct RetraceJob {
    g: u64,
    epoch: Arc<Snapshot>,
    current: Arc<Snapshot>,
    union: UnionWorld,
    indices: Vec<u64>,
    frustum: Frustum,
    elements: Arc<Elements>,
    scramble: Arc<HaltonScramble>,
    masking: Arc<TextureMasking>,
    path: PhotonPathSettings,
    inv_quantum: f64,
    layout: GroupLayout,
    pixels_high: u32,
    started: Instant,
}

/// What [`Selective::take_work`] did under the lock.
pub enum Work {
    /// A group to re-trace outside the lock.
    Retrace(Box<RetraceJob>),
    /// A step done under the lock ([`Selective::step`]'s result).
    Stepped(Option<u64>),
}

impl RetraceJob {
    /// The re-trace (in the union of the job's two scene states, which it owns; the
    /// caller keeps the world read-locked, as for any step).
    pub fn trace(&self) -> TraceOutput {
        TraceContext {
            elements: &self.elements,
            layout: self.layout,
            scramble: &self.scramble,
            path: self.path,
            inv_quantum: self.inv_quantum,
            frustum: &self.frustum,
            masking: &self.masking,
            view: MaskingView::of(&self.frustum, self.pixels_high),
        }
        .retrace(&self.union, &self.epoch, &self.current, &self.indices)
    }
}

impl Selective {
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

    /// The streaming thread's unit of work, under the lock: a stale group whose re-trace
    /// has something to trace becomes a [`RetraceJob`] for outside the lock; anything
    /// else (a group with nothing to trace, a fill chunk, growth) is done here as
    /// [`Selective::step`] does it.
    pub fn take_work(&mut self, world: &World) -> Work {
        let Some(g) = self.next_group() else {
            return Work::Stepped(self.step(world));
        };
        match self.prepare_retrace(world, g) {
            Some(job) => Work::Retrace(job),
            None => Work::Stepped(Some(0)),
        }
    }

    /// Sets up group `g`'s re-trace in `world` (current state): the job, or None when
    /// there is nothing to trace (the group is current already, or nothing photons see
    /// changed between its state and the current one), which is then settled here.
    fn prepare_retrace(&mut self, world: &World, g: u64) -> Option<Box<RetraceJob>> {
        let started = Instant::now();
        let epoch = Arc::clone(&self.groups[g as usize].epoch);
        let current = Arc::clone(&self.current);
        self.cursor = (g + 1) % self.layout.groups;
        if epoch.id == current.id {
            self.groups[g as usize].priority.p = 0.0;
            return None;
        }
        let key = (epoch.id, current.id);
        if self.union.as_ref().is_none_or(|u| u.key != key) {
            self.union = Some(UnionWorld::new(world, &epoch, &current));
        }
        if self.union.as_ref().is_none_or(|u| u.changes.none()) {
            // Nothing to trace: the group moves to the current state as it is.
            self.groups[g as usize].epoch = current;
            self.groups[g as usize].priority.p = 0.0;
            self.stale -= 1;
            self.counters.groups_retraced += 1;
            self.counters.trace_s += started.elapsed().as_secs_f64();
            return None;
        }
        Some(Box::new(RetraceJob {
            g,
            indices: self.layout.photons_of(g, self.filled),
            epoch,
            current,
            union: self.union.take().expect("built above"),
            frustum: crate::retrace::Frustum::of(&world.scene, self.aspect),
            elements: Arc::clone(&self.elements),
            scramble: Arc::clone(&self.scramble),
            masking: Arc::clone(&self.masking),
            path: self.settings.photon_path(),
            inv_quantum: 1.0 / self.quantum_w,
            layout: self.layout,
            pixels_high: self.pixels_high,
            started,
        }))
    }

    /// Applies a [`RetraceJob`]'s output under the lock, as [`Selective::retrace_group`]
    /// would have, unless the group no longer holds the state the job started from: the
    /// solution restarted meanwhile (a restart moves every group to the new state) or
    /// someone else brought the group up to date. Its deposits are then dropped: they
    /// belong to a state the accumulators no longer hold. A group that a newer change
    /// made stale again moves to the job's state and stays stale. Returns the photons
    /// traced.
    pub fn finish_retrace(&mut self, job: RetraceJob, out: TraceOutput) -> u64 {
        let g = job.g as usize;
        if self.groups[g].epoch.id != job.epoch.id {
            return 0;
        }
        self.apply(&out);
        self.record_pilots(&out);
        self.raise(&out, &job.epoch);
        let now_current = job.current.id == self.current.id;
        self.groups[g].epoch = job.current;
        if now_current {
            self.stale -= 1;
        }
        if self.union.is_none() {
            self.union = Some(job.union);
        }
        self.groups[g].priority.p = 0.0;
        self.counters.groups_retraced += 1;
        self.counters.trace_s += job.started.elapsed().as_secs_f64();
        out.photons
    }

    /// The next stale group by the settings' order.
    pub(crate) fn next_group(&mut self) -> Option<u64> {
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
        match self.prepare_retrace(world, g) {
            Some(job) => {
                let out = job.trace();
                self.finish_retrace(*job, out)
            }
            None => 0,
        }
    }

    pub(crate) fn record_pilots(&mut self, out: &TraceOutput) {
        for &(i, visible) in &out.pilots {
            let h = &mut self.groups[self.layout.raised_by_pilot(i) as usize].priority;
            h.pilots_seen += 1;
            h.pilots_visible += visible as u64;
            self.pilots_since_camera += 1;
        }
    }

    /// Raises P of the groups pilots point at (Eq. 6, §5.3).
    pub(crate) fn raise(&mut self, out: &TraceOutput, epoch: &Snapshot) {
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

    /// Grows the pool by one round of N_p correctives per group (R + 1: the indices
    /// N_g·N_p·R … N_g·N_p·(R + 1) − 1, N_p more per residue, so every group keeps its
    /// shape) if that stays within `max_photons`. Only called with every group current
    /// and the pool full: a static scene.
    pub(crate) fn grow(&mut self) -> bool {
        if !self.can_grow() {
            return false;
        }
        self.layout.ratio += 1;
        self.counters.growth_rounds += 1;
        true
    }

    /// True when one more round of N_p correctives per group stays within `max_photons`.
    pub(crate) fn can_grow(&self) -> bool {
        self.layout.pool() + self.layout.groups * self.layout.pilots <= self.settings.max_photons
    }

    /// Works until nothing is stale and the pool is full (grown to `max_photons` when
    /// that is set).
    pub fn converge(&mut self, world: &World) {
        while self.step(world).is_some() {}
    }
}
