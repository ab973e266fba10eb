//! The directional albedo of the glTF metallic-roughness BRDF: how much of a uniform
//! incident radiance a surface reflects towards a viewer, `A(wo) = ∫ f(wo, wi) cosθᵢ dωᵢ`.
//!
//! Techniques that store irradiance E rather than incident radiance (selective's mesh
//! elements, photon_stream's VSL sums) display it as `A(wo)/π · E`: exact for a
//! Lambertian receiver (A = ρ) and, for a glossy one, exact when the incident light is
//! uniform over the hemisphere — the "split-sum" environment-BRDF approximation of
//! real-time renderers (Karis 2013), here with the BRDF's diffuse layer included. Before
//! it they showed `ρ/π · E` on every surface, which is too bright on rough metals: a white
//! metal of roughness 0.6 reflects ≈ 0.82 of uniform light at normal incidence, not 1
//! (single scattering, [`crate::metal_rough`]). What the approximation still misses is
//! the direction the light comes from: a smooth metal shows E's mean, not a reflection.
//!
//! `A` is linear in the base colour for a fixed metalness, so three scalar integrals over
//! `(cosθₒ, roughness)` give it for every colour (`s = (1 − wo·h)⁵`, Schlick's term):
//! * `I₀ = ∫ D·V cosθᵢ dωᵢ` and `I₁ = ∫ D·V·s cosθᵢ dωᵢ`, the specular lobe with and
//!   without Fresnel's rise: a metal reflects `c·(I₀ − I₁) + I₁`, a dielectric's specular
//!   layer `F0·I₀ + (1 − F0)·I₁`;
//! * `K = ∫ s cosθᵢ/π dωᵢ`: the dielectric's diffuse layer reflects `ρ·(1 − F0)·(1 − K)`.
//!
//! They are tabulated once per process, on first use ([`TABLE`], 32 × 32 entries), by
//! stratified sampling — the specular integrals by GGX's visible normals, whose weight
//! `G₂/G₁` is bounded, the diffuse one by the cosine — and read bilinearly.

use crate::metal_rough::{DIELECTRIC_F0, MetalRough, sample_vndf, smith_g1, smith_visibility};
use illume_core::sampling::cosine_hemisphere;
use illume_core::{Rgb, Vec2, Vec3};
use std::sync::LazyLock;

/// Table resolution in cosθₒ and in roughness.
const N: usize = 32;
/// Stratified samples per table entry and integral: `STRATA × STRATA`.
const STRATA: usize = 24;

/// `(I₀, I₁, K)` at the grid points `cosθₒ = i/(N − 1)`, `roughness = j/(N − 1)`
/// (cosθₒ = 0 is evaluated just above the horizon).
struct Table {
    entries: Vec<[f32; 3]>,
}

static TABLE: LazyLock<Table> = LazyLock::new(Table::build);

impl Table {
    fn build() -> Self {
        let mut entries = Vec::with_capacity(N * N);
        for j in 0..N {
            let roughness = j as f32 / (N - 1) as f32;
            for i in 0..N {
                let cos_o = (i as f32 / (N - 1) as f32).max(1e-3);
                entries.push(integrals(cos_o, roughness));
            }
        }
        Self { entries }
    }

    /// The three integrals at `cos_o` and `roughness` (both clamped to [0, 1]), bilinear
    /// between grid points.
    fn lookup(&self, cos_o: f32, roughness: f32) -> [f32; 3] {
        let scale = (N - 1) as f32;
        let x = (cos_o.clamp(0.0, 1.0) * scale).min(scale);
        let y = (roughness.clamp(0.0, 1.0) * scale).min(scale);
        let (i, j) = ((x as usize).min(N - 2), (y as usize).min(N - 2));
        let (fx, fy) = (x - i as f32, y - j as f32);
        let at = |i: usize, j: usize| self.entries[j * N + i];
        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
        std::array::from_fn(|k| {
            let bottom = a[k] + (b[k] - a[k]) * fx;
            let top = c[k] + (d[k] - c[k]) * fx;
            bottom + (top - bottom) * fy
        })
    }
}

/// `(I₀, I₁, K)` for a view at `cos_o` over a surface of `roughness`.
fn integrals(cos_o: f32, roughness: f32) -> [f32; 3] {
    let wo = Vec3::new((1.0 - cos_o * cos_o).max(0.0).sqrt(), 0.0, cos_o);
    let alpha = MetalRough {
        base_color: Rgb::ONE,
        metallic: 1.0,
        roughness,
    }
    .alpha();
    let schlick = |wi: Vec3| {
        let h = (wo + wi).normalize_or_zero();
        (1.0 - wo.dot(h).clamp(0.0, 1.0)).powi(5)
    };
    let (mut i0, mut i1, mut k) = (0.0f64, 0.0f64, 0.0f64);
    let g1 = smith_g1(cos_o, alpha);
    for a in 0..STRATA {
        for b in 0..STRATA {
            let u = Vec2::new(
                (a as f32 + 0.5) / STRATA as f32,
                (b as f32 + 0.5) / STRATA as f32,
            );
            // Specular: wi reflected about a visible normal; D·V·cosθᵢ / pdf = 4·V·cosθᵢ·cosθₒ/G₁.
            let h = sample_vndf(wo, alpha, u);
            let wi = 2.0 * wo.dot(h) * h - wo;
            if wi.z > 0.0 && g1 > 0.0 {
                let w = 4.0 * smith_visibility(cos_o, wi.z, alpha) * wi.z * cos_o / g1;
                let s = (1.0 - wo.dot(h).clamp(0.0, 1.0)).powi(5);
                i0 += w as f64;
                i1 += (w * s) as f64;
            }
            // Diffuse: cosine-distributed wi, weight s.
            let wi = cosine_hemisphere(u).normalize();
            k += schlick(wi) as f64;
        }
    }
    let n = (STRATA * STRATA) as f64;
    [(i0 / n) as f32, (i1 / n) as f32, (k / n) as f32]
}

