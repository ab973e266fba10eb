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
//! `qr` were measured wrong on tall matrices (issue 12), f32 covariance + a symmetric
//! eigen solver was right, and the T×T problem is tiny. Blocks are multiplied in f32 (or
//! f64, [`Precision`]) and summed in f64; the eigen problem is solved in f64.
//!
//! Memory (issue 38): the block products use `matrixmultiply`, whose packing buffer is
//! fixed by compile-time block sizes (about 1 MiB a call), and the T×T eigen problem is
//! solved here ([`symmetric_eigen`]: Householder tridiagonalisation and implicit QL, the
//! EISPACK `tred2`/`tql2` pair). faer did both before, but its x86 product reserved twice
//! the L3 size read from `/sys` (600 MiB on a 300 MiB-L3 Xeon) in every thread that
//! multiplied, which aborted the PCA under an address-space limit (`prlimit --as`).
//! Written here rather than taken from another linear-algebra crate (nalgebra's
//! `SymmetricEigen` would do): the problem is one dense symmetric matrix of at most a few
//! hundred rows, solved once per precompute, and a whole crate for one textbook routine
//! would add to every cold build of a CI run that is already over its time budget.

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
    let products: Vec<Vec<f64>> = blocks
        .par_iter()
        .map(|&(r0, r1)| block_covariance(keys, &mean, r0, r1, precision))
        .collect();
    let mut covariance = vec![0f64; t_count * t_count];
    for b in &products {
        for (c, v) in covariance.iter_mut().zip(b) {
            *c += v;
        }
    }
    for c in &mut covariance {
        *c /= rows as f64;
    }
    let eigen = symmetric_eigen(&covariance, t_count).ok_or(PcaError::Eigen(t_count))?;
    // Largest first (the solver returns them ascending).
    let order: Vec<usize> = (0..t_count).rev().collect();
    let eigenvalues: Vec<f64> = order.iter().map(|&i| eigen.values[i]).collect();
    let u = |t: usize, col: usize| eigen.vectors[col * t_count + t];
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
            if u(t, col).abs() > best {
                best = u(t, col).abs();
                sign = u(t, col).signum();
            }
        }
        for t in 0..t_count {
            temporal[i * t_count + t] = (sign * u(t, col)) as f32;
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

/// `Y_bᵀ Y_b` of rows `r0..r1`, centred, in the chosen precision, returned in f64
/// (T×T, row-major).
fn block_covariance(
    keys: &[&[f32]],
    mean: &[f32],
    r0: usize,
    r1: usize,
    precision: Precision,
) -> Vec<f64> {
    let t = keys.len();
    let n = r1 - r0;
    match precision {
        Precision::F32 => {
            // Y_bᵀ (T×n, row-major): key j's centred rows, contiguous.
            let yt: Vec<f32> = keys
                .iter()
                .zip(mean)
                .flat_map(|(k, &m)| k[r0..r1].iter().map(move |&v| v - m))
                .collect();
            gram(&yt, t, n, matrixmultiply::sgemm, 1.0)
                .into_iter()
                .map(f64::from)
                .collect()
        }
        Precision::F64 => {
            let yt: Vec<f64> = keys
                .iter()
                .zip(mean)
                .flat_map(|(k, &m)| k[r0..r1].iter().map(move |&v| f64::from(v - m)))
                .collect();
            gram(&yt, t, n, matrixmultiply::dgemm, 1.0)
        }
    }
}

/// A general matrix product of matrixmultiply (`sgemm`, `dgemm`): C ← α A B + β C with
/// A m×k, B k×n, C m×n given by pointers and (row, column) strides.
type Gemm<T> = unsafe fn(
    usize,
    usize,
    usize,
    T,
    *const T,
    isize,
    isize,
    *const T,
    isize,
    isize,
    T,
    *mut T,
    isize,
    isize,
);

/// Rows of the Gram matrix computed per product: matrixmultiply's own row block (`MC` =
/// 64), so the lower triangle costs ≈ ⅔ of the full product at T = 180.
const GRAM_ROWS: usize = 64;

/// `A Aᵀ` (T×T, row-major) of a row-major T×n matrix `a`: the lower triangle in row
/// chunks of [`GRAM_ROWS`] (row chunk i0..i1 against rows 0..i1), mirrored above.
fn gram<T: Copy + Default>(a: &[T], t: usize, n: usize, gemm: Gemm<T>, one: T) -> Vec<T> {
    assert_eq!(a.len(), t * n, "gram: {} values for {t}×{n}", a.len());
    let mut c = vec![T::default(); t * t];
    if n == 0 || t == 0 {
        return c;
    }
    for i0 in (0..t).step_by(GRAM_ROWS) {
        let i1 = (i0 + GRAM_ROWS).min(t);
        let chunk = &mut c[i0 * t..i1 * t];
        #[expect(
            unsafe_code,
            reason = "matrixmultiply's products take raw pointers and strides"
        )]
        // SAFETY: `a` holds t·n values. A's rows i0..i1 are read as an (i1 − i0)×n
        // matrix from `a[i0·n..]` with strides (n, 1), and rows 0..i1 transposed as n×i1
        // with strides (1, n): every index (i·n + j, i < i1 ≤ t, j < n) is in bounds.
        // `chunk` holds (i1 − i0)·t values, written as (i1 − i0)×i1 with strides (t, 1):
        // distinct, in bounds (i1 ≤ t), and not aliasing `a` (a separate allocation,
        // borrowed mutably only here).
        unsafe {
            gemm(
                i1 - i0,
                n,
                i1,
                one,
                a[i0 * n..].as_ptr(),
                stride(n),
                1,
                a.as_ptr(),
                1,
                stride(n),
                T::default(),
                chunk.as_mut_ptr(),
                stride(t),
                1,
            );
        }
    }
    for i in 0..t {
        for j in i + 1..t {
            c[i * t + j] = c[j * t + i];
        }
    }
    c
}

