//! PCA of the key images (Bahnsen et al. §3.2, Fig. 5, Fig. 7).
//!
//! The data are P samples (one per texel and channel) of T dimensions (one per non-dark
//! key): the paper's 480 000 vectors of 180 dimensions. Samples are centred by the mean
//! over texels of each key (a T-vector, interpolated in time at run time like the
//! coefficients), the T×T covariance `YᵀY / P` is accumulated in row blocks (so a large
//! atlas never becomes one P×T matrix copy), and its self-adjoint eigen decomposition
//! gives T temporal eigenvectors. The first k are kept with their k projected images
//! `Y·eᵢ` (P values each); key t is restored as `mean(t) + Σᵢ imageᵢ · eᵢ(t)`.
//!
//! Why covariance + eigen and not an SVD of the tall matrix: faer 0.24's f32 `thin_svd` and
//! `qr` were measured wrong on tall matrices (issue 12), f32 covariance +
//! `self_adjoint_eigen` was right, and the T×T problem is tiny. Blocks are multiplied in
//! f32 (or f64, [`Precision`]) and summed in f64; the eigen problem is solved in f64.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par, Side};
use rayon::prelude::*;

/// Rows per covariance block: 16 384 rows × 288 keys × 4 bytes = 19 MB.
pub const BLOCK_ROWS: usize = 16_384;

/// Arithmetic of the covariance blocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// f32 products, f64 sums of blocks (default; as accurate as f64 at the paper's size,
    /// see the tests).
    F32,
    /// f64 throughout (the check).
    F64,
}

/// How many components to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Components {
    /// Exactly k (at most T).
    Fixed(usize),
    /// The fewest that capture this fraction of the variance (0 < v ≤ 1), at most `max`.
    VarianceTarget {
        /// Fraction of Σλ to capture.
        target: f64,
        /// Upper bound on k.
        max: usize,
    },
}

/// Why the PCA cannot run.
#[derive(Debug, thiserror::Error)]
pub enum PcaError {
    /// No keys, or keys of zero length.
    #[error("PCA needs at least one key of at least one value (got {keys} keys of {rows} values)")]
    Empty {
        /// Number of keys.
        keys: usize,
        /// Values per key.
        rows: usize,
    },
    /// Keys of different lengths.
    #[error("PCA key {key} has {got} values, key 0 has {expected}")]
    Ragged {
        /// The key.
        key: usize,
        /// Its length.
        got: usize,
        /// Key 0's length.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("PCA key {key} has a non-finite value at {index}")]
    NonFinite {
        /// The key.
        key: usize,
        /// The index in it.
        index: usize,
    },
    /// The eigen solver did not converge.
    #[error("PCA eigen decomposition of the {0}×{0} covariance did not converge")]
    Eigen(usize),
}

/// A fitted basis: what the file stores per channel group.
#[derive(Clone, Debug, PartialEq)]
pub struct PcaBasis {
    /// Values per key (P).
    pub rows: usize,
    /// Number of keys (T).
    pub keys: usize,
    /// Mean over rows of each key (T values).
    pub mean: Vec<f32>,
    /// All T eigenvalues of `YᵀY / P`, largest first.
    pub eigenvalues: Vec<f64>,
    /// The k kept temporal eigenvectors, eigenvector i at `[i·T .. (i+1)·T]`.
    pub temporal: Vec<f32>,
    /// The k projected images, image i at `[i·P .. (i+1)·P]`.
    pub images: Vec<f32>,
}

impl PcaBasis {
    /// Kept components k.
    pub fn components(&self) -> usize {
        self.temporal.len() / self.keys.max(1)
    }

    /// Fraction of the variance captured by the first `k` eigenvalues (Fig. 5):
    /// `Σ_{i<k} λᵢ / Σ λᵢ` (1 when the data have no variance).
    pub fn variance_captured(&self, k: usize) -> f64 {
        variance_captured(&self.eigenvalues, k)
    }

    /// Temporal coefficient of component `i` at key `t`.
    pub fn coefficient(&self, i: usize, t: usize) -> f32 {
        self.temporal[i * self.keys + t]
    }

    /// Projected image of component `i`.
    pub fn image(&self, i: usize) -> &[f32] {
        &self.images[i * self.rows..(i + 1) * self.rows]
    }

    /// Restores row `row` from a mean and k coefficients (interpolated or not):
    /// `mean + Σᵢ imageᵢ[row] · cᵢ`, O(k).
    #[inline]
    pub fn value(&self, row: usize, mean: f32, coefficients: &[f32]) -> f32 {
        let mut v = mean;
        for (i, c) in coefficients.iter().enumerate() {
            v += self.images[i * self.rows + row] * c;
        }
        v
    }

