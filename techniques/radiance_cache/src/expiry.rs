//! Step 1 of a frame, **expiry** (§4.2, §5 Fig. 9): the records that leave the cache
//! before the current frame, and their replacements.
//!
//! A record lives `lifespan_frames` frames from its own (Eq. 10 and Eq. 12 through τ,
//! [`crate::temporal`]). When its life ends it is:
//! * **deleted** (§5, Fig. 9) when no pixel used it in the last frame shaded
//!   (`deletion`; the exact use count stands in for the paper's occlusion query), or
//!   when no surface facing its normal lies at its position any more
//!   (`replace_only_on_surface`, beyond the paper);
//! * otherwise **replaced** by a new record at the same position and normal (§4.2,
//!   Fig. 6), traced with its predecessor's directions and random numbers
//!   (`reuse_directions`), so the difference between the two is change, not noise.
//!
//! `per_frame` (the paper's baseline) drops every record each frame instead.
//!
//! **Age.** On a timeline (the paper's setting) records age by frames; in real time by
//! an age clock that stops while the world rests (see `RadianceCache::age_clock`).
//!
//! **Neighbour aging** (`neighbour_aging`, §7's future work): a new record whose
//! lifespan is shorter than δt_max ends the lives of the records usable at its position
//! no later than its own.

use crate::RadianceCacheError;
use crate::placement::Made;
use crate::record::usable;
use crate::state::{RadianceCache, Slot};
use crate::temporal::is_valid;
use illume_core::sampling::mix64;
use illume_core::{Ray, Vec3};
use illume_transport::World;
use rayon::prelude::*;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// The records a frame's expiry ends, in id order.
struct Due {
    /// Every record leaving the cache.
    doomed: Vec<u32>,
    /// Those of them that may get a successor at their place (temporal modes, online).
    successors: Vec<u32>,
}

impl RadianceCache {
    /// True when a surface facing `n` lies at `p` in `world` (within 0.1 % of the
    /// scene's size, normals within 25°).
    pub(crate) fn surface_at(&self, world: &World, p: Vec3, n: Vec3) -> bool {
        let eps = self.record_settings.r_min_m.max(1e-4);
        let origin = p + n * eps;
        let Some(hit) = world.trace(&Ray::new(origin, -n), illume_scene::MASK_DEFAULT) else {
            return false;
        };
        let facing = if hit.front_face {
            hit.shading_normal
        } else {
            -hit.shading_normal
        };
        hit.t <= 2.0 * eps && hit.reflects && facing.dot(n) >= 25f32.to_radians().cos()
    }

    /// Step 1: the records that leave the cache before the current frame, and their
    /// replacements (see the module docs).
    pub(crate) fn expire(&mut self, world: &World) {
        let Due {
            mut doomed,
            successors,
        } = self.due();
        let (traced, deferred) = self.replacements_within_budget(world, &successors);
        // Both lists are in id order.
        doomed.retain(|id| deferred.binary_search(id).is_err());
        self.counters.deferred = deferred.len() as u64;
        self.counters.expired = doomed.len() as u64;
        let predecessors = self.trace_replacements(world, &traced);
        for id in doomed {
            self.remove(id);
        }
        for (predecessor, slot) in predecessors {
            match self.admit(slot) {
                Ok(id) => {
                    self.counters.replaced += 1;
                    if let (Some(p), Some(h)) = (
                        predecessor,
                        self.slots[id as usize].as_ref().and_then(|s| s.history),
                    ) {
                        self.history[p as usize].successor = Some(h);
                    }
                }
                Err(_) => self.counters.failed += 1,
            }
        }
        self.expire_all = false;
        self.expire_instances.clear();
    }

    /// The records whose life ends before the current frame, by a surprise
    /// (`surprise_expired`) or their lifespan, in id order.
    fn due(&mut self) -> Due {
        let per_frame = !self.temporal();
        let all = self.expire_all;
        let (real_time, now) = (self.settings.paced_real_time, self.age_now());
        let replaying = self.plan.is_some();
        let mut doomed = Vec::new();
        let mut successors = Vec::new();
        for (id, slot) in self.slots.iter().enumerate() {
            let Some(slot) = slot else { continue };
            let r = &slot.record;
            let surprised = all
                || (!self.expire_instances.is_empty()
                    && (r
                        .instance
                        .is_some_and(|i| self.expire_instances.contains(&i))
                        || slot.seen.iter().any(|i| self.expire_instances.contains(i))));
            if surprised {
                self.counters.surprise_expired += 1;
                doomed.push(id as u32);
            } else if per_frame || !is_valid(slot.made(real_time), r.lifespan_frames, now) {
                doomed.push(id as u32);
                if !per_frame && !replaying {
                    successors.push(id as u32);
                }
            }
        }
        Due { doomed, successors }
    }

