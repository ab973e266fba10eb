//! Hemispherical harmonics (Gautron, Křivánek, Pattanaik & Bouatouch 2004, "A novel
//! hemispherical basis for accurate and efficient rendering", EGSR): the basis radiance
//! records store incoming radiance in (§3, Křivánek et al. 2005).
//!
//! **The basis.** With x = cos θ in [0, 1] mapped to t = 2x − 1 in [−1, 1] (the
//! hemisphere stretched over the whole Legendre domain):
//!
//! H_l^m = K_l^m · P_l^m(t) · cos(mφ) (m > 0), K_l^0 · P_l^0(t) (m = 0),
//! K_l^|m| · P_l^|m|(t) · sin(|m|φ) (m < 0),
//!
//! K_l^m = √((2l + 1)(l − m)!/(2π(l + m)!)), times √2 for m ≠ 0, P_l^m the associated
//! Legendre functions. They are orthonormal over the hemisphere (dω = dx dφ). Order n
//! means bands l = 0..n, n² functions, indexed l(l + 1) + m. Directions are local: the
//! normal is +Z, φ is measured from +X towards +Y.
//!
//! **Quadrature.** Integrals over the hemisphere use Gauss–Legendre nodes in x and
//! equally spaced φ ([`Quadrature`]). With n nodes in x and 2n − 1 in φ the products of
//! two basis functions of order n are integrated exactly (polynomials of degree ≤ 2n − 2
//! in t, trigonometric polynomials of degree ≤ 2n − 2 in φ), so the Gram matrix is the
//! identity to rounding.
//!
//! **Rotation into a shading frame.** Coefficients live in their record's frame; a
//! point with another frame needs them in its own. A rotation Q (record-local →
//! shading-local directions) is split into Euler angles Q = R_z(α)·R_y(β)·R_z(γ):
//! * turns about the normal (α, γ) are exact: the pair (m, −m) of band l rotates by mα
//!   like a 2-D vector ([`HshBasis::rotate_about_normal`]);
//! * the tilt β is the least-squares projection of the tilted function onto the new
//!   hemisphere's basis, M_ij = ∫ H_i(ω)·H_j(R_y(−β)ω) dω, by quadrature. The sliver of
//!   the new hemisphere that lay below the old horizon has no data: there the function
//!   is extended by its value at the old horizon (where every HSH function is constant in
//!   φ, since t = −1 there). A tilt is therefore not exactly invertible: the basis of
//!   order n is not closed under tilts, and the sliver is extrapolated
//!   (`tests/hsh.rs` states the round-trip tolerance).
//!
//! **Shading.** Radiance leaving towards `wo` is ∫ f(wo, ω) cos θ L(ω) dω = Σ_i b_i c_i
//! (Parseval, exact when L lies in the span), b the projection of the BRDF×cos lobe for
//! `wo` ([`HshBasis::brdf_cos`]). For an isotropic BRDF b at azimuth φ_o is b at φ = 0
//! turned by φ_o about the normal, which is how it is computed (a table over θ_o is
//! then possible).

use crate::RadianceCacheError;
use illume_core::{Frame, Mat3, Rgb, Vec3};
use illume_transport::metal_rough::MetalRough;
use std::f64::consts::PI as PI64;

/// The largest order supported (256 functions per channel).
pub const MAX_ORDER: usize = 16;

/// Gauss–Legendre nodes and weights on [0, 1] (`count` ≥ 1), by Newton's iteration on
/// the Legendre polynomial P_count.
pub fn gauss_legendre_unit(count: usize) -> Vec<(f64, f64)> {
    let n = count.max(1);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess for the i-th root of P_n.
        let mut x = (PI64 * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            // p1 = P_n(x), p0 = P_{n−1}(x) (also for n = 1, where the loop is empty).
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (x + 1.0), 0.5 * w));
    }
    out
}

/// A quadrature over the hemisphere: Gauss–Legendre in x = cos θ, equally spaced
/// (midpoint) in φ. Weights sum to 2π.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadrature {
    /// Local unit directions (normal +Z).
    pub directions: Vec<Vec3>,
    /// Solid-angle weights \[sr\].
    pub weights: Vec<f64>,
}

impl Quadrature {
    /// `x_nodes` Gauss–Legendre nodes in cos θ times `phi_nodes` azimuths.
    pub fn new(x_nodes: usize, phi_nodes: usize) -> Self {
        let phi_nodes = phi_nodes.max(1);
        let d_phi = 2.0 * PI64 / phi_nodes as f64;
        let mut directions = Vec::new();
        let mut weights = Vec::new();
        for (x, w) in gauss_legendre_unit(x_nodes) {
            let s = (1.0 - x * x).max(0.0).sqrt();
            for j in 0..phi_nodes {
                let phi = d_phi * (j as f64 + 0.5);
                directions.push(Vec3::new(
                    (s * phi.cos()) as f32,
                    (s * phi.sin()) as f32,
                    x as f32,
                ));
                weights.push(w * d_phi);
            }
        }
        Self {
            directions,
            weights,
        }
    }

