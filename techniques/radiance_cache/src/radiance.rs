//! Radiance records for glossy surfaces (§3, Křivánek et al. 2005, Gautron et al. 2004):
//! a record's gathered incoming radiance projected onto hemispherical harmonics
//! ([`crate::hsh`]), with translation gradients, and the shading of a glossy point's
//! specular part from them.
//!
//! **Which part is cached where.** The glTF metallic-roughness BRDF is split as
//! f = ρ_d/π + f_s, with ρ_d = (1 − metallic)·(1 − F0)·base colour (F0 = 0.04) the
//! Lambertian part at its smallest (normal-incidence) Fresnel, and f_s the remainder: the
//! GGX lobes plus the small angle-dependent loss of the diffuse part (F − F0 ≥ 0, so
//! f_s's diffuse term is slightly negative). ρ_d/π·E comes from irradiance records, as in
//! the paper's Japanese Interior; f_s from radiance records (roughness at or above
//! `traced_roughness_max`) or per-pixel rays (below it, [`GlossyShading::traced`]). The
//! split is exact: both parts together are the whole BRDF.
//!
//! **Projection.** c_i = Σ over the gather's cells of L_cell·∫_cell H_i dω: the
//! radiance is taken constant over each cell (as the irradiance gradients take it) and
//! H_i is integrated over the cell exactly (a per-grid table; the cells are
//! cosine-stratified, so their plain solid angles differ). Evaluating H_i at the cell's
//! ray instead would put errors of 1 % of c_0 into the higher coefficients.
//!
//! **Translation gradient.** Moving the record by δ, a surface point seen in direction ω
//! at distance r is seen in direction ω − δ⊥/r, so L_new(ω) ≈ L(ω) + δ·∇_ω L/r, with
//! ∇_ω L the tangent gradient of the incoming radiance on the sphere (finite differences
//! over the grid: central in φ, between neighbouring strata in θ). Hence ∇_p c_i =
//! Σ Ω·H_i(ω)·∇_ω L(ω)/r (r clamped below at the R_k floor; escaped rays contribute
//! nothing). This is the first-order (non-occlusion-aware) form: Ward & Heckbert's
//! wall terms, which also see occluders slide over each other, are not generalised here.
//!
//! **Shading.** A point with normal n takes each usable record's coefficients, moved to
//! the point (c + ∇_p c·(p − p_k), plus the temporal gradient, Eq. 17 applied to each
//! coefficient), rotated from the record's frame into the point's ([`crate::hsh`]:
//! exact about the normal, a least-squares tilt otherwise, tilts tabulated every 0.5°),
//! averages them with Ward's weights (Eq. 1), and shades with the BRDF×cos coefficients
//! of f_s for the view direction: L_o = Σ_i b_i·c_i.

use crate::RadianceCacheError;
use crate::hsh::{HshBasis, Quadrature, apply_tilt, frame_rotation, zyz_angles};
use crate::record::{HemisphereGather, RgbGradient};
use illume_core::sampling::{Pcg32, SampleStream, mix64};
use illume_core::{Frame, INV_PI, PI, Ray, Rgb, Vec3};
use illume_transport::World;
use illume_transport::metal_rough::{DIELECTRIC_F0, MetalRough};
use illume_transport::path::{PathRadiance, PathSettings, continue_path};
use std::collections::HashMap;
use std::sync::{Arc, OnceLock, RwLock};

/// Step of the tabulated tilt matrices \[rad\]: 0.5°.
const TILT_STEP: f32 = 0.5 * PI / 180.0;
/// Tilts tabulated: 0 to 30° (usable records' normals are within acos(1 − a²) of the
/// point's: 11.5° at a = 0.2, 60° at a = 1); larger tilts are computed when needed.
const TILT_TABLE: usize = 61;

/// A radiance record's payload: incoming radiance in hemispherical harmonics, in the
/// record's frame ([`HemisphereGather::frame`]).
#[derive(Clone, Debug, PartialEq)]
pub struct RadianceData {
    /// c_i per colour channel, n² of them.
    pub coefficients: Vec<Rgb>,
    /// ∇_p c_i (world space, per channel), n² of them.
    pub translation_gradient: Vec<RgbGradient>,
    /// ∂c_i/∂t per frame (Eq. 16 applied to each coefficient); zero without one.
    pub temporal_gradient: Vec<Rgb>,
}

/// The Lambertian part ρ_d = (1 − metallic)·(1 − F0)·base of a metallic-roughness BRDF
/// (see the module docs); the base colour itself for a Lambertian surface.
pub fn diffuse_albedo(brdf: &MetalRough) -> Rgb {
    if brdf.is_lambertian() {
        brdf.base_color
    } else {
        brdf.base_color * ((1.0 - brdf.metallic) * (1.0 - DIELECTRIC_F0))
    }
}

