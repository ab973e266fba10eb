//! Index-addressable sample sources and the warps that turn uniform numbers into
//! directions and points.
//!
//! Every stochastic result in illume is a pure function of (seed, index, dimension):
//! a photon path `i` re-traced with the same [`SampleStream`] gives the same path, bit
//! for bit, whatever the thread count or order (selective photon tracing depends on it).
//!
//! * [`Pcg32`] — O'Neill's PCG-XSH-RR generator; `(seed, stream)` selects an independent
//!   sequence, so a path index maps to its own stream.
//! * [`HaltonStream`] — the Halton sequence at one index, walking the dimensions
//!   (prime bases 2, 3, 5, …), optionally digit-permuted per dimension. Permutation
//!   scrambling keeps the sequence's periodicity properties (Dmitriev et al. 2002, §4.2).
//!
//! PCG and Halton are written here rather than taken from `rand`: both are a few lines,
//! and the engine needs exact control over stream addressing and dimension order that a
//! general RNG API hides.

use crate::math::{PI, Vec2, Vec3};

/// A source of uniform numbers in `[0, 1)` consumed dimension by dimension.
pub trait SampleStream {
    /// Next number in `[0, 1)`.
    fn next_1d(&mut self) -> f32;
    /// Next two numbers in `[0, 1)²`.
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let a = self.next_1d();
        let b = self.next_1d();
        Vec2::new(a, b)
    }
}

/// Largest `f32` below 1.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// PCG-XSH-RR 32-bit generator (O'Neill 2014). `Pcg32::new(seed, stream)`: the same pair
/// always yields the same sequence; different `stream` values give independent sequences.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    const MULT: u64 = 6364136223846793005;

    /// Generator for `(seed, stream)`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut g = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        g.next_u32();
        g.state = g.state.wrapping_add(seed);
        g.next_u32();
        g
    }

    /// Next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform integer in `[0, n)` (n > 0), without modulo bias.
    pub fn next_below(&mut self, n: u32) -> u32 {
        let threshold = n.wrapping_neg() % n;
        loop {
            let r = self.next_u32();
            if r >= threshold {
                return r % n;
            }
        }
    }

    /// Uniform `f64` in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        ((hi | lo) as f64) * (1.0 / (1u64 << 53) as f64)
    }
}

impl SampleStream for Pcg32 {
    #[inline]
    fn next_1d(&mut self) -> f32 {
        ((self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)).min(ONE_MINUS_EPSILON)
    }
}

/// A 64-bit mix (SplitMix64 finaliser) for deriving seeds from indices.
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58476d1ce4e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d049bb133111eb);
    x ^ (x >> 31)
}

/// The first 64 primes: Halton bases for dimensions 0..64.
pub const PRIMES: [u32; 64] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
    101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163, 167, 173, 179, 181, 191, 193,
    197, 199, 211, 223, 227, 229, 233, 239, 241, 251, 257, 263, 269, 271, 277, 281, 283, 293, 307,
    311,
];

/// Radical inverse of `index` in `base` (the Halton coordinate), in `f64`.
pub fn radical_inverse(base: u32, mut index: u64) -> f64 {
    let b = base as u64;
    let inv_base = 1.0 / base as f64;
    let mut inv = inv_base;
    let mut reversed = 0.0f64;
    while index > 0 {
        let digit = index % b;
        reversed += digit as f64 * inv;
        inv *= inv_base;
        index /= b;
    }
    reversed
}

/// Radical inverse with every digit (including the infinite tail of zeros, to the
/// precision of `f64`) mapped through `perm` (a permutation of `0..base`).
pub fn scrambled_radical_inverse(base: u32, mut index: u64, perm: &[u16]) -> f64 {
    let b = base as u64;
    let inv_base = 1.0 / base as f64;
    let mut inv = inv_base;
    let mut reversed = 0.0f64;
    // Enough digits for f64 precision in this base.
    let digits = (53.0 / (base as f64).log2()).ceil() as usize;
    for _ in 0..digits {
        let digit = index % b;
        reversed += perm[digit as usize] as f64 * inv;
        inv *= inv_base;
        index /= b;
    }
    reversed.min(1.0 - f64::EPSILON)
}

/// Per-dimension digit permutations for scrambled Halton, derived from a seed.
#[derive(Clone, Debug)]
pub struct HaltonScramble {
    perms: Vec<Vec<u16>>,
}