    /// Restores the whole of key `t` (unclamped), for checks and `info --dump`.
    pub fn reconstruct_key(&self, t: usize) -> Vec<f32> {
        let coefficients: Vec<f32> = (0..self.components())
            .map(|i| self.coefficient(i, t))
            .collect();
        (0..self.rows)
            .into_par_iter()
            .map(|r| self.value(r, self.mean[t], &coefficients))
            .collect()
    }
}

/// `Σ_{i<k} λᵢ / Σ λᵢ` of eigenvalues sorted largest first (negative rounding clamped).
pub fn variance_captured(eigenvalues: &[f64], k: usize) -> f64 {
    let total: f64 = eigenvalues.iter().map(|l| l.max(0.0)).sum();
    if total <= 0.0 {
        return 1.0;
    }
    eigenvalues.iter().take(k).map(|l| l.max(0.0)).sum::<f64>() / total
}

/// Fits the basis to `keys` (T slices of P values each).
pub fn fit(
    keys: &[&[f32]],
    components: Components,
    precision: Precision,
) -> Result<PcaBasis, PcaError> {
    let t_count = keys.len();
    let rows = keys.first().map_or(0, |k| k.len());
    if t_count == 0 || rows == 0 {
        return Err(PcaError::Empty {
            keys: t_count,
            rows,
        });
    }
    for (key, k) in keys.iter().enumerate() {
        if k.len() != rows {
            return Err(PcaError::Ragged {
                key,
                got: k.len(),
                expected: rows,
            });
        }
        if let Some(index) = k.iter().position(|v| !v.is_finite()) {
            return Err(PcaError::NonFinite { key, index });
        }
    }
    // Means per key, summed in f64.
    let mean: Vec<f32> = keys
        .par_iter()
        .map(|k| (k.iter().map(|&v| v as f64).sum::<f64>() / rows as f64) as f32)
        .collect();

    // Covariance YᵀY accumulated over row blocks.
    let blocks: Vec<(usize, usize)> = (0..rows)
        .step_by(BLOCK_ROWS)
        .map(|r0| (r0, (r0 + BLOCK_ROWS).min(rows)))
        .collect();
    // Block products in parallel, summed in block order: the same bits on any machine
    // and thread count (merged shards must equal the unsharded file).
    let products: Vec<Mat<f64>> = blocks
        .par_iter()
        .map(|&(r0, r1)| block_covariance(keys, &mean, r0, r1, precision))
        .collect();
    let mut covariance = Mat::<f64>::zeros(t_count, t_count);
    for b in &products {
        covariance += b;
    }
    let covariance = Mat::<f64>::from_fn(t_count, t_count, |i, j| covariance[(i, j)] / rows as f64);
    let eigen = covariance
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| PcaError::Eigen(t_count))?;
    let s = eigen.S().column_vector();
    let u = eigen.U();
    // Largest first.
    let order: Vec<usize> = (0..t_count).rev().collect();
    let eigenvalues: Vec<f64> = order.iter().map(|&i| s[i]).collect();
    let k = match components {
        Components::Fixed(k) => k.min(t_count),
        Components::VarianceTarget { target, max } => {
            let max = max.min(t_count);
            (1..=max)
                .find(|&k| variance_captured(&eigenvalues, k) >= target)
                .unwrap_or(max)
        }
    };
    let mut temporal = vec![0f32; k * t_count];
    for (i, &col) in order.iter().take(k).enumerate() {
        // A deterministic sign: the largest-magnitude entry is positive.
        let mut sign = 1.0;
        let mut best = 0.0;
        for t in 0..t_count {
            if u[(t, col)].abs() > best {
                best = u[(t, col)].abs();
                sign = u[(t, col)].signum();
            }
        }
        for t in 0..t_count {
            temporal[i * t_count + t] = (sign * u[(t, col)]) as f32;
        }
    }
    // Projected images: imageᵢ[r] = Σ_t (x_t[r] − mean_t) eᵢ(t), in f64 per row.
    let mut images = vec![0f32; k * rows];
    if k > 0 {
        let columns: Vec<Vec<f32>> = (0..k)
            .into_par_iter()
            .map(|i| {
                let e = &temporal[i * t_count..(i + 1) * t_count];
                (0..rows)
                    .map(|r| {
                        let mut acc = 0f64;
                        for t in 0..t_count {
                            acc += (keys[t][r] - mean[t]) as f64 * e[t] as f64;
                        }
                        acc as f32
                    })
                    .collect()
            })
            .collect();
        for (i, c) in columns.into_iter().enumerate() {
            images[i * rows..(i + 1) * rows].copy_from_slice(&c);
        }
    }
    Ok(PcaBasis {
        rows,
        keys: t_count,
        mean,
        eigenvalues,
        temporal,
        images,
    })
}