    /// The smallest quadrature that integrates products of two order-`order` basis
    /// functions exactly: `order` nodes in x, 2·order − 1 in φ.
    pub fn exact_for_products(order: usize) -> Self {
        Self::new(order.max(1), (2 * order).max(2) - 1)
    }
}

/// Hemispherical-harmonic coefficients of an RGB function, one [`Rgb`] per basis
/// function (index l(l + 1) + m).
pub type Coefficients = Vec<Rgb>;

/// The hemispherical-harmonic basis of one order.
#[derive(Clone, Debug, PartialEq)]
pub struct HshBasis {
    order: usize,
    /// K_l^m (with the √2 for m ≠ 0), at `index(l, m)` for m ≥ 0.
    norm: Vec<f64>,
    /// ∫ H_i cos θ dω: the irradiance of each basis function.
    cosine: Vec<f64>,
}

impl HshBasis {
    /// The basis of order `order` (bands 0..order); errors outside 1..=[`MAX_ORDER`].
    pub fn new(order: usize) -> Result<Self, RadianceCacheError> {
        if !(1..=MAX_ORDER).contains(&order) {
            return Err(RadianceCacheError::HshOrder {
                order,
                max: MAX_ORDER,
            });
        }
        let mut norm = vec![0.0; order * order];
        for l in 0..order {
            for m in 0..=l {
                // (l − m)!/(l + m)! as a product of inverses, no overflow.
                let ratio: f64 = ((l - m + 1)..=(l + m)).map(|k| 1.0 / k as f64).product();
                let k = ((2 * l + 1) as f64 * ratio / (2.0 * PI64)).sqrt();
                norm[Self::index(l, m as i32)] = if m == 0 { k } else { k * 2f64.sqrt() };
            }
        }
        let mut basis = Self {
            order,
            norm,
            cosine: Vec::new(),
        };
        let quadrature = Quadrature::exact_for_products(order + 1);
        let mut cosine = vec![0.0; order * order];
        let mut h = vec![0.0; order * order];
        for (d, w) in quadrature.directions.iter().zip(&quadrature.weights) {
            basis.eval_into(*d, &mut h);
            for (c, hi) in cosine.iter_mut().zip(&h) {
                *c += w * hi * d.z as f64;
            }
        }
        basis.cosine = cosine;
        Ok(basis)
    }

    /// The order n (bands 0..n).
    pub fn order(&self) -> usize {
        self.order
    }

    /// n², the number of basis functions.
    pub fn len(&self) -> usize {
        self.order * self.order
    }

    /// Never true (an order is at least 1); for symmetry with [`HshBasis::len`].
    pub fn is_empty(&self) -> bool {
        self.order == 0
    }

    /// The index of H_l^m: l(l + 1) + m, for |m| ≤ l.
    #[inline]
    pub fn index(l: usize, m: i32) -> usize {
        ((l * (l + 1)) as isize + m as isize) as usize
    }

    /// Every basis function at local direction `d` (normal +Z; need not be unit in the
    /// plane, only its azimuth and z are used) into `out` (length ≥ n²). Directions
    /// below the horizon take the value at the horizon on their azimuth (z clamped to
    /// 0), which is where tilted coefficients extend the function.
    pub fn eval_into(&self, d: Vec3, out: &mut [f64]) {
        let n = self.order;
        let z = (d.z as f64).clamp(0.0, 1.0);
        let t = 2.0 * z - 1.0;
        let s = (1.0 - t * t).max(0.0).sqrt();
        let (x, y) = (d.x as f64, d.y as f64);
        let r = (x * x + y * y).sqrt();
        let (cos_phi, sin_phi) = if r > 0.0 { (x / r, y / r) } else { (1.0, 0.0) };
        // cos(mφ), sin(mφ) by the Chebyshev recurrence.
        let (mut cm, mut sm) = (1.0f64, 0.0f64);
        // P_m^m = (−1)^m (2m − 1)!! s^m.
        let mut pmm = 1.0f64;
        for m in 0..n {
            if m > 0 {
                pmm *= -((2 * m - 1) as f64) * s;
                let (c, si) = (cm * cos_phi - sm * sin_phi, sm * cos_phi + cm * sin_phi);
                cm = c;
                sm = si;
            }
            let (mut p_prev, mut p) = (0.0f64, pmm);
            for l in m..n {
                if l > m {
                    let next = if l == m + 1 {
                        t * (2 * m + 1) as f64 * pmm
                    } else {
                        ((2 * l - 1) as f64 * t * p - (l + m - 1) as f64 * p_prev) / (l - m) as f64
                    };
                    p_prev = p;
                    p = next;
                }
                let k = self.norm[Self::index(l, m as i32)];
                if m == 0 {
                    out[Self::index(l, 0)] = k * p;
                } else {
                    out[Self::index(l, m as i32)] = k * p * cm;
                    out[Self::index(l, -(m as i32))] = k * p * sm;
                }
            }
        }
    }

