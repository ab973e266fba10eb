//! The photon pool (§0.3, §0.5, Algorithm 2, Figure 6): a fixed-size FIFO of photon
//! impacts, each linked to its VSL, whose power sums are updated in O(1) per impact.
//!
//! **Fixed point.** Powers are integers ([`Quanta`], illume-transport's shared signed
//! fixed-point flux): an impact carries `quanta = round(ρ·Φ / q)` per channel
//! (q = [`PhotonPool::quantum_w`] watts), a VSL side sums the quanta of its pooled
//! impacts, and evicting an impact subtracts exactly the integers it added. Integer addition is associative, so a VSL's power equals the sum of its
//! pooled impacts *exactly*, after any number of updates: no drift, by construction
//! ([`PhotonPool::validate`] re-sums and compares).
//!
//! **Whole photons.** The pool evicts whole photon paths (all impacts of the oldest
//! photon, Algorithm 2 once per impact), so it always holds every impact of the last
//! K emitted photons, including photons that hit nothing (counted by the weight of the
//! next pooled impact). K is exact, and VSL flux = Σ(pooled quanta)·q / K is an unbiased
//! estimate of the flux leaving each VSL's surface over those K photons.
//!
//! **Sides.** Each VSL has a front and a back accumulator (index `2·vsl + side`): a
//! double-sided surface lit from both sides emits on both.

use illume_transport::flux::Quanta;
use std::collections::VecDeque;

/// One impact entering the pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolImpact {
    /// Accumulator index `2·vsl + side` (side 1 = the VSL's back face).
    pub slot: u32,
    /// ρ·Φ of the impact in quanta per channel.
    pub quanta: Quanta,
}

#[derive(Clone, Copy, Debug)]
struct Pooled {
    slot: u32,
    /// Photons this entry closes: 1 + preceding impact-less photons for a photon's
    /// first impact, 0 for its later impacts.
    weight: u32,
    quanta: Quanta,
}

/// The FIFO pool and the VSL power sums it feeds.
#[derive(Clone, Debug)]
pub struct PhotonPool {
    capacity: usize,
    quantum_w: f64,
    ring: VecDeque<Pooled>,
    power: Vec<Quanta>,
    applied_photons: u64,
    evicted_photons: u64,
    carry: u32,
    impacts_added: u64,
    stamps: VecDeque<(u64, f64)>,
}

impl PhotonPool {
    /// An empty pool of `capacity` impacts for `vsl_count` VSLs; one quantum is
    /// `quantum_w` watts.
    pub fn new(capacity: usize, vsl_count: usize, quantum_w: f64) -> Self {
        Self {
            capacity,
            quantum_w,
            ring: VecDeque::with_capacity(capacity),
            power: vec![Quanta::ZERO; 2 * vsl_count],
            applied_photons: 0,
            evicted_photons: 0,
            carry: 0,
            impacts_added: 0,
            stamps: VecDeque::new(),
        }
    }

    /// Watts per quantum.
    pub fn quantum_w(&self) -> f64 {
        self.quantum_w
    }

    /// Impacts the pool holds at most.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Impacts pooled now.
    pub fn len(&self) -> usize {
        self.ring.len()
    }

    /// True when no impact is pooled.
    pub fn is_empty(&self) -> bool {
        self.ring.is_empty()
    }

    /// K: emitted photons whose impacts (possibly none) are all in the pool.
    pub fn photons(&self) -> u64 {
        self.applied_photons - self.evicted_photons
    }

    /// Photons ever pushed.
    pub fn photons_pushed(&self) -> u64 {
        self.applied_photons
    }

    /// Impacts ever pushed.
    pub fn impacts_pushed(&self) -> u64 {
        self.impacts_added
    }

    /// The power accumulators in quanta, index `2·vsl + side`.
    pub fn power_quanta(&self) -> &[Quanta] {
        &self.power
    }

    /// Records that photons pushed from now on were emitted at `time_s` (for the pool
    /// age).
    pub fn stamp(&mut self, time_s: f64) {
        if self
            .stamps
            .back()
            .is_none_or(|&(i, _)| i != self.applied_photons)
        {
            self.stamps.push_back((self.applied_photons, time_s));
        } else if let Some(last) = self.stamps.back_mut() {
            last.1 = time_s;
        }
    }

    /// Emission time of the oldest pooled photon (from [`PhotonPool::stamp`]).
    pub fn oldest_time_s(&self) -> Option<f64> {
        if self.photons() == 0 {
            return None;
        }
        self.stamps
            .iter()
            .rev()
            .find(|&&(i, _)| i <= self.evicted_photons)
            .or(self.stamps.front())
            .map(|s| s.1)
    }

