//! Photon groups (§5.1, Fig. 1) and their update priority (§5.3).
//!
//! The pool holds N = N_g·N_p·R photons. Photons `[0, N_g·N_p)` are pilots, N_p
//! consecutive indices per group: group g's pilots are `g·N_p … (g+1)·N_p − 1`. The
//! rest are correctives, N_g apart: group g's are `N_g·N_p + g + c·N_g`, c = 0 … N_p·(R−1)
//! − 1. Correctives of one group agree to within b^−k_b in every factored Halton base
//! (Eq. 3) — a tight bundle of similar paths — while pilots sample the whole space; a
//! pilot `i` that meets a change tells that group `i mod N_g` (Eq. 6) holds similar
//! paths, since `i` differs from each of its correctives by a multiple of N_g.

/// The index layout of the pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GroupLayout {
    /// N_g, groups.
    pub groups: u64,
    /// N_p, pilots per group.
    pub pilots: u64,
    /// R, photons per group over pilots per group.
    pub ratio: u64,
}

impl GroupLayout {
    /// Pool size N = N_g·N_p·R.
    pub fn pool(&self) -> u64 {
        self.groups * self.pilots * self.ratio
    }

    /// Photons per group, N_p·R.
    pub fn per_group(&self) -> u64 {
        self.pilots * self.ratio
    }

    /// First corrective index, N_g·N_p.
    pub fn first_corrective(&self) -> u64 {
        self.groups * self.pilots
    }

    /// True for a pilot photon.
    pub fn is_pilot(&self, i: u64) -> bool {
        i < self.first_corrective()
    }

    /// The group photon `i` belongs to (pilots by block, correctives by residue).
    pub fn group_of(&self, i: u64) -> u64 {
        if self.is_pilot(i) {
            i / self.pilots
        } else {
            (i - self.first_corrective()) % self.groups
        }
    }

    /// The group a pilot `i` that meets a change raises (Eq. 6): `i mod N_g`.
    pub fn raised_by_pilot(&self, i: u64) -> u64 {
        i % self.groups
    }

    /// Group `g`'s pilots.
    pub fn pilots_of(&self, g: u64) -> std::ops::Range<u64> {
        g * self.pilots..(g + 1) * self.pilots
    }

    /// Group `g`'s correctives, in increasing order.
    pub fn correctives_of(&self, g: u64) -> impl Iterator<Item = u64> + Clone + use<> {
        let first = self.first_corrective() + g;
        let step = self.groups;
        let count = self.pilots * (self.ratio - 1);
        (0..count).map(move |c| first + c * step)
    }

    /// Every photon of group `g` below `limit` (photons not yet traced in an index-order
    /// fill are left out): pilots first.
    pub fn photons_of(&self, g: u64, limit: u64) -> Vec<u64> {
        let mut v: Vec<u64> = self.pilots_of(g).filter(|&i| i < limit).collect();
        v.extend(self.correctives_of(g).take_while(|&i| i < limit));
        v
    }
}

/// Update priority of one group (§5.3).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Priority {
    /// P: pilot hits on changed objects (Δp each, reduced by texture masking).
    pub p: f64,
    /// Pilots of this group's residue shot since the last camera move.
    pub pilots_seen: u64,
    /// Of those, pilots with an impact in the view frustum.
    pub pilots_visible: u64,
}

impl Priority {
    /// V·P with V = 1 + `weight`·(visible fraction) once `enough` pilots were shot since
    /// the last camera move across all groups (else V = 1).
    pub fn score(&self, enough: bool, weight: f64) -> f64 {
        let v = if enough && self.pilots_seen > 0 {
            1.0 + weight * self.pilots_visible as f64 / self.pilots_seen as f64
        } else {
            1.0
        };
        v * self.p
    }
}
