//! The **temporal modes** and pass 1 of `interpolated` (§4.4, Fig. 5).
//!
//! `reuse`: lifespans and replacement, no temporal gradient (Fig. 5c). `extrapolated`: also the
//! extrapolated gradients (Fig. 5d), one pass. `interpolated` (Fig. 5e):
//! [`Technique::precompute`](illume_transport::Technique::precompute) runs the extrapolated
//! loop over the whole timeline (pass 1) on a private world, keeping every record with its
//! successor; each replaced record's temporal gradient then becomes the interpolated one
//! towards its replacement (Eq. 21–23), and the frames (pass 2) replay that plan: a frame
//! admits the records made at it and drops the expired, with no new gather except for pixels
//! the plan does not cover (counted as `records_created`).

use crate::RadianceCacheError;
use crate::state::{RadianceCache, Slot};
use crate::temporal::interpolated_gradient;
use illume_core::progress::Progress;
use illume_transport::{GBuffer, World};

impl RadianceCache {
    /// Pass 2 of `interpolated`: the planned records made at the current frame enter.
    pub(crate) fn admit_planned(&mut self) {
        let Some(plan) = &self.plan else { return };
        let Some(ids) = plan.get(self.frame as usize) else {
            return;
        };
        let slots: Vec<Slot> = ids
            .iter()
            .map(|&h| self.history[h as usize].slot.clone())
            .collect();
        for slot in slots {
            match self.insert(slot) {
                Ok(_) => self.counters.admitted += 1,
                Err(_) => self.counters.failed += 1,
            }
        }
    }

    /// Pass 1 of `interpolated` over the timeline on a private world (see the module
    /// docs), then the interpolated gradients (Eq. 21–23) and the plan.
    pub(crate) fn plan_timeline(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), RadianceCacheError> {
        let times = self.timeline.times().to_vec();
        let (w, h) = (self.timeline.width(), self.timeline.height());
        progress.begin(
            "radiance_cache pass 1 (records of the whole timeline)",
            times.len() as u64,
        );
        self.clear_cache();
        self.history.clear();
        self.recording = true;
        let mut private = world.at_time(times[0]);
        for (i, &t) in times.iter().enumerate() {
            if i > 0 {
                private.set_time(t);
            }
            let gbuffer = GBuffer::rasterize(&private, w, h);
            self.frame_step(&private, &gbuffer);
            progress.set(i as u64 + 1);
        }
        self.recording = false;
        progress.end();
        // Eq. 21–23: each replaced record moves towards its replacement.
        for k in 0..self.history.len() {
            if let Some(l) = self.history[k].successor {
                let (rk, rl) = (
                    &self.history[k].slot.record,
                    &self.history[l as usize].slot.record,
                );
                let span = rl.frame.saturating_sub(rk.frame);
                if let Ok(g) = interpolated_gradient(&rk.value, rk.frame, &rl.value, rl.frame) {
                    self.history[k].slot.record.temporal_gradient = g;
                }
                let next = self.history[l as usize]
                    .slot
                    .radiance
                    .as_ref()
                    .map(|d| d.coefficients.clone());
                if let (Some(next), Some(data), true) =
                    (next, self.history[k].slot.radiance.as_mut(), span > 0)
                {
                    data.temporal_gradient = next
                        .iter()
                        .zip(&data.coefficients)
                        .map(|(a, b)| (*a - *b) * (1.0 / span as f32))
                        .collect();
                }
            }
        }
        let mut plan = vec![Vec::new(); times.len()];
        for (i, p) in self.history.iter().enumerate() {
            if let Some(at) = plan.get_mut(p.slot.record.frame as usize) {
                at.push(i as u32);
            }
        }
        let planned = self.history.len();
        self.clear_cache();
        self.plan = Some(plan);
        progress.message(&format!(
            "radiance_cache: pass 1 made {planned} records over {} frames",
            times.len()
        ));
        Ok(())
    }
}
