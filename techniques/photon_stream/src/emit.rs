//! Photon emission and tracing (§0.7.1): equal-power photons from lights chosen by
//! power, Russian roulette on albedo at each impact (the shared
//! [`illume_transport::photon::trace_photon`] kernel, through the world's
//! tracer), and each impact turned into a pool entry for its nearest VSL.
//!
//! What an impact deposits: the flux *leaving* the surface it hit, ρ(x)·Φ_arriving
//! (diffusely reflected), for every impact of the path (bounce 0, 1, 2, …). Shading a
//! point with these VSLs therefore gives light reflected two or more times: exactly the
//! reference's `indirect` image, never direct light (the renderer's). With
//! [`Emitter::first_deposit`] = 1 (`gather_direct`) bounce 0 deposits nothing: the gather
//! computes that light at its hits by next-event estimation ([`crate::near_field`]).
//!
//! Photon `seq` uses PCG stream `seq` of the technique's seed, so the same photon index
//! in the same world gives the same path, whatever the thread count.

use crate::placement::VslSet;
use crate::pool::PoolImpact;
use illume_core::sampling::{Pcg32, mix64};
use illume_transport::World;
use illume_transport::flux::Quanta;
use illume_transport::photon::{PhotonPathSettings, trace_photon};
use rayon::prelude::*;

/// Traced photons ready for the pool: impacts of photon `k` are
/// `impacts[ends[k − 1]..ends[k]]` (zero impacts allowed).
#[derive(Clone, Debug, Default)]
pub struct PhotonBatch {
    /// Pool entries of every photon, in photon order.
    pub impacts: Vec<PoolImpact>,
    /// End offset of each photon's impacts.
    pub ends: Vec<u32>,
    /// Rays traced.
    pub rays: u64,
}

impl PhotonBatch {
    /// Number of photons.
    pub fn photons(&self) -> usize {
        self.ends.len()
    }

    /// The impacts of each photon in order.
    pub fn paths(&self) -> impl Iterator<Item = &[PoolImpact]> {
        let mut start = 0usize;
        self.ends.iter().map(move |&e| {
            let s = &self.impacts[start..e as usize];
            start = e as usize;
            s
        })
    }

    fn append(&mut self, mut other: PhotonBatch) {
        let base = self.impacts.len() as u32;
        self.impacts.append(&mut other.impacts);
        self.ends.extend(other.ends.iter().map(|e| e + base));
        self.rays += other.rays;
    }
}

/// Everything photon tracing needs besides the world.
pub struct Emitter<'a> {
    /// The VSLs impacts are assigned to.
    pub vsls: &'a VslSet,
    /// 1 / (watts per quantum).
    pub inv_quantum: f64,
    /// Path settings (bounce limit, mask).
    pub path: PhotonPathSettings,
    /// Seed of the photon streams.
    pub seed: u64,
    /// Impacts of a lower bounce deposit nothing
    /// ([`PhotonStreamSettings::first_deposit`](crate::PhotonStreamSettings::first_deposit)).
    pub first_deposit: u32,
}

impl<'a> Emitter<'a> {
    /// An emitter for photons traced in `_world` (hits carry their object-space
    /// positions, so nothing of the world's current transforms needs deriving here).
    pub fn new(
        _world: &World,
        vsls: &'a VslSet,
        inv_quantum: f64,
        path: PhotonPathSettings,
        seed: u64,
    ) -> Self {
        Self {
            vsls,
            inv_quantum,
            path,
            seed: mix64(seed ^ 0x9407_0a57),
            first_deposit: 0,
        }
    }

    /// This emitter with impacts below bounce `first` depositing nothing.
    pub fn with_first_deposit(self, first: u32) -> Self {
        Self {
            first_deposit: first,
            ..self
        }
    }

    /// Traces photons `first..first + count` sequentially.
    pub fn trace(&self, world: &World, first: u64, count: u64) -> PhotonBatch {
        self.trace_until(world, first, count, || false)
    }

    /// [`Emitter::trace`], stopping early (after a whole photon) once `stop` returns
    /// true; the batch holds the photons traced so far, `first..first + photons()`.
    /// `stop` is called once before each photon.
    pub fn trace_until(
        &self,
        world: &World,
        first: u64,
        count: u64,
        mut stop: impl FnMut() -> bool,
    ) -> PhotonBatch {
        let mut batch = PhotonBatch {
            impacts: Vec::with_capacity(count as usize * 3),
            ends: Vec::with_capacity(count as usize),
            rays: 0,
        };
        for seq in first..first + count {
            if stop() {
                break;
            }
            let mut rng = Pcg32::new(self.seed, seq);
            let stats = trace_photon(world, &mut rng, &self.path, |imp| {
                if imp.bounce < self.first_deposit {
                    return;
                }
                let Some(vsl) = self.vsls.nearest_on(
                    imp.hit.instance,
                    imp.hit.triangle,
                    imp.hit.position_object,
                ) else {
                    return;
                };
                let side = u32::from(!imp.hit.front_face);
                let out = imp.hit.albedo * imp.flux; // flux leaving the surface, ρ·Φ
                batch.impacts.push(PoolImpact {
                    slot: 2 * vsl + side,
                    // ρ·Φ ≥ 0; the clamp keeps a NaN or rounding sign out of the pool.
                    quanta: Quanta::from_flux(out.max(illume_core::Rgb::ZERO), self.inv_quantum),
                });
            });
            batch.rays += stats.rays as u64;
            batch.ends.push(batch.impacts.len() as u32);
        }
        batch
    }

    /// Traces photons `first..first + count` in parallel (rayon); the result is the
    /// same as [`Emitter::trace`], bit for bit.
    pub fn trace_parallel(&self, world: &World, first: u64, count: u64) -> PhotonBatch {
        const CHUNK: u64 = 512;
        let chunks: Vec<PhotonBatch> = (0..count.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let start = first + c * CHUNK;
                self.trace(world, start, CHUNK.min(first + count - start))
            })
            .collect();
        let mut out = PhotonBatch::default();
        for c in chunks {
            out.append(c);
        }
        out
    }
}
