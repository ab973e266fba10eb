//! Reconstruction at run time (§3.1, Eq. 2, §4.2): the k temporal coefficients and the
//! mean interpolated between the keys around the clock time (linearly, or Catmull–Rom
//! beyond the paper), every texel rebuilt in O(k), clamped at 0, plus the sky image
//! scaled by s(t).

use crate::schedule::bracket;
use crate::settings::Interpolation;
use crate::state::Precomputed;
use illume_core::Rgb;
use rayon::prelude::*;

/// One PCA group (a channel, or all three joint) ready to reconstruct.
#[derive(Clone, Debug)]
pub(crate) struct Group {
    /// Mean per key (all keys; dark keys 0).
    pub(crate) mean: Vec<f32>,
    /// k × keys coefficients.
    pub(crate) temporal: Vec<f32>,
    /// k × rows projected images.
    pub(crate) images: Vec<f32>,
    /// Values per image.
    pub(crate) rows: usize,
}

/// Catmull–Rom weights of the four keys around α between keys `n` and `m = n + 1`,
/// spaced by their times (not their indices: adaptive keys are uneven): a cubic Hermite
/// segment whose tangents at `t_n` and `t_m` are the slopes `(P_m − P_{n−1})/(t_m −
/// t_{n−1})` and `(P_{m+1} − P_n)/(t_{m+1} − t_n)`, ends repeated (a one-sided slope).
/// It passes through the keys and reproduces any signal linear in time exactly.
pub(crate) fn catmull_rom(times: &[f64], n: usize, m: usize, alpha: f32) -> Vec<(usize, f32)> {
    let last = times.len().saturating_sub(1);
    let (p0, p3) = (n.saturating_sub(1), (m + 1).min(last));
    let h = times[m] - times[n];
    if m == n || h <= 0.0 {
        return vec![(n, 1.0)];
    }
    let t = alpha as f64;
    let (t2, t3) = (t * t, t * t * t);
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + t;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    // Tangent scale of each end: the segment's length over the span of its slope.
    let a = h / (times[m] - times[p0]);
    let b = h / (times[p3] - times[n]);
    vec![
        (p0, (-h10 * a) as f32),
        (n, (h00 - h11 * b) as f32),
        (m, (h01 + h10 * a) as f32),
        (p3, (h11 * b) as f32),
    ]
}

/// `cube`: texels are reconstructed in runs of this many (those some pixel reads).
pub(crate) const RUN: usize = 64;

impl Precomputed {
    /// Weights of the keys around clock time `hours`: (key index, weight) pairs.
    fn weights(&self, hours: f64) -> Vec<(usize, f32)> {
        let (n, m, alpha) = bracket(&self.times, hours);
        match self.settings.interpolation {
            Interpolation::Linear => vec![(n, 1.0 - alpha), (m, alpha)],
            Interpolation::Cubic => catmull_rom(&self.times, n, m, alpha),
        }
    }

    /// Each PCA group's mean and k coefficients at clock time `hours`, interpolated
    /// between the keys around it.
    fn blend(&self, hours: f64) -> Vec<(f32, Vec<f32>)> {
        let weights = self.weights(hours);
        let keys = self.times.len();
        let blend = |values: &[f32], offset: usize| -> f32 {
            weights.iter().map(|&(i, w)| w * values[offset + i]).sum()
        };
        self.groups
            .iter()
            .map(|g| {
                (
                    blend(&g.mean, 0),
                    (0..self.k).map(|c| blend(&g.temporal, c * keys)).collect(),
                )
            })
            .collect()
    }

