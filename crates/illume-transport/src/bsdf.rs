//! The Lambertian BSDF and Russian roulette.
//!
//! illume's materials are diffuse: f = ρ/π. Sampling is cosine-weighted about the
//! shading normal, so the path weight f·cosθ/pdf is exactly ρ.

use illume_core::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use illume_core::{Frame, Rgb, Vec2, Vec3};

/// A sampled outgoing direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Unit world direction.
    pub wi: Vec3,
    /// f·cosθ/pdf (= ρ for Lambert).
    pub weight: Rgb,
    /// Solid-angle pdf of `wi`.
    pub pdf: f32,
}

/// Cosine-weighted sample about `normal` (the side the light leaves to).
#[inline]
pub fn lambert_sample(albedo: Rgb, normal: Vec3, u: Vec2) -> BsdfSample {
    let local = cosine_hemisphere(u);
    let wi = Frame::from_normal(normal).to_world(local).normalize();
    BsdfSample {
        wi,
        weight: albedo,
        pdf: cosine_hemisphere_pdf(local.z),
    }
}

/// Solid-angle pdf of [`lambert_sample`] for `wi`.
#[inline]
pub fn lambert_pdf(normal: Vec3, wi: Vec3) -> f32 {
    cosine_hemisphere_pdf(normal.dot(wi))
}

/// Russian roulette: continue with probability `min(1, max channel of throughput)`;
/// returns the weight factor `1/p` for a survivor or `None` for termination.
/// Unbiased: E\[weight\] is unchanged.
#[inline]
pub fn russian_roulette(throughput: Rgb, u: f32) -> Option<f32> {
    let p = throughput.max_element().min(1.0);
    if p <= 0.0 || u >= p {
        None
    } else {
        Some(1.0 / p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{Pcg32, SampleStream};

    /// Pearson's chi-square test of cosine-weighted sampling over a (θ, φ) grid: the
    /// expected bin counts are the exact integrals of cosθ/π over each bin.
    #[test]
    fn cosine_sampling_passes_chi_square() {
        let (nt, np) = (10usize, 20usize);
        let n = 400_000u32;
        let normal = Vec3::new(0.3, 0.5, -0.81).normalize();
        let frame = Frame::from_normal(normal);
        let mut counts = vec![0f64; nt * np];
        let mut rng = Pcg32::new(11, 0);
        for _ in 0..n {
            let s = lambert_sample(Rgb::ONE, normal, rng.next_2d());
            let l = frame.to_local(s.wi);
            assert!((s.pdf - l.z.max(0.0) / std::f32::consts::PI).abs() < 1e-3);
            let theta = l.z.clamp(-1.0, 1.0).acos();
            let phi = l.y.atan2(l.x).rem_euclid(2.0 * std::f32::consts::PI);
            let it =
                ((theta / (std::f32::consts::FRAC_PI_2)) * nt as f32).min(nt as f32 - 1.0) as usize;
            let ip =
                ((phi / (2.0 * std::f32::consts::PI)) * np as f32).min(np as f32 - 1.0) as usize;
            counts[it * np + ip] += 1.0;
        }
        let mut chi2 = 0.0;
        for it in 0..nt {
            let t0 = it as f64 / nt as f64 * std::f64::consts::FRAC_PI_2;
            let t1 = (it + 1) as f64 / nt as f64 * std::f64::consts::FRAC_PI_2;
            // ∫∫ cosθ/π sinθ dθ dφ over the bin = (sin²θ1 − sin²θ0)/2 · (1/π) · (2π/np)
            let p = (t1.sin().powi(2) - t0.sin().powi(2)) / np as f64;
            for ip in 0..np {
                let e = p * n as f64;
                chi2 += (counts[it * np + ip] - e).powi(2) / e;
            }
        }
        // 199 degrees of freedom: the 99.9th percentile is ≈ 266.
        assert!(chi2 < 266.0, "chi2 = {chi2}");
    }

    #[test]
    fn russian_roulette_is_unbiased() {
        let mut rng = Pcg32::new(1, 1);
        let t = Rgb::new(0.3, 0.2, 0.1);
        let n = 1_000_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            if let Some(w) = russian_roulette(t, rng.next_1d()) {
                sum += w as f64;
            }
        }
        assert!((sum / n as f64 - 1.0).abs() < 0.01);
    }
}