impl HaltonScramble {
    /// Random digit permutations (Fisher–Yates from PCG) for all 64 dimensions.
    pub fn new(seed: u64) -> Self {
        let perms = PRIMES
            .iter()
            .enumerate()
            .map(|(d, &b)| {
                let mut rng = Pcg32::new(seed, d as u64);
                let mut p: Vec<u16> = (0..b as u16).collect();
                for i in (1..p.len()).rev() {
                    let j = rng.next_below(i as u32 + 1) as usize;
                    p.swap(i, j);
                }
                p
            })
            .collect();
        Self { perms }
    }
}

/// The Halton point with index `index`, consumed one dimension at a time (dimension `d`
/// uses base `PRIMES[d]`). Past 64 dimensions it continues with a PCG stream seeded by
/// the index, so long photon paths never run out of numbers (those tail dimensions are
/// random, not quasi-random).
#[derive(Clone, Debug)]
pub struct HaltonStream<'a> {
    index: u64,
    dim: usize,
    scramble: Option<&'a HaltonScramble>,
    tail: Option<Pcg32>,
}

impl<'a> HaltonStream<'a> {
    /// Stream for point `index`, unscrambled.
    pub fn new(index: u64) -> Self {
        Self {
            index,
            dim: 0,
            scramble: None,
            tail: None,
        }
    }

    /// Stream for point `index` with digit permutations.
    pub fn scrambled(index: u64, scramble: &'a HaltonScramble) -> Self {
        Self {
            index,
            dim: 0,
            scramble: Some(scramble),
            tail: None,
        }
    }

    /// The index this stream walks.
    pub fn index(&self) -> u64 {
        self.index
    }

    /// The next dimension to be consumed.
    pub fn dimension(&self) -> usize {
        self.dim
    }
}

impl HaltonStream<'_> {
    /// The next dimension's value in `[0, 1)` at `f64` precision (what
    /// [`SampleStream::next_1d`] rounds to `f32`): the first digits of the radical
    /// inverse are exact, so a technique can tell which `base^-k` cell the point lies in
    /// (selective photon tracing's light choice).
    pub fn next_f64(&mut self) -> f64 {
        let d = self.dim;
        self.dim += 1;
        if d < PRIMES.len() {
            match self.scramble {
                Some(s) => scrambled_radical_inverse(PRIMES[d], self.index, &s.perms[d]),
                None => radical_inverse(PRIMES[d], self.index),
            }
        } else {
            let index = self.index;
            self.tail
                .get_or_insert_with(|| Pcg32::new(mix64(index), 0x48616c74))
                .next_1d() as f64
        }
    }
}

impl SampleStream for HaltonStream<'_> {
    fn next_1d(&mut self) -> f32 {
        (self.next_f64() as f32).min(ONE_MINUS_EPSILON)
    }
}

/// Point `i` of the R₂ low-discrepancy sequence in [0, 1)² (Roberts 2018: the additive
/// recurrence on 1/φ₂ and 1/φ₂², φ₂ the plastic number, x³ = x + 1), started at the
/// centre (0.5, 0.5) for `i = 0`. Any run of n consecutive points covers the square
/// evenly (a discrepancy of order 1/n), with no period: the pixel offsets of a
/// progressive refinement that may stop after any frame.
pub fn r2_point(i: u32) -> Vec2 {
    const A: [f64; 2] = [0.754_877_666_246_692_8, 0.569_840_290_998_053_3];
    let f = |a: f64| (0.5 + a * f64::from(i)).fract() as f32;
    Vec2::new(f(A[0]), f(A[1]))
}

/// Cosine-weighted direction on the hemisphere around +Z; pdf = cosθ/π.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Pdf (per steradian) of [`cosine_hemisphere`] for local direction `w`.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * crate::math::INV_PI
}

/// Shirley–Chiu concentric map from the square to the unit disk.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = u * 2.0 - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Uniform direction on the unit sphere; pdf = 1/(4π).
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics `(b1, b2)` on a triangle (Heitz 2019 low-distortion map); the
/// point is `(1 − b1 − b2)·p0 + b1·p1 + b2·p2`.
#[inline]
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    let (b0, b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    Vec2::new(b1, 1.0 - b0 - b1)
}

/// Discrete distribution over weights, sampled in O(1) by Walker's alias method.
#[derive(Clone, Debug, Default)]
pub struct AliasTable {
    prob: Vec<f32>,
    alias: Vec<u32>,
    pmf: Vec<f32>,
    total: f64,
}

/// The sum of `weights` in f64 when a table can be built over them: some, all finite and
/// non-negative, with a positive finite sum.
fn weights_total(weights: &[f32]) -> Option<f64> {
    let total: f64 = weights.iter().map(|&w| w as f64).sum();
    if weights.is_empty()
        || total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || !total.is_finite()
        || weights.iter().any(|w| *w < 0.0)
    {
        return None;
    }
    Some(total)
}