    /// Channel `c` of texels `first..first + out.len()` before the clamp: the blended
    /// mean, then one multiply-add pass per component (vectorised for per-channel
    /// groups).
    fn accumulate(&self, c: usize, blended: &(f32, Vec<f32>), first: usize, out: &mut [f32]) {
        let group = &self.groups[if self.joint { 0 } else { c }];
        let (mean, coefficients) = blended;
        out.fill(*mean);
        for (i, coefficient) in coefficients.iter().enumerate() {
            let image = &group.images[i * group.rows..(i + 1) * group.rows];
            if self.joint {
                for (j, o) in out.iter_mut().enumerate() {
                    *o += image[3 * (first + j) + c] * coefficient;
                }
            } else {
                let src = &image[first..first + out.len()];
                for (o, x) in out.iter_mut().zip(src) {
                    *o += x * coefficient;
                }
            }
        }
    }

    /// [`Precomputed::reconstruct`] of the runs of [`RUN`] texels marked in `needed`,
    /// written into `out` (other texels left as they are).
    pub(crate) fn reconstruct_runs(
        &self,
        hours: f64,
        sky_scale: f32,
        needed: &[bool],
        out: &mut [Rgb],
    ) {
        let blended = self.blend(hours);
        out.par_chunks_mut(RUN)
            .zip(needed)
            .enumerate()
            .filter(|(_, (_, n))| **n)
            .for_each(|(run, (out, _))| {
                let first = run * RUN;
                let mut planes = [[0f32; RUN]; 3];
                for (c, plane) in planes.iter_mut().enumerate() {
                    let g = if self.joint { 0 } else { c };
                    self.accumulate(c, &blended[g], first, &mut plane[..out.len()]);
                }
                for (j, o) in out.iter_mut().enumerate() {
                    *o = Rgb::new(
                        planes[0][j].max(0.0),
                        planes[1][j].max(0.0),
                        planes[2][j].max(0.0),
                    ) + self.sky[first + j] * sky_scale;
                }
            });
    }

    /// The sun's indirect light at clock time `hours` plus the sky's whole light (direct
    /// and indirect) at scale `sky_scale`, one value per texel of the file's key image
    /// (screen: its pixels).
    pub fn reconstruct(&self, hours: f64, sky_scale: f32) -> Vec<Rgb> {
        let per_group = self.blend(hours);
        let pixels = self.width as usize * self.height as usize;
        // Channel planes, filled in cache-sized chunks: per chunk, mean then one
        // multiply-add pass per component (vectorised), then clamp at 0.
        const CHUNK: usize = 4096;
        let mut planes = vec![vec![0f32; pixels]; 3];
        for (c, plane) in planes.iter_mut().enumerate() {
            let g = if self.joint { 0 } else { c };
            plane
                .par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(chunk, out)| self.accumulate(c, &per_group[g], chunk * CHUNK, out));
        }
        (0..pixels)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|p| {
                Rgb::new(
                    planes[0][p].max(0.0),
                    planes[1][p].max(0.0),
                    planes[2][p].max(0.0),
                ) + self.sky[p] * sky_scale
            })
            .collect()
    }

    /// Every texel's value at `hours` (what [`Precomputed::reconstruct`] gives, to
    /// rounding): with linear interpolation, Eq. 2 literally, `(1 − α)·L_N + α·L_{N+1} +
    /// s·L_sky` from the two key images reconstructed once per key interval (each
    /// clamped at 0), so a frame costs a blend instead of k multiply-adds per texel;
    /// with cubic interpolation a whole reconstruction.
    pub(crate) fn values(&mut self, hours: f64, sky_scale: f32) -> Vec<Rgb> {
        if self.settings.interpolation != Interpolation::Linear {
            return self.reconstruct(hours, sky_scale);
        }
        let (n, m, alpha) = bracket(&self.times, hours);
        if self.pair.as_ref().is_none_or(|p| (p.0, p.1) != (n, m)) {
            let a = self.reconstruct(self.times[n], 0.0);
            let b = self.reconstruct(self.times[m], 0.0);
            self.pair = Some((n, m, a, b));
        }
        let (_, _, a, b) = self.pair.as_ref().expect("just filled");
        a.par_iter()
            .zip(b)
            .zip(&self.sky)
            .with_min_len(4096)
            .map(|((a, b), sky)| *a * (1.0 - alpha) + *b * alpha + *sky * sky_scale)
            .collect()
    }
}
