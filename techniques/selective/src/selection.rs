//! The selective update (§5.1–§5.3, Algorithm 1): which stale group is re-traced next
//! (by priority P and the view factor V, in index order, or at random), its re-tracing
//! with negative and positive energy in the union of its epoch's world and the current
//! one ([`crate::retrace`]), the priorities its pilots raise (Eq. 6), and the pool's
//! growth by rounds of correctives once everything is current.

use crate::retrace::{Met, PilotHit, Snapshot, TraceOutput, UnionWorld};
use crate::settings::GroupOrder;
use crate::state::{Group, Selective};
use illume_transport::World;
use std::sync::Arc;
use std::time::Instant;

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