/// f_s(wo, wi) = f − ρ_d/π, local directions (zero below the surface).
pub fn specular_part(brdf: &MetalRough, wo: Vec3, wi: Vec3) -> Rgb {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Rgb::ZERO;
    }
    brdf.eval(wo, wi) - diffuse_albedo(brdf) * INV_PI
}

/// Bins of the view angle θ_o in the table of BRDF×cos coefficients: 0.5° each.
const VIEW_BINS: f32 = 180.0;
/// Most entries the table keeps (each n² RGB values: 0.77 kB at order 8); beyond it,
/// coefficients are computed and not kept (textured roughness can make many).
const TABLE_CAP: usize = 8192;

/// ∫_cell H_i dω of a grid's cells, shared.
type CellTable = Arc<Vec<f64>>;

/// Key of a tabulated BRDF×cos vector: the BRDF's parameters (bits) and the view bin.
type TableKey = (u32, u32, [u32; 3], u16);

/// What shading glossy points needs: the basis, a quadrature with the basis tabulated
/// at its nodes (for BRDF×cos coefficients), and the tilt matrices.
pub struct GlossyShading {
    basis: HshBasis,
    nodes: Quadrature,
    /// Basis values at the nodes, node-major (nodes × n²).
    node_values: Vec<f64>,
    tilts: Vec<OnceLock<Vec<f64>>>,
    /// BRDF×cos coefficients of f_s at φ_o = 0, by BRDF and view bin.
    table: RwLock<HashMap<TableKey, Arc<Vec<Rgb>>>>,
    /// ∫_cell H_i dω for every cell of an M×N gather grid, cell-major, by (M, N).
    cell_integrals: RwLock<HashMap<(u32, u32), CellTable>>,
}

impl GlossyShading {
    /// For hemispherical harmonics of order `order`. The BRDF quadrature has
    /// 4·order + 8 nodes in cos θ and 8·order + 16 in φ (the lobes of roughness ≥ 0.5,
    /// which order 8 represents, are resolved by it: `tests/radiance.rs`).
    pub fn new(order: usize) -> Result<Self, RadianceCacheError> {
        let basis = HshBasis::new(order)?;
        let nodes = Quadrature::new(4 * order + 8, 8 * order + 16);
        let n2 = basis.len();
        let mut node_values = vec![0.0; nodes.directions.len() * n2];
        for (d, out) in nodes.directions.iter().zip(node_values.chunks_mut(n2)) {
            basis.eval_into(*d, out);
        }
        Ok(Self {
            basis,
            nodes,
            node_values,
            tilts: (0..TILT_TABLE).map(|_| OnceLock::new()).collect(),
            table: RwLock::new(HashMap::new()),
            cell_integrals: RwLock::new(HashMap::new()),
        })
    }

    /// The basis.
    pub fn basis(&self) -> &HshBasis {
        &self.basis
    }

    /// ∫_cell H_i dω of every cell (j, k) of an M×N cosine-stratified grid in the
    /// record's local frame (cell-major, n² values per cell), by Gauss–Legendre
    /// quadrature within each cell (6 nodes in cos θ, 6 in φ: exact to far below the
    /// f32 rounding of the coefficients for n ≤ 16 on grids of 8×8 and finer).
    fn cell_integrals(&self, m: u32, n: u32) -> CellTable {
        if let Some(t) = self
            .cell_integrals
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .get(&(m, n))
        {
            return t.clone();
        }
        let n2 = self.basis.len();
        let nodes = crate::hsh::gauss_legendre_unit(6);
        let mut table = vec![0.0f64; (m * n) as usize * n2];
        let mut h = vec![0.0; n2];
        let d_phi = 2.0 * std::f64::consts::PI / n as f64;
        for j in 0..m {
            // Stratum j spans cos θ from √(1 − (j+1)/M) to √(1 − j/M).
            let x_lo = (1.0 - (j + 1) as f64 / m as f64).max(0.0).sqrt();
            let x_hi = (1.0 - j as f64 / m as f64).max(0.0).sqrt();
            for k in 0..n {
                let out = &mut table[((j * n + k) as usize) * n2..((j * n + k + 1) as usize) * n2];
                for &(ux, wx) in &nodes {
                    let x = x_lo + (x_hi - x_lo) * ux;
                    let s_t = (1.0 - x * x).max(0.0).sqrt();
                    for &(up, wp) in &nodes {
                        let phi = d_phi * (k as f64 + up);
                        let d =
                            Vec3::new((s_t * phi.cos()) as f32, (s_t * phi.sin()) as f32, x as f32);
                        self.basis.eval_into(d, &mut h);
                        let w = wx * (x_hi - x_lo) * wp * d_phi;
                        for (o, hi) in out.iter_mut().zip(&h) {
                            *o += w * hi;
                        }
                    }
                }
            }
        }
        let table = Arc::new(table);
        self.cell_integrals
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .insert((m, n), table.clone());
        table
    }

