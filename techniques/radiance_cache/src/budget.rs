//! The frame's **work budget** (beyond the paper): how many records a frame computes.
//!
//! A frame's records are computed in
//! [`Technique::indirect`](illume_transport::Technique::indirect) (the G-buffer says where).
//! [`Budget::work`](illume_transport::Budget::work) (from
//! [`Technique::advance`](illume_transport::Technique::advance), else the settings'
//! `records_per_frame_max`) caps the records a frame computes: replacements first, in record
//! order (those past the cap live one frame longer: `records_deferred`), then new records pass
//! by pass, coarse to fine, spread evenly over a pass's pixels (`records_skipped` counts those
//! left out; a later frame places them). Pixels that no record reaches then take the mean light
//! of their neighbours on the same surface, pass after pass (`pixels_filled`,
//! `pixels_unfilled`). Pass 1 of `interpolated` and the planned records pass 2 admits are not
//! capped. [`Budget::time_ms`](illume_transport::Budget::time_ms) becomes a record cap the same
//! way: the limit divided by the cost of a record measured on the previous frames (the gathers'
//! wall time over the records made, smoothed; at least one record per frame), the smaller of
//! the two caps when both are set. The first frame, with no cost measured yet, is capped by
//! `Budget::work` alone. The time limit covers the records' gathers only: expiry, reprojection
//! and shading are not in it.

use crate::placement::Candidate;
use crate::state::RadianceCache;

impl RadianceCache {
    /// The records this frame may compute: the smaller of `work_cap` and the time
    /// limit over the measured cost of a record (at least one); `None`: no limit.
    pub(crate) fn frame_cap(&self) -> Option<u64> {
        let by_time = match (self.time_cap_ms, self.ms_per_record) {
            (Some(limit), Some(ms)) if ms > 0.0 => Some(((limit / ms).floor() as u64).max(1)),
            _ => None,
        };
        match (self.work_cap, by_time) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Folds a frame's gathers (`made` records in `ms`) into the cost per record that
    /// turns `Budget::time_ms` into a record cap. Frames of fewer than 4 records say
    /// too little and are skipped.
    pub(crate) fn measure_gathers(&mut self, made: u64, ms: f64) {
        if made < 4 || !ms.is_finite() {
            return;
        }
        let now = ms / made as f64;
        self.ms_per_record = Some(match self.ms_per_record {
            Some(old) => 0.5 * (old + now),
            None => now,
        });
    }

    /// Takes one record from the frame's work budget; false when it is spent.
    pub(crate) fn take_work(&mut self) -> bool {
        match &mut self.work_left {
            None => true,
            Some(0) => false,
            Some(n) => {
                *n -= 1;
                true
            }
        }
    }

    /// The placements of one pass the frame's work budget allows: all of them, or as
    /// many as are left, spread evenly over the pass's list (pixel order); the others
    /// are counted as skipped.
    pub(crate) fn within_budget(&mut self, wanted: Vec<Candidate>) -> Vec<Candidate> {
        let Some(left) = self.work_left else {
            return wanted;
        };
        let (len, take) = (wanted.len() as u64, (wanted.len() as u64).min(left));
        self.work_left = Some(left - take);
        self.counters.skipped += len - take;
        if take == len {
            return wanted;
        }
        // The middle element of each of `take` equal runs of the list.
        (0..take)
            .map(|i| wanted[((2 * i + 1) * len / (2 * take)) as usize])
            .collect()
    }
}
