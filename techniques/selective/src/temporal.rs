//! The frames' display of the element solution while it is being updated (issue 34,
//! goal 7: no boiling).
//!
//! While groups are stale, each re-traced photon that met a change continues along a
//! new path: its later impacts land in other elements, so the static parts of the
//! scene gain and lose whole impacts from frame to frame. With ≈ 20 impacts per element
//! that is a change of several per cent per element per frame, and the shown indirect
//! light boils although its expectation barely moves. The paper leaves it there (its
//! ROOM holds ≈ 90 photons per element).
//!
//! Here the display vertices the frames see follow the solution through a noise-aware
//! exponential filter: a vertex whose new value lies within `temporal_sigmas` standard
//! deviations of its impact noise ([`Display::noise`]) of what the last frame showed
//! moves only `temporal_alpha` of the way; a larger change is real and passes, the more
//! of it the larger it is (the gain `1 − (kσ/δ)²`, the share of the change's energy
//! beyond the noise). Once nothing is stale and the pool is full, frames show the
//! solution itself, exactly (so stills, the converged state after an edit and every
//! test of the solution are untouched).

use crate::elements::Display;
use crate::state::Selective;
use illume_core::{Rgb, luminance};
use illume_transport::World;

/// The gain with which a vertex follows a change of `delta` (luminance) given its noise
/// `sigma`: `alpha` within `sigmas`·σ, rising towards 1 beyond as `1 − (kσ/δ)²`.
#[inline]
pub fn gain(delta: f32, sigma: f32, alpha: f32, sigmas: f32) -> f32 {
    let t = sigmas * sigma;
    if delta.is_nan() || delta <= t {
        return alpha;
    }
    let r = t / delta;
    (1.0 - r * r).max(alpha)
}

/// Moves `shown` towards `target` vertex by vertex with [`gain`] (`noise` from the same
/// display as `target`).
pub fn blend(shown: &mut [[Rgb; 2]], target: &Display, alpha: f32, sigmas: f32) {
    for ((s, t), n) in shown.iter_mut().zip(&target.irradiance).zip(&target.noise) {
        for side in 0..2 {
            let delta = (luminance(t[side]) - luminance(s[side])).abs();
            let k = gain(delta, n[side], alpha, sigmas);
            s[side] += (t[side] - s[side]) * k;
        }
    }
}

impl Selective {
    /// The display a frame shows: the solution itself when it is settled (nothing stale,
    /// the pool full), when the filter is off (`temporal_alpha` = 1) and on the first
    /// frame; else the last frame's values moved towards the solution (module docs).
    /// Mind the cost: a copy of the vertex values per frame.
    pub fn frame_display(&mut self, world: &World) -> Display {
        let alpha = self.settings.temporal_alpha;
        let settled = !self.has_work();
        if settled || alpha >= 1.0 {
            let display = self.display(world);
            self.shown = (alpha < 1.0).then(|| display.irradiance.clone());
            return display;
        }
        let target = self.elements.display_with_noise(
            &world.scene,
            &self.accumulators,
            &self.counts,
            self.quantum_w,
            self.filled,
        );
        let shown = match self.shown.take() {
            Some(mut shown) if shown.len() == target.irradiance.len() => {
                blend(&mut shown, &target, alpha, self.settings.temporal_sigmas);
                shown
            }
            _ => target.irradiance.clone(),
        };
        self.shown = Some(shown.clone());
        Display {
            irradiance: shown,
            noise: target.noise,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_moves_by_alpha_and_real_changes_pass() {
        // Within 2σ: alpha; at 2σ·√2 half the energy is beyond the noise: 1/2; far beyond: ≈ 1.
        assert_eq!(gain(0.0, 1.0, 0.2, 2.0), 0.2);
        assert_eq!(gain(1.9, 1.0, 0.2, 2.0), 0.2);
        assert!((gain(2.0 * 2f32.sqrt(), 1.0, 0.2, 2.0) - 0.5).abs() < 1e-6);
        assert!(gain(40.0, 1.0, 0.2, 2.0) > 0.997);
        // No noise estimate (σ = 0): every change is real.
        assert_eq!(gain(1e-3, 0.0, 0.2, 2.0), 1.0);
        // NaN never blends in more than alpha.
        assert_eq!(gain(f32::NAN, 1.0, 0.2, 2.0), 0.2);
        let mut shown = vec![[Rgb::splat(1.0), Rgb::splat(1.0)]];
        let target = Display {
            irradiance: vec![[Rgb::splat(1.5), Rgb::splat(100.0)]],
            noise: vec![[1.0, 1.0]],
        };
        blend(&mut shown, &target, 0.2, 2.0);
        assert!((shown[0][0].x - 1.1).abs() < 1e-6, "{:?}", shown[0][0]);
        assert!(shown[0][1].x > 99.0, "{:?}", shown[0][1]);
    }
}