impl MetalRough {
    /// The directional albedo `A(wo) = ∫ f(wo, wi) cosθᵢ dωᵢ` for a view at `cos_o` =
    /// cosθₒ: the radiance reflected towards `wo` per unit uniform incident radiance, so
    /// `A/π · E` is the radiance a uniform irradiance E leaves with. Exactly the base
    /// colour for a Lambertian material; otherwise from a table (within ≈ 1 % of
    /// quadrature of [`MetalRough::eval`]; see the module docs).
    pub fn directional_albedo(&self, cos_o: f32) -> Rgb {
        if self.is_lambertian() {
            return self.base_color;
        }
        let [i0, i1, k] = TABLE.lookup(cos_o, self.roughness);
        let metal = self.base_color * (i0 - i1) + Rgb::splat(i1);
        let dielectric = self.base_color * ((1.0 - DIELECTRIC_F0) * (1.0 - k))
            + Rgb::splat(DIELECTRIC_F0 * i0 + (1.0 - DIELECTRIC_F0) * i1);
        dielectric * (1.0 - self.metallic) + metal * self.metallic
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::PI;

    /// ∫ f cosθᵢ dωᵢ by midpoint quadrature in (θ, φ), fine enough for roughness ≥ 0.2.
    fn quadrature(m: &MetalRough, wo: Vec3) -> Rgb {
        let (nt, np) = (512usize, 1024usize);
        let mut sum = Rgb::ZERO;
        for i in 0..nt {
            let theta = (i as f32 + 0.5) / nt as f32 * 0.5 * PI;
            let (s, c) = theta.sin_cos();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
                sum += m.eval(wo, Vec3::new(s * phi.cos(), s * phi.sin(), c)) * (c * s);
            }
        }
        sum * (0.5 * PI * 2.0 * PI / (nt * np) as f32)
    }

    #[test]
    fn lambertian_albedo_is_the_base_colour_bit_for_bit() {
        let m = MetalRough::lambertian(Rgb::new(0.2, 0.5, 0.8));
        for cos_o in [0.0, 0.3, 1.0] {
            assert_eq!(m.directional_albedo(cos_o), m.base_color);
        }
    }

    /// The table against quadrature of the BRDF it tabulates, for metals, dielectrics and
    /// a mix, coloured, at angles and roughness between grid points.
    #[test]
    fn the_table_agrees_with_quadrature_of_the_brdf() {
        for roughness in [0.23f32, 0.41, 0.6, 0.87, 1.0] {
            for metallic in [0.0f32, 0.5, 1.0] {
                if metallic == 0.0 && roughness == 1.0 {
                    continue; // exactly Lambertian: the test above
                }
                for theta in [0.05f32, 0.6, 1.1, 1.4] {
                    let m = MetalRough {
                        base_color: Rgb::new(0.9, 0.5, 0.1),
                        metallic,
                        roughness,
                    };
                    let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                    let table = m.directional_albedo(wo.z);
                    let exact = quadrature(&m, wo);
                    let err = ((table - exact) / exact).abs().max_element();
                    assert!(
                        err < 0.015,
                        "r {roughness} m {metallic} θ {theta}: table {table:?}, quadrature {exact:?}"
                    );
                }
            }
        }
    }

    /// A white metal loses energy as it roughens (single scattering) and a near-mirror
    /// reflects almost everything: the ρ/π display was right only at roughness → 0. At
    /// roughness 1 the integral has a closed form.
    #[test]
    fn a_white_metal_reflects_less_as_it_roughens() {
        let white = |roughness| MetalRough {
            base_color: Rgb::ONE,
            metallic: 1.0,
            roughness,
        };
        let at_normal = |r| white(r).directional_albedo(1.0).x;
        assert!(at_normal(0.0) > 0.99, "{}", at_normal(0.0));
        assert!((at_normal(0.6) - 0.82).abs() < 0.015, "{}", at_normal(0.6));
        // α = 1: D = 1/π and V = 1/(2(cosθᵢ + 1)) at normal view, so
        // A = ∫₀¹ μ/(μ + 1) dμ = 1 − ln 2 exactly.
        let analytic = 1.0 - std::f32::consts::LN_2;
        assert!(
            (at_normal(1.0) - analytic).abs() < 0.005,
            "{}",
            at_normal(1.0)
        );
        assert!(at_normal(1.0) < at_normal(0.6) && at_normal(0.6) < at_normal(0.3));
    }
}