/// `Y_bᵀ Y_b` of rows `r0..r1`, centred, in the chosen precision, returned in f64.
fn block_covariance(
    keys: &[&[f32]],
    mean: &[f32],
    r0: usize,
    r1: usize,
    precision: Precision,
) -> Mat<f64> {
    let t = keys.len();
    let n = r1 - r0;
    match precision {
        Precision::F32 => {
            let y = Mat::<f32>::from_fn(n, t, |i, j| keys[j][r0 + i] - mean[j]);
            let mut c = Mat::<f32>::zeros(t, t);
            matmul(
                c.as_mut(),
                Accum::Replace,
                y.transpose(),
                y.as_ref(),
                1.0f32,
                Par::Seq,
            );
            Mat::<f64>::from_fn(t, t, |i, j| c[(i, j)] as f64)
        }
        Precision::F64 => {
            let y = Mat::<f64>::from_fn(n, t, |i, j| (keys[j][r0 + i] - mean[j]) as f64);
            let mut c = Mat::<f64>::zeros(t, t);
            matmul(
                c.as_mut(),
                Accum::Replace,
                y.transpose(),
                y.as_ref(),
                1.0f64,
                Par::Seq,
            );
            c
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Orthonormal DCT-II vector `i ≥ 1` of length n (orthogonal to the constant).
    fn dct(i: usize, n: usize) -> Vec<f64> {
        (0..n)
            .map(|p| {
                (2.0 / n as f64).sqrt()
                    * (std::f64::consts::PI * i as f64 * (p as f64 + 0.5) / n as f64).cos()
            })
            .collect()
    }

    /// X = key means + U S Vᵀ with U ⟂ 1 (so the centring removes exactly the means).
    fn low_rank(rows: usize, keys: usize, singular: &[f64]) -> Vec<Vec<f32>> {
        let us: Vec<Vec<f64>> = (0..singular.len()).map(|i| dct(i + 1, rows)).collect();
        let vs: Vec<Vec<f64>> = (0..singular.len()).map(|i| dct(i + 1, keys)).collect();
        (0..keys)
            .map(|t| {
                (0..rows)
                    .map(|r| {
                        let mut v = 1.0 + 0.1 * t as f64;
                        for (i, s) in singular.iter().enumerate() {
                            v += s * us[i][r] * vs[i][t];
                        }
                        v as f32
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn rank_r_matrix_is_recovered_to_f32_rounding() {
        let singular = [40.0, 20.0, 5.0, 1.0];
        let keys = low_rank(3000, 24, &singular);
        let refs: Vec<&[f32]> = keys.iter().map(|k| k.as_slice()).collect();
        let basis = fit(&refs, Components::Fixed(10), Precision::F32).unwrap();
        assert_eq!(basis.components(), 10);
        let max = keys.iter().flatten().fold(0f32, |m, v| m.max(v.abs()));
        for (t, key) in keys.iter().enumerate() {
            let restored = basis.reconstruct_key(t);
            let err = key
                .iter()
                .zip(&restored)
                .fold(0f32, |m, (a, b)| m.max((a - b).abs()));
            assert!(err < 1e-5 * max.max(1.0), "key {t}: error {err}");
        }
    }

    #[test]
    fn eigenvalues_and_variance_match_hand_set_singular_values() {
        let singular = [30.0, 10.0, 3.0, 1.0, 0.5];
        let rows = 2000;
        let keys = low_rank(rows, 16, &singular);
        let refs: Vec<&[f32]> = keys.iter().map(|k| k.as_slice()).collect();
        let basis = fit(&refs, Components::Fixed(3), Precision::F32).unwrap();
        let expected: Vec<f64> = singular.iter().map(|s| s * s / rows as f64).collect();
        for (i, e) in expected.iter().enumerate() {
            let got = basis.eigenvalues[i];
            assert!((got - e).abs() < 1e-4 * expected[0], "λ{i}: {got} vs {e}");
        }
        for l in &basis.eigenvalues[singular.len()..] {
            assert!(l.abs() < 1e-5 * expected[0], "{l}");
        }
        let total: f64 = expected.iter().sum();
        let want = expected[..3].iter().sum::<f64>() / total;
        assert!((basis.variance_captured(3) - want).abs() < 1e-5);
        // Choosing k by a variance target.
        let target = fit(
            &refs,
            Components::VarianceTarget {
                target: 0.99,
                max: 10,
            },
            Precision::F32,
        )
        .unwrap();
        let k_expected = (1..=5)
            .find(|&k| expected[..k].iter().sum::<f64>() / total >= 0.99)
            .unwrap();
        assert_eq!(target.components(), k_expected);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            fit(&[], Components::Fixed(1), Precision::F32),
            Err(PcaError::Empty { .. })
        ));
        let a = [1.0f32, 2.0];
        let b = [1.0f32];
        assert!(matches!(
            fit(&[&a, &b], Components::Fixed(1), Precision::F32),
            Err(PcaError::Ragged { key: 1, .. })
        ));
        let c = [1.0f32, f32::NAN];
        assert!(matches!(
            fit(&[&a, &c], Components::Fixed(1), Precision::F32),
            Err(PcaError::NonFinite { key: 1, index: 1 })
        ));
    }
}