    /// Of the expired records that may get a successor, those replaced this frame
    /// (`.0`) and those the work budget puts off (`.1`, living one frame more), both
    /// in id order; the others are deleted (`deletion`, `replace_only_on_surface`),
    /// decided from the cache's state now.
    fn replacements_within_budget(
        &mut self,
        world: &World,
        successors: &[u32],
    ) -> (Vec<u32>, Vec<u32>) {
        let this = &*self;
        let replace: Vec<bool> = successors
            .par_iter()
            .map(|&id| {
                let slot = this.slots[id as usize].as_ref().expect("live slot");
                let unused =
                    this.settings.deletion && this.uses[id as usize].load(Ordering::Relaxed) == 0;
                !(unused
                    || (this.settings.replace_only_on_surface
                        && !this.surface_at(world, slot.record.position, slot.record.normal)))
            })
            .collect();
        // The work budget: replacements in id order; those past it live one frame more.
        let mut traced = Vec::new();
        let mut deferred = Vec::new();
        for (&id, replace) in successors.iter().zip(replace) {
            if !replace {
                self.counters.deleted += 1;
            } else if self.take_work() {
                traced.push(id);
            } else {
                deferred.push(id);
            }
        }
        for &id in &deferred {
            if let Some(slot) = self.slots[id as usize].as_mut() {
                slot.record.lifespan_frames += 1;
            }
        }
        (traced, deferred)
    }

    /// The successors of records `traced`, computed from the cache's state now, in id
    /// order, each with its predecessor's entry in pass 1's history.
    fn trace_replacements(&mut self, world: &World, traced: &[u32]) -> Vec<(Option<u32>, Slot)> {
        let frame = self.frame;
        let this = &*self;
        let gathers = Instant::now();
        let made: Vec<(u32, Result<Made, RadianceCacheError>)> = traced
            .par_iter()
            .map(|&id| {
                let slot = this.slots[id as usize].as_ref().expect("live slot");
                let key = if this.settings.reuse_directions {
                    slot.key
                } else {
                    mix64(slot.key ^ ((frame as u64) << 40))
                };
                let r = &slot.record;
                let glossy = slot.radiance.is_some();
                let result = this.make(world, r.position, r.normal, r.instance, key, glossy);
                (id, result)
            })
            .collect();
        self.counters.gather_ms += gathers.elapsed().as_secs_f64() * 1e3;
        let mut predecessors = Vec::new();
        for (id, result) in made {
            let predecessor = self.slots[id as usize].as_ref().and_then(|s| s.history);
            match result {
                Ok(m) => {
                    self.counters.holes += m.holes as u64;
                    predecessors.push((predecessor, m.slot));
                }
                Err(_) => self.counters.failed += 1,
            }
        }
        predecessors
    }

    /// `neighbour_aging`: the records usable at new record `id`'s position end their
    /// lives no later than it, when its lifespan is shorter than `max_age_frames`.
    pub(crate) fn age_neighbours(&mut self, id: u32) {
        let real_time = self.settings.paced_real_time;
        let Some((new, new_made)) = self.slots[id as usize]
            .as_ref()
            .map(|s| (s.record, s.made(real_time)))
        else {
            return;
        };
        if new.lifespan_frames >= self.settings.max_age_frames {
            return;
        }
        let end = new_made + new.lifespan_frames;
        let mut neighbours = Vec::new();
        self.octree.for_each_containing(new.position, |k| {
            if k != id {
                neighbours.push(k);
            }
        });
        neighbours.sort_unstable();
        for k in neighbours {
            let accuracy = self.settings.accuracy;
            let Some(slot) = self.slots[k as usize].as_mut() else {
                continue;
            };
            let made = slot.made(real_time);
            let r = &mut slot.record;
            if usable(r.ward_error(new.position, new.normal), accuracy)
                && made + r.lifespan_frames > end
            {
                r.lifespan_frames = end.saturating_sub(made).max(1);
                self.counters.aged += 1;
            }
        }
    }

    /// The present in what records age by: the age clock in real time, frames otherwise.
    pub(crate) fn age_now(&self) -> u32 {
        if self.settings.paced_real_time {
            self.age_clock
        } else {
            self.frame
        }
    }

    /// True when the frame being made (`self.frame`) ticks the real-time age clock (at
    /// its start): it is the frame of the last change or one of the δt_max − 1 after it.
    pub(crate) fn age_clock_running(&self) -> bool {
        self.settings.paced_real_time
            && self
                .last_world_change
                .is_some_and(|c| self.frame < c.saturating_add(self.settings.max_age_frames))
    }
}