/// A matrix dimension as matrixmultiply's signed stride (block sizes are far below
/// `isize::MAX`: a block is at most `BLOCK_ROWS` rows of at most `MAX_KEYS` keys).
fn stride(n: usize) -> isize {
    isize::try_from(n).expect("a PCA block dimension fits in isize")
}

/// Eigen decomposition of a symmetric matrix.
#[derive(Clone, Debug)]
pub struct SymmetricEigen {
    /// The n eigenvalues, ascending.
    pub values: Vec<f64>,
    /// The n orthonormal eigenvectors, column-major: eigenvector j (of `values[j]`) at
    /// `[j·n .. (j+1)·n]`.
    pub vectors: Vec<f64>,
}

/// The eigen decomposition of the symmetric n×n matrix `a` (row-major; only its lower
/// triangle is read), in f64: Householder reduction to tridiagonal form and the
/// implicit QL method with Wilkinson-like shifts (EISPACK `tred2`/`tql2`, as in JAMA),
/// O(n³) with no allocation beyond the n×n result. `None` if an eigenvalue needs more
/// than 30·n QL iterations (never seen for a finite matrix) or `a` has a non-finite value.
pub fn symmetric_eigen(a: &[f64], n: usize) -> Option<SymmetricEigen> {
    assert_eq!(
        a.len(),
        n * n,
        "symmetric_eigen: {} values for {n}×{n}",
        a.len()
    );
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    if n == 0 {
        return Some(SymmetricEigen {
            values: Vec::new(),
            vectors: Vec::new(),
        });
    }
    // v[col·n + row]: column-major, so every inner loop below runs down a column.
    // JAMA's V[i][j] (row i, column j) is v[j·n + i]; the lower triangle of `a` is
    // copied into both triangles.
    let mut v = vec![0f64; n * n];
    for i in 0..n {
        for j in 0..=i {
            v[j * n + i] = a[i * n + j];
            v[i * n + j] = a[i * n + j];
        }
    }
    let mut d = vec![0f64; n];
    let mut e = vec![0f64; n];
    tred2(&mut v, &mut d, &mut e, n);
    if !tql2(&mut v, &mut d, &mut e, n) {
        return None;
    }
    // Ascending, eigenvectors with them.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| d[i].total_cmp(&d[j]));
    let values = order.iter().map(|&i| d[i]).collect();
    let mut vectors = Vec::with_capacity(n * n);
    for &i in &order {
        vectors.extend_from_slice(&v[i * n..(i + 1) * n]);
    }
    Some(SymmetricEigen { values, vectors })
}