impl AliasTable {
    /// Table over non-negative `weights`; `None` when they sum to zero or any is not finite.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let total = weights_total(weights)?;
        let n = weights.len();
        let pmf: Vec<f32> = weights.iter().map(|&w| (w as f64 / total) as f32).collect();
        let mut scaled: Vec<f64> = weights
            .iter()
            .map(|&w| w as f64 / total * n as f64)
            .collect();
        let mut prob = vec![1.0f32; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) =
            (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
            prob[s] = scaled[s] as f32;
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        Some(Self {
            prob,
            alias,
            pmf,
            total,
        })
    }

    /// [`AliasTable::new`] built in place from owned weights, for tables of tens of
    /// millions of entries (an environment map's texels): the weights' buffer becomes the
    /// probabilities, and there are no work lists or f64 copies, so building peaks at the
    /// table's own 12 bytes an entry where `new` needs 32 (issue 38). The same
    /// distribution as `new`, its entries paired in another order: Vose's method with
    /// two cursors sweeping the entries instead of stacks of small and large ones. The
    /// current large entry's remaining mass is kept in f64 (from its weight, as `new`
    /// computes it) and decreased by what each small entry gives it as stored (`1 − prob`
    /// in f32), so the table's implied probabilities add up as `new`'s do.
    pub fn from_vec(mut weights: Vec<f32>) -> Option<Self> {
        let total = weights_total(&weights)?;
        let n = weights.len();
        // Scaled weights w·n/total: < 1 small, ≥ 1 large; a small entry's is final.
        let mut prob: Vec<f32> = weights
            .iter()
            .map(|&w| (w as f64 / total * n as f64) as f32)
            .collect();
        // A large entry's mass in f64 from its weight, as `new` has it (from its f32
        // `prob`, the rounding of equal large weights would add up on the last one).
        let scaled = |w: f32| w as f64 / total * n as f64;
        let mut alias: Vec<u32> = (0..n as u32).collect();
        // The next small (or large) entry at or after `from`.
        let next =
            |prob: &[f32], from: usize, small: bool| (from..n).find(|&i| (prob[i] < 1.0) == small);
        // Every small entry before `small_from` is paired or is `s`; every large one
        // before `large_from` is used up or is `l`.
        let mut s = next(&prob, 0, true);
        let mut small_from = s.map_or(n, |i| i + 1);
        let mut l = next(&prob, 0, false);
        let mut large_from = l.map_or(n, |i| i + 1);
        let mut mass = l.map_or(0.0, |i| scaled(weights[i]));
        while let (Some(si), Some(li)) = (s, l) {
            alias[si] = li as u32;
            mass -= 1.0 - prob[si] as f64;
            if mass < 1.0 {
                // The large entry is small now: its probability is final, and it gives
                // the rest of its column to the next large entry. Paired next if the
                // small cursor has passed it, found by that cursor otherwise.
                prob[li] = mass as f32;
                l = next(&prob, large_from, false);
                large_from = l.map_or(n, |i| i + 1);
                mass = l.map_or(0.0, |i| scaled(weights[i]));
                if li < small_from {
                    s = Some(li);
                    continue;
                }
            }
            s = next(&prob, small_from, true);
            small_from = s.map_or(n, |i| i + 1);
        }
        // Large entries left keep their whole column; so do small ones left by rounding
        // (their alias is themselves).
        for p in &mut prob {
            *p = p.min(1.0);
        }
        for w in &mut weights {
            *w = (*w as f64 / total) as f32;
        }
        Some(Self {
            prob,
            alias,
            pmf: weights,
            total,
        })
    }