    /// Every basis function at local direction `d`.
    pub fn eval(&self, d: Vec3) -> Vec<f64> {
        let mut out = vec![0.0; self.len()];
        self.eval_into(d, &mut out);
        out
    }

    /// Coefficients c_i = ∫ f(ω) H_i(ω) dω of `f` (local direction → RGB) by `quadrature`.
    pub fn project(&self, quadrature: &Quadrature, mut f: impl FnMut(Vec3) -> Rgb) -> Coefficients {
        let mut acc = vec![[0.0f64; 3]; self.len()];
        let mut h = vec![0.0; self.len()];
        for (d, w) in quadrature.directions.iter().zip(&quadrature.weights) {
            let v = f(*d);
            if v == Rgb::ZERO {
                continue;
            }
            self.eval_into(*d, &mut h);
            for (a, hi) in acc.iter_mut().zip(&h) {
                let s = w * hi;
                for c in 0..3 {
                    a[c] += s * v[c] as f64;
                }
            }
        }
        acc.iter()
            .map(|a| Rgb::new(a[0] as f32, a[1] as f32, a[2] as f32))
            .collect()
    }

    /// Σ c_i H_i(d) at local direction `d`.
    pub fn reconstruct(&self, coefficients: &[Rgb], d: Vec3) -> Rgb {
        let h = self.eval(d);
        coefficients
            .iter()
            .zip(&h)
            .fold(Rgb::ZERO, |s, (c, &hi)| s + *c * hi as f32)
    }

    /// The irradiance ∫ L cos θ dω the coefficients imply \[W/m²\] (what the temporal
    /// weight of a radiance record looks at, §4.2).
    pub fn irradiance(&self, coefficients: &[Rgb]) -> Rgb {
        coefficients
            .iter()
            .zip(&self.cosine)
            .fold(Rgb::ZERO, |s, (c, &e)| s + *c * e as f32)
    }

    /// Turns the function the coefficients describe by `angle` \[rad\] about the normal
    /// (counter-clockwise seen from above: f'(φ) = f(φ − angle)). Exact.
    pub fn rotate_about_normal(&self, coefficients: &mut [Rgb], angle: f32) {
        for m in 1..self.order {
            let (s, c) = (m as f32 * angle).sin_cos();
            for l in m..self.order {
                let (ic, is) = (Self::index(l, m as i32), Self::index(l, -(m as i32)));
                let (a, b) = (coefficients[ic], coefficients[is]);
                coefficients[ic] = a * c - b * s;
                coefficients[is] = a * s + b * c;
            }
        }
    }

    /// The least-squares tilt matrix M(β) (row-major n² × n², see the module doc):
    /// coefficients of the function turned by `beta` \[rad\] about the local +Y axis.
    pub fn tilt_matrix(&self, beta: f32) -> Vec<f64> {
        let n2 = self.len();
        let quadrature = Quadrature::new(4 * self.order + 8, 8 * self.order + 16);
        let inverse = Mat3::from_rotation_y(-beta);
        let mut m = vec![0.0; n2 * n2];
        let (mut a, mut b) = (vec![0.0; n2], vec![0.0; n2]);
        for (d, w) in quadrature.directions.iter().zip(&quadrature.weights) {
            self.eval_into(*d, &mut a);
            self.eval_into(inverse * *d, &mut b);
            for (i, ai) in a.iter().enumerate() {
                let wa = w * ai;
                let row = &mut m[i * n2..(i + 1) * n2];
                for (mij, bj) in row.iter_mut().zip(&b) {
                    *mij += wa * bj;
                }
            }
        }
        m
    }

    /// The rotation of coefficients by `q` (a proper rotation taking directions local
    /// to the coefficients' frame to directions local to the target frame; see
    /// [`frame_rotation`]).
    pub fn rotation(&self, q: Mat3) -> HshRotation {
        let (alpha, beta, gamma) = zyz_angles(q);
        HshRotation {
            alpha,
            gamma,
            tilt: (beta.abs() > 1e-7).then(|| self.tilt_matrix(beta)),
        }
    }