/// Householder reduction of the symmetric matrix in `v` (column-major) to tridiagonal
/// form: `d` the diagonal, `e` the subdiagonal (`e[0]` = 0), `v` the orthogonal
/// transformation (JAMA's `tred2`).
fn tred2(v: &mut [f64], d: &mut [f64], e: &mut [f64], n: usize) {
    let at = |i: usize, j: usize| j * n + i;
    for j in 0..n {
        d[j] = v[at(n - 1, j)];
    }
    for i in (1..n).rev() {
        // Scale to avoid under/overflow.
        let scale: f64 = d[..i].iter().map(|x| x.abs()).sum();
        let mut h = 0.0;
        if scale == 0.0 {
            e[i] = d[i - 1];
            for j in 0..i {
                d[j] = v[at(i - 1, j)];
                v[at(i, j)] = 0.0;
                v[at(j, i)] = 0.0;
            }
        } else {
            // The Householder vector.
            for x in &mut d[..i] {
                *x /= scale;
                h += *x * *x;
            }
            let mut f = d[i - 1];
            let mut g = if f > 0.0 { -h.sqrt() } else { h.sqrt() };
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            e[..i].fill(0.0);
            // The similarity transformation of the remaining columns.
            for j in 0..i {
                f = d[j];
                v[at(j, i)] = f;
                g = e[j] + v[at(j, j)] * f;
                let col = &v[j * n + j + 1..j * n + i];
                for (k, &vkj) in (j + 1..i).zip(col) {
                    g += vkj * d[k];
                    e[k] += vkj * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for j in 0..i {
                e[j] /= h;
                f += e[j] * d[j];
            }
            let hh = f / (h + h);
            for j in 0..i {
                e[j] -= hh * d[j];
            }
            for j in 0..i {
                let (f, g) = (d[j], e[j]);
                let col = &mut v[j * n + j..j * n + i];
                for (k, vkj) in (j..i).zip(col) {
                    *vkj -= f * e[k] + g * d[k];
                }
                d[j] = v[at(i - 1, j)];
                v[at(i, j)] = 0.0;
            }
        }
        d[i] = h;
    }
    // Accumulate the transformations.
    for i in 0..n - 1 {
        v[at(n - 1, i)] = v[at(i, i)];
        v[at(i, i)] = 1.0;
        let h = d[i + 1];
        if h != 0.0 {
            for k in 0..=i {
                d[k] = v[at(k, i + 1)] / h;
            }
            for j in 0..=i {
                let (left, right) = v.split_at_mut((i + 1) * n);
                let next = &right[..=i];
                let col = &mut left[j * n..j * n + i + 1];
                let g: f64 = next.iter().zip(col.iter()).map(|(a, b)| a * b).sum();
                for (x, dk) in col.iter_mut().zip(&d[..=i]) {
                    *x -= g * dk;
                }
            }
        }
        for k in 0..=i {
            v[at(k, i + 1)] = 0.0;
        }
    }
    for j in 0..n {
        d[j] = v[at(n - 1, j)];
        v[at(n - 1, j)] = 0.0;
    }
    v[at(n - 1, n - 1)] = 1.0;
    e[0] = 0.0;
}

/// The implicit QL method on the tridiagonal (`d`, `e`) from [`tred2`], accumulating
/// into `v` (column-major): eigenvalues in `d`, eigenvectors in `v`'s columns (JAMA's
/// `tql2`). False if an eigenvalue takes more than 30·n iterations.
fn tql2(v: &mut [f64], d: &mut [f64], e: &mut [f64], n: usize) -> bool {
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let mut f = 0.0f64;
    let mut tst1 = 0.0f64;
    let eps = f64::EPSILON;
    for l in 0..n {
        // The smallest subdiagonal element below l that is negligible.
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        let mut m = l;
        while m < n - 1 && e[m].abs() > eps * tst1 {
            m += 1;
        }
        // m == l: d[l] is an eigenvalue; otherwise iterate.
        if m > l {
            let mut iterations = 0;
            loop {
                iterations += 1;
                if iterations > 30 * n.max(1) {
                    return false;
                }
                // The implicit shift.
                let g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = p.hypot(1.0);
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let h = g - d[l];
                for x in &mut d[l + 2..n] {
                    *x -= h;
                }
                f += h;
                // The implicit QL transformation.
                p = d[m];
                let (mut c, mut c2, mut c3) = (1.0f64, 1.0f64, 1.0f64);
                let el1 = e[l + 1];
                let (mut s, mut s2) = (0.0f64, 0.0f64);
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    let h = c * p;
                    r = p.hypot(e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    // Accumulate the rotation into columns i and i + 1.
                    let (left, right) = v.split_at_mut((i + 1) * n);
                    let col_i = &mut left[i * n..];
                    let col_i1 = &mut right[..n];
                    for (a, b) in col_i.iter_mut().zip(col_i1.iter_mut()) {
                        let h = *b;
                        *b = s * *a + c * h;
                        *a = c * *a - s * h;
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if e[l].abs() <= eps * tst1 {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    true
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

    /// The largest |A·v − λ·v| over all pairs and |VᵀV − I| of a decomposition.
    fn residuals(a: &[f64], n: usize, eigen: &SymmetricEigen) -> (f64, f64) {
        let v = |j: usize| &eigen.vectors[j * n..(j + 1) * n];
        let mut pair = 0f64;
        let mut orthogonality = 0f64;
        for j in 0..n {
            for i in 0..n {
                let av: f64 = (0..n).map(|k| a[i * n + k] * v(j)[k]).sum();
                pair = pair.max((av - eigen.values[j] * v(j)[i]).abs());
            }
            for k in 0..n {
                let dot: f64 = v(j).iter().zip(v(k)).map(|(x, y)| x * y).sum();
                let want = if j == k { 1.0 } else { 0.0 };
                orthogonality = orthogonality.max((dot - want).abs());
            }
        }
        (pair, orthogonality)
    }

    #[test]
    fn eigen_solver_matches_the_discrete_laplacian() {
        // tridiag(−1, 2, −1): λ_k = 2 − 2 cos(kπ/(n+1)), k = 1..n (ascending).
        let n: usize = 60;
        let a: Vec<f64> = (0..n * n)
            .map(|k| match (k / n).abs_diff(k % n) {
                0 => 2.0,
                1 => -1.0,
                _ => 0.0,
            })
            .collect();
        let eigen = symmetric_eigen(&a, n).unwrap();
        for (k, got) in eigen.values.iter().enumerate() {
            let want = 2.0 - 2.0 * (std::f64::consts::PI * (k + 1) as f64 / (n + 1) as f64).cos();
            assert!((got - want).abs() < 1e-13, "λ{k}: {got} vs {want}");
        }
        let (pair, orthogonality) = residuals(&a, n, &eigen);
        assert!(
            pair < 1e-13 && orthogonality < 1e-13,
            "{pair} {orthogonality}"
        );
    }

    #[test]
    fn eigen_solver_recovers_a_dense_matrix_with_repeated_and_zero_eigenvalues() {
        // A = Q diag(λ) Qᵀ with Q an orthonormal DCT basis (dense, no structure left).
        let n: usize = 40;
        let q: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                if i == 0 {
                    vec![1.0 / (n as f64).sqrt(); n]
                } else {
                    dct(i, n)
                }
            })
            .collect();
        let lambda: Vec<f64> = (0..n)
            .map(|i| match i {
                0..5 => 0.0,
                5..9 => 3.5,
                _ => (i * i) as f64 / 7.0 - 50.0,
            })
            .collect();
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                let (r, c) = (k / n, k % n);
                (0..n).map(|i| lambda[i] * q[i][r] * q[i][c]).sum()
            })
            .collect();
        let eigen = symmetric_eigen(&a, n).unwrap();
        let mut want = lambda.clone();
        want.sort_by(f64::total_cmp);
        for (k, (got, want)) in eigen.values.iter().zip(&want).enumerate() {
            assert!((got - want).abs() < 1e-11, "λ{k}: {got} vs {want}");
        }
        let (pair, orthogonality) = residuals(&a, n, &eigen);
        assert!(
            pair < 1e-11 && orthogonality < 1e-12,
            "{pair} {orthogonality}"
        );
    }

    #[test]
    fn eigen_solver_edge_cases() {
        assert!(symmetric_eigen(&[], 0).unwrap().values.is_empty());
        let one = symmetric_eigen(&[-2.5], 1).unwrap();
        assert_eq!((one.values[0], one.vectors[0].abs()), (-2.5, 1.0));
        let zero = symmetric_eigen(&[0.0; 9], 3).unwrap();
        assert_eq!(zero.values, [0.0; 3]);
        assert!(residuals(&[0.0; 9], 3, &zero).1 < 1e-15);
        assert!(symmetric_eigen(&[1.0, f64::NAN, f64::NAN, 1.0], 2).is_none());
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