    /// The radiance record of `gather` (see the module docs); distances below
    /// `min_distance_m` count as that distance in the translation gradient.
    pub fn project(&self, gather: &HemisphereGather, min_distance_m: f32) -> RadianceData {
        let n2 = self.basis.len();
        let (m, n) = gather.strata();
        let frame = gather.frame();
        let cells = gather.cells();
        let d_phi = 2.0 * PI / n as f32;
        let theta_centre = |j: u32| ((j as f32 + 0.5) / m as f32).sqrt().asin();
        let integrals = self.cell_integrals(m, n);
        let mut c = vec![[0.0f64; 3]; n2];
        let mut g = vec![RgbGradient::ZERO; n2];
        for j in 0..m {
            // Neighbouring strata for ∂L/∂θ (one-sided at the ends).
            let (j0, j1) = (j.saturating_sub(1), (j + 1).min(m - 1));
            let d_theta = theta_centre(j1) - theta_centre(j0);
            for k in 0..n {
                let i = (j * n + k) as usize;
                let cell = &cells[i];
                let local = frame.to_local(cell.direction);
                // ∫_cell H_i dω: the cell's radiance is taken constant over the cell.
                let h = &integrals[i * n2..(i + 1) * n2];
                let l = cell.radiance;
                for (ci, hi) in c.iter_mut().zip(h) {
                    for ch in 0..3 {
                        ci[ch] += hi * l[ch] as f64;
                    }
                }
                if !cell.distance_m.is_finite() {
                    continue;
                }
                let at = |jj: u32, kk: u32| cells[(jj * n + kk % n) as usize].radiance;
                let dl_dtheta = if d_theta > 0.0 {
                    (at(j1, k) - at(j0, k)) * (1.0 / d_theta)
                } else {
                    Rgb::ZERO
                };
                let dl_dphi = (at(j, k + 1) - at(j, k + n - 1)) * (0.5 / d_phi);
                let sin_t = (local.x * local.x + local.y * local.y).sqrt().max(1e-4);
                let (cos_p, sin_p) = (local.x / sin_t, local.y / sin_t);
                let e_theta = frame.to_world(Vec3::new(local.z * cos_p, local.z * sin_p, -sin_t));
                let e_phi = frame.to_world(Vec3::new(-sin_p, cos_p, 0.0));
                let scale = 1.0 / cell.distance_m.max(min_distance_m.max(1e-6));
                for (gi, hi) in g.iter_mut().zip(h) {
                    let s = scale * *hi as f32;
                    gi.add_scaled(e_theta, dl_dtheta * s);
                    gi.add_scaled(e_phi, dl_dphi * (s / sin_t));
                }
            }
        }
        RadianceData {
            coefficients: c
                .iter()
                .map(|a| Rgb::new(a[0] as f32, a[1] as f32, a[2] as f32))
                .collect(),
            translation_gradient: g,
            temporal_gradient: vec![Rgb::ZERO; n2],
        }
    }

    /// The BRDF×cos coefficients b_i of f_s for the local view direction `wo` (see the
    /// module docs); zero below the horizon.
    pub fn specular_coefficients(&self, brdf: &MetalRough, wo: Vec3) -> Vec<Rgb> {
        let n2 = self.basis.len();
        if wo.z <= 0.0 {
            return vec![Rgb::ZERO; n2];
        }
        let sin_o = (wo.x * wo.x + wo.y * wo.y).sqrt();
        let wo0 = Vec3::new(sin_o, 0.0, wo.z).normalize();
        let mut acc = vec![[0.0f64; 3]; n2];
        for ((d, w), h) in self
            .nodes
            .directions
            .iter()
            .zip(&self.nodes.weights)
            .zip(self.node_values.chunks(n2))
        {
            let v = specular_part(brdf, wo0, *d) * d.z;
            if v == Rgb::ZERO {
                continue;
            }
            for (a, hi) in acc.iter_mut().zip(h) {
                let s = w * hi;
                for c in 0..3 {
                    a[c] += s * v[c] as f64;
                }
            }
        }
        let mut b: Vec<Rgb> = acc
            .iter()
            .map(|a| Rgb::new(a[0] as f32, a[1] as f32, a[2] as f32))
            .collect();
        if sin_o > 0.0 {
            self.basis.rotate_about_normal(&mut b, wo.y.atan2(wo.x));
        }
        b
    }