    /// Algorithm 2 for every impact of one emitted photon: evicts whole oldest photons
    /// until the new ones fit, subtracting their power from their VSLs, then adds each
    /// new impact's power to its VSL. An empty `impacts` (the photon hit nothing) still
    /// counts in K.
    pub fn push_photon(&mut self, impacts: &[PoolImpact]) {
        self.applied_photons += 1;
        if impacts.is_empty() {
            self.carry += 1;
            return;
        }
        assert!(
            impacts.len() <= self.capacity,
            "a photon path of {} impacts exceeds the pool of {}",
            impacts.len(),
            self.capacity
        );
        while self.ring.len() + impacts.len() > self.capacity {
            self.evict_oldest_photon();
        }
        for (j, imp) in impacts.iter().enumerate() {
            let weight = if j == 0 {
                1 + std::mem::take(&mut self.carry)
            } else {
                0
            };
            self.power[imp.slot as usize] += imp.quanta;
            self.ring.push_back(Pooled {
                slot: imp.slot,
                weight,
                quanta: imp.quanta,
            });
        }
        self.impacts_added += impacts.len() as u64;
    }

    fn evict_oldest_photon(&mut self) {
        let mut first = true;
        while let Some(p) = self.ring.front() {
            if !first && p.weight > 0 {
                break;
            }
            first = false;
            let p = self.ring.pop_front().expect("front exists");
            self.power[p.slot as usize] -= p.quanta;
            self.evicted_photons += p.weight as u64;
        }
        while self.stamps.len() > 1 && self.stamps[1].0 <= self.evicted_photons {
            self.stamps.pop_front();
        }
    }

    /// Empties the pool (the paper's alternative to ageing out, §0.9.1).
    pub fn flush(&mut self) {
        self.ring.clear();
        self.power.iter_mut().for_each(|p| *p = Quanta::ZERO);
        self.evicted_photons = self.applied_photons;
        self.carry = 0;
        self.stamps.clear();
    }

    /// Checks that every VSL side's power equals the sum of its pooled impacts and that
    /// K equals the pooled photon weights; the message names the first mismatch.
    pub fn validate(&self) -> Result<(), String> {
        let mut sums = vec![Quanta::ZERO; self.power.len()];
        let mut weights = self.carry as u64;
        for p in &self.ring {
            sums[p.slot as usize] += p.quanta;
            weights += p.weight as u64;
        }
        if let Some((i, _)) = sums
            .iter()
            .zip(&self.power)
            .enumerate()
            .find(|(_, (a, b))| a != b)
        {
            return Err(format!(
                "slot {i}: power {:?} but pooled impacts sum to {:?}",
                self.power[i], sums[i]
            ));
        }
        if weights != self.photons() {
            return Err(format!(
                "K = {} but pooled photon weights sum to {weights}",
                self.photons()
            ));
        }
        if self.ring.len() > self.capacity {
            return Err(format!(
                "{} impacts in a pool of {}",
                self.ring.len(),
                self.capacity
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_photons_are_evicted_and_k_counts_empty_photons() {
        let mut pool = PhotonPool::new(4, 2, 1.0);
        let imp = |slot, q| PoolImpact {
            slot,
            quanta: Quanta([q, 2 * q, 3 * q]),
        };
        pool.push_photon(&[]); // hits nothing
        pool.push_photon(&[imp(0, 1), imp(1, 2)]);
        pool.push_photon(&[imp(2, 4)]);
        assert_eq!(pool.photons(), 3);
        assert_eq!(pool.len(), 3);
        // Two more impacts: the oldest photon with impacts (and the empty one before it) go.
        pool.push_photon(&[imp(3, 8), imp(3, 16)]);
        assert_eq!(pool.len(), 3);
        assert_eq!(pool.photons(), 2);
        assert_eq!(pool.power_quanta()[0], Quanta([0, 0, 0]));
        assert_eq!(pool.power_quanta()[1], Quanta([0, 0, 0]));
        assert_eq!(pool.power_quanta()[2], Quanta([4, 8, 12]));
        assert_eq!(pool.power_quanta()[3], Quanta([24, 48, 72]));
        pool.validate().unwrap();
        pool.flush();
        assert_eq!(pool.photons(), 0);
        assert!(pool.power_quanta().iter().all(|p| p.is_zero()));
        pool.validate().unwrap();
    }
}
