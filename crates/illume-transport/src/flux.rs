//! Signed fixed-point photon power (flux), for accumulators that add and remove photons
//! and must return exactly to what they held.
//!
//! A [`Quanta`] is RGB power in whole quanta of `q` watts, as `i64` per channel. Adding
//! and subtracting integers is exact and order-independent, so an accumulator that adds
//! a set of photons and later subtracts the same photons (photon streaming's pool
//! evicting old impacts; selective photon tracing shooting a corrective photon with
//! negative energy along an old path, then with positive energy along the new one)
//! returns to its previous value bit for bit, after any number of updates: no drift.
//!
//! Arithmetic wraps (two's complement), so sums are exact whenever the true total fits
//! in `i64`, even if a partial sum overflowed along the way. Room: ±2⁶³ quanta per
//! channel, i.e. ≈ 5.5·10¹¹ photons each carrying 2²⁴ quanta (photon streaming's
//! quantum gives a photon of the scene's whole power 2²⁴ quanta).

use illume_core::Rgb;

/// RGB power in whole quanta (signed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Quanta(pub [i64; 3]);

impl Quanta {
    /// No power.
    pub const ZERO: Quanta = Quanta([0; 3]);

    /// `flux` \[W\] in quanta of `1 / inv_quantum` watts, each channel rounded to
    /// nearest (halves away from zero); NaN gives 0, values beyond ±2⁶³ quanta
    /// saturate.
    #[inline]
    pub fn from_flux(flux: Rgb, inv_quantum: f64) -> Quanta {
        Quanta([
            quantize(flux.x, inv_quantum),
            quantize(flux.y, inv_quantum),
            quantize(flux.z, inv_quantum),
        ])
    }

    /// The power in watts for quanta of `quantum_w` watts (`Σ quanta · quantum_w`).
    #[inline]
    pub fn to_flux(self, quantum_w: f64) -> Rgb {
        Rgb::new(
            (self.0[0] as f64 * quantum_w) as f32,
            (self.0[1] as f64 * quantum_w) as f32,
            (self.0[2] as f64 * quantum_w) as f32,
        )
    }

    /// Sum of the three channels.
    pub fn channel_sum(self) -> i64 {
        self.0[0].wrapping_add(self.0[1]).wrapping_add(self.0[2])
    }

    /// True when every channel is zero.
    pub fn is_zero(self) -> bool {
        self == Quanta::ZERO
    }
}

/// One channel of [`Quanta::from_flux`]: round to nearest, halves away from zero.
#[inline]
pub fn quantize(flux_w: f32, inv_quantum: f64) -> i64 {
    // Adding ½ and truncating rounds without `f64::round`, a libm call on the baseline
    // x86-64 target (three per photon impact). `as i64` saturates and maps NaN to 0.
    let x = flux_w as f64 * inv_quantum;
    if x >= 0.0 {
        (x + 0.5) as i64
    } else {
        -((0.5 - x) as i64)
    }
}

impl std::ops::Add for Quanta {
    type Output = Quanta;
    #[inline]
    fn add(self, o: Quanta) -> Quanta {
        Quanta([
            self.0[0].wrapping_add(o.0[0]),
            self.0[1].wrapping_add(o.0[1]),
            self.0[2].wrapping_add(o.0[2]),
        ])
    }
}

impl std::ops::Sub for Quanta {
    type Output = Quanta;
    #[inline]
    fn sub(self, o: Quanta) -> Quanta {
        Quanta([
            self.0[0].wrapping_sub(o.0[0]),
            self.0[1].wrapping_sub(o.0[1]),
            self.0[2].wrapping_sub(o.0[2]),
        ])
    }
}

impl std::ops::Neg for Quanta {
    type Output = Quanta;
    #[inline]
    fn neg(self) -> Quanta {
        Quanta::ZERO - self
    }
}

impl std::ops::AddAssign for Quanta {
    #[inline]
    fn add_assign(&mut self, o: Quanta) {
        *self = *self + o;
    }
}

impl std::ops::SubAssign for Quanta {
    #[inline]
    fn sub_assign(&mut self, o: Quanta) {
        *self = *self - o;
    }
}

impl std::iter::Sum for Quanta {
    fn sum<I: Iterator<Item = Quanta>>(iter: I) -> Quanta {
        iter.fold(Quanta::ZERO, |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{Pcg32, SampleStream};

    fn random_photons(n: usize, seed: u64) -> Vec<Rgb> {
        let mut rng = Pcg32::new(seed, 0);
        (0..n)
            .map(|_| {
                let [a, b] = rng.next_2d().to_array();
                Rgb::new(a * 3.0, b * 1e-3, (a - b) * 50.0)
            })
            .collect()
    }

    #[test]
    fn adding_then_subtracting_in_any_order_returns_exactly_to_zero() {
        let inv = 1e6;
        let photons: Vec<Quanta> = random_photons(10_000, 1)
            .into_iter()
            .map(|p| Quanta::from_flux(p, inv))
            .collect();
        let mut acc = Quanta::ZERO;
        for &p in &photons {
            acc += p;
        }
        let total = acc;
        // Remove in another order (every 7th first, then the rest backwards).
        for &p in photons.iter().step_by(7) {
            acc -= p;
        }
        for (i, &p) in photons.iter().enumerate().rev() {
            if i % 7 != 0 {
                acc -= p;
            }
        }
        assert!(acc.is_zero(), "{acc:?}");
        assert_eq!(photons.iter().copied().sum::<Quanta>(), total);
        assert_eq!(-total + total, Quanta::ZERO);
    }

    #[test]
    fn sums_match_float_sums_within_one_quantum_per_photon() {
        let q = 1e-4;
        let photons = random_photons(5_000, 2);
        let sum: Quanta = photons.iter().map(|&p| Quanta::from_flux(p, 1.0 / q)).sum();
        for c in 0..3 {
            let exact: f64 = photons.iter().map(|p| p.to_array()[c] as f64).sum();
            let got = sum.0[c] as f64 * q;
            assert!(
                (got - exact).abs() <= 0.5 * q * photons.len() as f64,
                "channel {c}: {got} vs {exact}"
            );
        }
        // Negative totals (the third channel is mostly negative here) convert back.
        let back = sum.to_flux(q);
        let exact: f64 = photons.iter().map(|p| p.z as f64).sum();
        assert!(exact < 0.0 && (back.z as f64 - exact).abs() < 1e-3 * exact.abs());
    }

    #[test]
    fn rounding_is_symmetric_and_nan_is_zero() {
        assert_eq!(quantize(2.5, 1.0), 3);
        assert_eq!(quantize(-2.5, 1.0), -3);
        assert_eq!(quantize(2.4, 1.0), 2);
        assert_eq!(quantize(-2.4, 1.0), -2);
        assert_eq!(quantize(f32::NAN, 1.0), 0);
        assert_eq!(quantize(f32::INFINITY, 1.0), i64::MAX);
        assert_eq!(quantize(f32::NEG_INFINITY, 1.0), -i64::MAX);
    }

    #[test]
    fn overflow_in_a_partial_sum_still_gives_the_exact_total() {
        let big = Quanta([i64::MAX - 10, 5, -5]);
        let mut acc = big;
        acc += Quanta([100, 0, 0]); // past i64::MAX: wraps
        acc -= Quanta([100, 0, 0]);
        assert_eq!(acc, big);
        acc -= big;
        assert!(acc.is_zero());
    }
}
