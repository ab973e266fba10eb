//! The pool in index order (§5.1): photons traced once, in the current scene state,
//! until the pool of N_g groups × (pilots + correctives) is full; `warm_up` fills it
//! before the first frame.

use crate::state::Selective;
use illume_core::Progress;
use illume_transport::World;
use std::time::Instant;

impl Selective {
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

    /// With `warm_up`, fills the whole pool the first time it is called (unless
    /// [`Technique::precompute`] already did); otherwise nothing.
    pub fn warm_up(&mut self, world: &World, progress: &mut dyn Progress) {
        if self.settings.warm_up && !self.warmed_up {
            self.fill_all(world, progress);
            self.warmed_up = true;
        }
    }
}