    /// [`GlossyShading::specular_coefficients`] with θ_o rounded to 0.5° (the
    /// coefficients at φ_o = 0 are tabulated per BRDF and view bin, then turned to
    /// `wo`'s azimuth exactly).
    pub fn specular_coefficients_tabulated(&self, brdf: &MetalRough, wo: Vec3) -> Vec<Rgb> {
        if wo.z <= 0.0 {
            return vec![Rgb::ZERO; self.basis.len()];
        }
        let theta = wo.z.clamp(0.0, 1.0).acos();
        let bin = (theta / (PI / 2.0) * VIEW_BINS)
            .round()
            .min(VIEW_BINS - 1.0) as u16;
        let b = brdf.base_color;
        let key = (
            brdf.metallic.to_bits(),
            brdf.roughness.to_bits(),
            [b.x.to_bits(), b.y.to_bits(), b.z.to_bits()],
            bin,
        );
        let cached = self
            .table
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .get(&key)
            .cloned();
        let at_zero = match cached {
            Some(v) => v,
            None => {
                let t = bin as f32 / VIEW_BINS * (PI / 2.0);
                let v =
                    Arc::new(self.specular_coefficients(brdf, Vec3::new(t.sin(), 0.0, t.cos())));
                let mut table = self.table.write().unwrap_or_else(|e| e.into_inner());
                if table.len() < TABLE_CAP {
                    table.insert(key, v.clone());
                }
                v
            }
        };
        let mut out = at_zero.to_vec();
        if wo.x != 0.0 || wo.y != 0.0 {
            self.basis.rotate_about_normal(&mut out, wo.y.atan2(wo.x));
        }
        out
    }

    /// `coefficients` (in `from`'s frame) rotated into `to`'s frame.
    pub fn rotate(&self, coefficients: &[Rgb], from: &Frame, to: &Frame) -> Vec<Rgb> {
        let (alpha, beta, gamma) = zyz_angles(frame_rotation(from, to));
        let mut c = coefficients.to_vec();
        self.basis.rotate_about_normal(&mut c, gamma);
        if beta.abs() > 1e-6 {
            let i = (beta / TILT_STEP).round() as usize;
            let computed;
            let m: &[f64] = if i < TILT_TABLE {
                self.tilts[i].get_or_init(|| self.basis.tilt_matrix(i as f32 * TILT_STEP))
            } else {
                computed = self.basis.tilt_matrix(beta);
                &computed
            };
            c = apply_tilt(m, &c);
        }
        self.basis.rotate_about_normal(&mut c, alpha);
        c
    }

    /// f_s's share of the indirect light leaving a point towards `wo` (world, unit),
    /// by `samples` rays drawn from the BRDF: each brings back the light reflected at
    /// least once where it lands (`continue_path`), weighted by f_s·cos/pdf. `key`
    /// names the random stream (a pixel's: the same noise frame after frame).
    #[expect(clippy::too_many_arguments, reason = "one shading point's inputs")]
    pub fn traced(
        world: &World,
        position: Vec3,
        normal: Vec3,
        brdf: &MetalRough,
        wo: Vec3,
        samples: u32,
        seed: u64,
        key: u64,
        path: &PathSettings,
    ) -> Rgb {
        let frame = Frame::from_normal(normal);
        let wo_local = frame.to_local(wo);
        if wo_local.z <= 0.0 || samples == 0 {
            return Rgb::ZERO;
        }
        let diffuse = diffuse_albedo(brdf) * INV_PI;
        let mut stream = Pcg32::new(mix64(seed ^ mix64(key)), 0x5bec);
        let mut sum = Rgb::ZERO;
        for _ in 0..samples {
            let u_lobe = stream.next_1d();
            let Some(s) = brdf.sample(wo_local, u_lobe, stream.next_2d()) else {
                continue;
            };
            if !(s.pdf > 0.0 && s.wi.z > 0.0) {
                continue;
            }
            let weight = s.weight - diffuse * (s.wi.z / s.pdf);
            if !weight.is_finite() {
                continue;
            }
            let wi = frame.to_world(s.wi).normalize();
            let ray = Ray::new(illume_core::offset_ray_origin(position, normal, wi), wi);
            let Some(hit) = world.trace(&ray, illume_scene::MASK_DEFAULT) else {
                continue;
            };
            let mut out = PathRadiance::default();
            continue_path(world, hit, -wi, &mut stream, path, &mut out);
            sum += weight * (out.direct + out.indirect);
        }
        sum * (1.0 / samples as f32)
    }
}