    /// Index drawn with probability proportional to its weight, and that probability.
    /// `u` in `[0, 1)`.
    ///
    /// One f32 holds 24 random bits, shared by the column and the coin: exact enough for
    /// light lists, not for tables of millions of entries, where the coin is left with
    /// a few bits (1/8 steps at 2²¹ entries) and above 2²⁴ entries some columns are never
    /// drawn. Those use [`AliasTable::sample_fine`].
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let n = self.prob.len();
        let x = u * n as f32;
        let i = (x as usize).min(n - 1);
        let frac = x - i as f32;
        let idx = if frac < self.prob[i] {
            i
        } else {
            self.alias[i] as usize
        };
        (idx, self.pmf[idx])
    }

    /// [`AliasTable::sample`] for tables of millions of entries (an environment map's
    /// texels): the index is drawn from a 48-bit uniform made of `u.x` and `u.y` (24
    /// bits each, as [`Pcg32`]'s `next_1d` gives them), so every column is drawn with its
    /// share and the coin keeps 48 − log₂ n bits. Also returns what is left of the
    /// coin's uniform, rescaled to `[0, 1)` and independent of the index, so that a
    /// caller needs no third number (an environment map places its point in the texel
    /// with it).
    #[inline]
    pub fn sample_fine(&self, u: Vec2) -> (usize, f32, f32) {
        let n = self.prob.len();
        let x = (u.x as f64 + u.y as f64 * (1.0 / (1u32 << 24) as f64)) * n as f64;
        let i = (x as usize).min(n - 1);
        let frac = (x - i as f64).clamp(0.0, 1.0);
        let p = self.prob[i] as f64;
        let (idx, rest) = if frac < p {
            (i, frac / p)
        } else {
            (self.alias[i] as usize, (frac - p) / (1.0 - p))
        };
        (idx, self.pmf[idx], (rest as f32).min(ONE_MINUS_EPSILON))
    }

    /// Probability of index `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Sum of the weights the table was built from.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True when the table has no entry.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_streams_are_reproducible_and_distinct() {
        let a: Vec<u32> = {
            let mut g = Pcg32::new(1, 2);
            (0..8).map(|_| g.next_u32()).collect()
        };
        let b: Vec<u32> = {
            let mut g = Pcg32::new(1, 2);
            (0..8).map(|_| g.next_u32()).collect()
        };
        let c: Vec<u32> = {
            let mut g = Pcg32::new(1, 3);
            (0..8).map(|_| g.next_u32()).collect()
        };
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn pcg_matches_reference_vector() {
        // Reference output of pcg32_random_r from the PCG C library demo (seed 42, stream 54).
        let mut g = Pcg32::new(42, 54);
        let got: Vec<u32> = (0..6).map(|_| g.next_u32()).collect();
        assert_eq!(
            got,
            [
                0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e
            ]
        );
    }

    #[test]
    fn radical_inverse_known_values() {
        assert_eq!(radical_inverse(2, 1), 0.5);
        assert_eq!(radical_inverse(2, 2), 0.25);
        assert_eq!(radical_inverse(2, 3), 0.75);
        assert!((radical_inverse(3, 1) - 1.0 / 3.0).abs() < 1e-15);
        assert!((radical_inverse(3, 5) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-15);
    }

    #[test]
    fn halton_stream_same_index_same_numbers() {
        let s = HaltonScramble::new(9);
        let a: Vec<f32> = {
            let mut h = HaltonStream::scrambled(1234, &s);
            (0..80).map(|_| h.next_1d()).collect()
        };
        let b: Vec<f32> = {
            let mut h = HaltonStream::scrambled(1234, &s);
            (0..80).map(|_| h.next_1d()).collect()
        };
        assert_eq!(a, b);
        assert!(a.iter().all(|&x| (0.0..1.0).contains(&x)));
    }

    #[test]
    fn halton_first_dimension_is_stratified() {
        // Any 2^k consecutive indices of base-2 radical inverse hit each of the 2^k strata once.
        let mut seen = [false; 16];
        for i in 16..32 {
            let v = radical_inverse(2, i);
            seen[(v * 16.0) as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn alias_table_matches_weights() {
        let w = [1.0, 0.0, 3.0, 4.0];
        let t = AliasTable::new(&w).unwrap();
        let mut counts = [0u32; 4];
        let n = 200_000;
        let mut g = Pcg32::new(3, 0);
        for _ in 0..n {
            counts[t.sample(g.next_1d()).0] += 1;
        }
        for i in 0..4 {
            let expected = w[i] / 8.0;
            assert!(
                (counts[i] as f32 / n as f32 - expected).abs() < 0.005,
                "bin {i}"
            );
            assert!((t.pmf(i) - expected).abs() < 1e-6);
        }
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[f32::NAN]).is_none());
    }

    /// A table of millions of entries (an environment map's size), light and heavy
    /// entries alternating: drawn with one f32, the coin has 3·2²⁰/2²⁴ = 3/16 steps and the
    /// light entries (scaled weight ≈ 0.095) are drawn about twice too often; drawn with
    /// two, each class within sampling noise of its probability, and the leftover uniform
    /// is uniform in each class.
    #[test]
    fn a_table_of_millions_is_drawn_in_proportion_with_two_numbers() {
        let n = 3 << 20;
        let w: Vec<f32> = (0..n)
            .map(|i| if i % 2 == 0 { 1.0 } else { 0.05 })
            .collect();
        let t = AliasTable::new(&w).unwrap();
        let light: f64 = 0.05 / 1.05;
        let draws = 2_000_000;
        let mut g = Pcg32::new(11, 0);
        let (mut coarse, mut fine) = (0u32, 0u32);
        let mut rest_mean = [0f64; 2];
        let mut rest_count = [0u32; 2];
        for _ in 0..draws {
            coarse += (t.sample(g.next_1d()).0 % 2) as u32;
            let (i, pmf, rest) = t.sample_fine(g.next_2d());
            assert_eq!(pmf, t.pmf(i));
            assert!((0.0..1.0).contains(&rest));
            fine += (i % 2) as u32;
            rest_mean[i % 2] += rest as f64;
            rest_count[i % 2] += 1;
        }
        // 4 standard deviations of a binomial share.
        let tolerance = 4.0 * (light * (1.0 - light) / draws as f64).sqrt();
        let share = |k: u32| k as f64 / draws as f64;
        assert!(
            (share(fine) - light).abs() < tolerance,
            "two numbers: light share {} against {light}",
            share(fine)
        );
        assert!(
            share(coarse) > 1.5 * light,
            "one number: light share {} (the coin's steps are what this test must see)",
            share(coarse)
        );
        for k in 0..2 {
            let mean = rest_mean[k] / rest_count[k] as f64;
            let sd = (1.0 / 12.0 / rest_count[k] as f64).sqrt();
            assert!(
                (mean - 0.5).abs() < 4.0 * sd,
                "class {k}: leftover mean {mean}"
            );
        }
    }

    /// The probability of each index the table implies (its own column's `prob` plus what
    /// the columns aliased to it give), summed exactly in f64.
    fn implied(t: &AliasTable) -> Vec<f64> {
        let n = t.prob.len();
        let mut q = vec![0f64; n];
        for i in 0..n {
            let p = t.prob[i] as f64;
            assert!((0.0..=1.0).contains(&p), "prob[{i}] = {p}");
            q[i] += p / n as f64;
            q[t.alias[i] as usize] += (1.0 - p) / n as f64;
        }
        q
    }

    #[test]
    fn both_alias_builders_imply_the_weights_distribution() {
        let mut g = Pcg32::new(7, 1);
        let random: Vec<f32> = (0..20_000)
            .map(|i| if i % 7 == 0 { 0.0 } else { g.next_1d() * 10.0 })
            .collect();
        // One entry holding almost everything: one large column fed by every other.
        let mut spike = vec![1e-3f32; 50_000];
        spike[31_337] = 1e6;
        // Many large entries among many tiny ones, the large ones late.
        let late: Vec<f32> = (0..30_000)
            .map(|i| if i > 29_000 { 100.0 } else { 0.01 })
            .collect();
        for (name, w) in [
            ("random", random),
            ("spike", spike),
            ("late", late),
            ("equal", vec![2.5; 1000]),
            ("one", vec![3.0]),
        ] {
            let total: f64 = w.iter().map(|&x| x as f64).sum();
            for (builder, t) in [
                ("new", AliasTable::new(&w).unwrap()),
                ("from_vec", AliasTable::from_vec(w.clone()).unwrap()),
            ] {
                assert_eq!((t.len(), t.total()), (w.len(), total), "{name} {builder}");
                let q = implied(&t);
                let mut variation = 0.0;
                for (i, (&qi, &wi)) in q.iter().zip(&w).enumerate() {
                    let want = wi as f64 / total;
                    assert!(
                        (qi - want).abs() <= 1e-5 * want.max(1.0 / w.len() as f64),
                        "{name} {builder}: index {i} has {qi}, weight gives {want}"
                    );
                    assert!((t.pmf(i) as f64 - want).abs() <= 1e-6 * want.max(1e-30));
                    variation += (qi - want).abs();
                }
                assert!(
                    variation < 1e-5,
                    "{name} {builder}: total variation {variation}"
                );
            }
        }
        assert!(AliasTable::from_vec(vec![0.0, 0.0]).is_none());
        assert!(AliasTable::from_vec(vec![1.0, f32::NAN]).is_none());
        assert!(AliasTable::from_vec(vec![1.0, -1.0]).is_none());
        assert!(AliasTable::from_vec(Vec::new()).is_none());
    }

    #[test]
    fn uniform_triangle_stays_inside() {
        let mut g = Pcg32::new(5, 5);
        for _ in 0..10000 {
            let b = uniform_triangle(g.next_2d());
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }
}
