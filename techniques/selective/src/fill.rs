//! The pool in index order (§5.1): photons traced once, in the current scene state,
//! until the pool of N_g groups × (pilots + correctives) is full; `warm_up` fills it
//! before the first frame.

use crate::qmc::{LightCells, emit, photon_stream};
use crate::state::Selective;
use illume_core::Progress;
use illume_core::Rgb;
use illume_core::sampling::{HaltonScramble, HaltonStream};
use illume_scene::MASK_DEFAULT;
use illume_transport::World;
use illume_transport::photon::{PhotonPath, PhotonPathSettings};
use rayon::prelude::*;
use std::time::Instant;

/// Photons traced at the start to measure the yield (impacts stored per photon) that
/// `min_impacts_per_element` sizes the pool by: ±1–2 % on the yield for a scene
/// storing a few tenths of an impact per photon.
pub const YIELD_PROBE: u64 = 1 << 14;

/// First photon index of the yield probe: far above the pool's indices (below 2³²)
/// and the emission map's pilots (from 2⁴⁰).
const PROBE_INDEX_BASE: u64 = 1 << 41;

/// Impacts stored per photon (reflections after the first, as the pool deposits
/// them) over [`YIELD_PROBE`] photons emitted as the pool's are (`cells`, with their
/// emission maps) and traced with `path` in `world`.
pub fn impacts_per_photon(
    world: &World,
    cells: &LightCells,
    path: &PhotonPathSettings,
    scramble: &HaltonScramble,
) -> f64 {
    const CHUNK: u64 = 256;
    let stored: u64 = (0..YIELD_PROBE / CHUNK)
        .into_par_iter()
        .map(|chunk| {
            let mut n = 0u64;
            world.tracer.scoped(|tracer| {
                for i in chunk * CHUNK..(chunk + 1) * CHUNK {
                    let mut s = photon_stream(PROBE_INDEX_BASE + i, scramble);
                    if let Some((p, _)) = emit(&world.lights, cells, &mut s) {
                        run_to_its_end(world, tracer, path, p, &mut s, |_| n += 1);
                    }
                }
            });
            n
        })
        .sum();
    stored as f64 / YIELD_PROBE as f64
}

/// Traces photon `p` in `world` (mask [`MASK_DEFAULT`], `tracer` being `world`'s) to
/// the end of its path, calling `stored` with the flux of every impact the pool would
/// store (reflections after the first: the renderer draws direct light).
pub(crate) fn run_to_its_end(
    world: &World,
    tracer: &mut illume_accel::ScopedTracer<'_>,
    path: &PhotonPathSettings,
    mut p: PhotonPath,
    s: &mut HaltonStream<'_>,
    mut stored: impl FnMut(Rgb),
) {
    while p.alive(path) {
        let Some(hit) = p.trace(world, tracer, MASK_DEFAULT, path) else {
            break;
        };
        if !hit.reflects {
            break;
        }
        let (impact, continues) = p.scatter(hit, s, path);
        if impact.bounce >= 1 {
            stored(impact.flux);
        }
        if !continues {
            break;
        }
    }
}

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