    /// The coefficients b_i = ∫ f(wo, ω) cos θ H_i(ω) dω of the BRDF×cos lobe of `brdf`
    /// for the local view direction `wo` (unit, z > 0; zero below the horizon), by
    /// `quadrature`, computed at φ_o = 0 and turned to `wo`'s azimuth.
    pub fn brdf_cos(&self, brdf: &MetalRough, wo: Vec3, quadrature: &Quadrature) -> Coefficients {
        if wo.z <= 0.0 {
            return vec![Rgb::ZERO; self.len()];
        }
        let sin_o = (wo.x * wo.x + wo.y * wo.y).sqrt();
        let wo0 = Vec3::new(sin_o, 0.0, wo.z).normalize();
        let mut b = self.project(quadrature, |wi| brdf.eval(wo0, wi) * wi.z.max(0.0));
        if sin_o > 0.0 {
            self.rotate_about_normal(&mut b, wo.y.atan2(wo.x));
        }
        b
    }
}

/// Σ_i b_i ⊙ c_i: outgoing radiance from incoming-radiance coefficients `c` and
/// BRDF×cos coefficients `b` (per channel).
pub fn shade(b: &[Rgb], c: &[Rgb]) -> Rgb {
    b.iter().zip(c).fold(Rgb::ZERO, |s, (b, c)| s + *b * *c)
}

/// A rotation of coefficients ([`HshBasis::rotation`]): R_z(γ), then the tilt, then
/// R_z(α).
#[derive(Clone, Debug, PartialEq)]
pub struct HshRotation {
    alpha: f32,
    gamma: f32,
    /// M(β), row-major; `None` for no tilt.
    tilt: Option<Vec<f64>>,
}

impl HshRotation {
    /// The rotated coefficients.
    pub fn apply(&self, basis: &HshBasis, coefficients: &[Rgb]) -> Coefficients {
        let mut c = coefficients.to_vec();
        basis.rotate_about_normal(&mut c, self.gamma);
        if let Some(m) = &self.tilt {
            c = apply_tilt(m, &c);
        }
        basis.rotate_about_normal(&mut c, self.alpha);
        c
    }
}

/// `m` (row-major n² × n², a tilt matrix [`HshBasis::tilt_matrix`]) times the
/// coefficients `c` (n² of them), per channel, summed in f64.
pub fn apply_tilt(m: &[f64], c: &[Rgb]) -> Coefficients {
    let n2 = c.len();
    (0..n2)
        .map(|i| {
            let row = &m[i * n2..(i + 1) * n2];
            let mut acc = [0.0f64; 3];
            for (mij, cj) in row.iter().zip(c) {
                for k in 0..3 {
                    acc[k] += mij * cj[k] as f64;
                }
            }
            Rgb::new(acc[0] as f32, acc[1] as f32, acc[2] as f32)
        })
        .collect()
}

/// The rotation taking directions local to `from` to directions local to `to`.
pub fn frame_rotation(from: &Frame, to: &Frame) -> Mat3 {
    Mat3::from_cols(
        to.to_local(from.s),
        to.to_local(from.t),
        to.to_local(from.n),
    )
}

/// Euler angles (α, β, γ) with `q` = R_z(α)·R_y(β)·R_z(γ), β in [0, π]; when β is 0
/// or π, γ = 0.
pub fn zyz_angles(q: Mat3) -> (f32, f32, f32) {
    let (r00, r10) = (q.x_axis.x, q.x_axis.y);
    let r20 = q.x_axis.z;
    let r21 = q.y_axis.z;
    let (r02, r12, r22) = (q.z_axis.x, q.z_axis.y, q.z_axis.z);
    let beta = r22.clamp(-1.0, 1.0).acos();
    if beta.sin() > 1e-6 {
        (r12.atan2(r02), beta, r21.atan2(-r20))
    } else if r22 > 0.0 {
        (r10.atan2(r00), 0.0, 0.0)
    } else {
        ((-r10).atan2(-r00), std::f32::consts::PI, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zyz_angles_rebuild_the_rotation() {
        for (a, b, g) in [
            (0.3f32, 0.7f32, -1.2f32),
            (2.5, 0.0, 0.0),
            (-0.4, std::f32::consts::PI, 0.0),
            (1.0, 3.0, 2.0),
        ] {
            let q = Mat3::from_rotation_z(a) * Mat3::from_rotation_y(b) * Mat3::from_rotation_z(g);
            let (a2, b2, g2) = zyz_angles(q);
            let q2 =
                Mat3::from_rotation_z(a2) * Mat3::from_rotation_y(b2) * Mat3::from_rotation_z(g2);
            assert!(q.abs_diff_eq(q2, 1e-5), "{q:?} vs {q2:?}");
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let nodes = gauss_legendre_unit(5);
        let sum: f64 = nodes.iter().map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-14);
        // ∫₀¹ x⁹ dx = 1/10 with 5 nodes (exact to degree 9).
        let i: f64 = nodes.iter().map(|(x, w)| w * x.powi(9)).sum();
        assert!((i - 0.1).abs() < 1e-14, "{i}");
    }
}
