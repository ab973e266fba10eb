//! Visual masking of lighting patterns by textures (§5.3): a pilot hit on a textured
//! surface raises its group's P by Δp/T_e instead of Δp, T_e the texture's visibility
//! threshold elevation at the MIP level the camera sees it at.
//!
//! **The model** — a documented simplification of the paper's procedure (Dumont et al.'s
//! use of the VDP of Ramasubramanian et al., with frequencies finer than the mesh
//! removed first, after Luebke et al.):
//!
//! 1. **Luminance pyramid.** Per base-colour texture, Rec.709 luminance of the linear
//!    texels, reduced by 2×2 box means level after level down to one texel (odd sides
//!    end in blocks of one or two texels).
//! 2. **Band-limited contrast** (Peli 1990). Band `b` is what level `b` holds beyond
//!    level `b + 1`: for each texel of level `b + 1`, the RMS of its 2×2 children about
//!    their mean, divided by that mean (the local luminance). A block of black texels
//!    has contrast 0; the contrast of a 2×2 block never exceeds √3, so the measure is
//!    bounded whatever the texture.
//! 3. **Threshold elevation per band** — the contrast-masking function of Daly's Visible
//!    Differences Predictor (Daly 1993), the form Ferwerda et al. (1997) also use:
//!    `T_e = (1 + (k₁·(k₂·m)^s)^b)^(1/b)` with `k₁ = 0.0153`, `k₂ = 392.498`, `b = 4`
//!    and slope `s = 0.7` (Daly: 0.65–1; 0.7 is the value Yee's perceptual metric, 2004,
//!    uses). `m` is the masker contrast in threshold units: the band contrast divided by
//!    the contrast of an artefact just visible on a plain surface
//!    (`masking_contrast_threshold`, the inverse of contrast sensitivity; one value for
//!    every frequency instead of a CSF, because the display's pixels per degree are not
//!    known). Masking starts where the texture's contrast passes that threshold (T_e
//!    ≈ 1.19 at `m = 1`) and grows as `m^0.7` beyond. Band `b`'s T_e is the mean over its
//!    blocks.
//! 4. **Frequencies finer than an element removed.** The mesh reconstructs no
//!    illumination detail finer than an element, and masking acts between similar
//!    frequencies (§5.3), so only bands whose features are at least an element wide
//!    mask. With `e` the element's side in texels (`√(texel area / elements)` over the
//!    triangles using the texture: UV area × width × height of each, with the material's
//!    UV scale, over their k² elements) and `l_e = log₂ e`, band `b` (features `2^b`
//!    texels wide) survives from `b = l_e` on (linear in `b` between the two bands
//!    around a fractional `l_e`).
//! 5. **Per MIP level.** Seen at MIP level `l` (a pixel covers 2^l texels), the finest
//!    band shown that the low-pass keeps is `max(l, l_e)`:
//!    `T_e(l) = T_e,band(max(l, l_e))`, and 1 at the last (1×1) level — the paper's
//!    "set of the average T_e values for a given texture at each MipMap level".
//!
//! **MIP level at a hit** (the paper's "simple heuristic which takes into account the
//! surface distance to the observer and its spatial orientation"): one pixel, of angle
//! `pixel_rad = 2·tan(yfov/2) / image height` (the image centre's), covers
//! `d·pixel_rad / cos θ` metres along the surface at distance `d` from the eye seen at
//! angle θ from its normal (the stretched axis; `cos θ` at least [`MIN_COS`]); with the
//! triangle's texel density `√(texel area / world area)` that is a footprint of `f`
//! texels, and the level is `log₂ f` (0 when magnified, clamped to the pyramid; T_e is
//! interpolated linearly between levels).
//!
//! Untextured materials, light changes, textures no triangle maps with area (no UVs,
//! degenerate UVs), empty textures and textures that appear only after construction:
//! T_e = 1. The table is per texture: meshes mapping one texture at very different
//! densities share its mean element size.
//!
//! Only the order of re-tracing depends on T_e; the converged solution does not.
//!
//! References: S. Daly, "The Visible Differences Predictor: an algorithm for the
//! assessment of image fidelity", in *Digital Images and Human Vision*, MIT Press 1993;
//! J. Ferwerda, S. Pattanaik, P. Shirley, D. Greenberg, "A model of visual masking for
//! computer graphics", SIGGRAPH 1997; E. Peli, "Contrast in complex images", JOSA A 7(10),
//! 1990; H. Yee, "A perceptual metric for production testing", Journal of Graphics Tools
//! 9(4), 2004.

use crate::elements::Elements;
use crate::retrace::Frustum;
use illume_core::{Vec2, Vec3, luminance};
use illume_scene::{Scene, Texture, TextureId};
use illume_transport::surface::PhotonHit;
use rayon::prelude::*;

/// Δp, the increment of an unmasked pilot hit (§5.3: "some arbitrary value is chosen,
/// e.g., Δp = 1").
pub const DELTA_P: f32 = 1.0;

/// Daly's masking-function constant k₁.
pub const K1: f32 = 0.0153;
/// Daly's masking-function constant k₂.
pub const K2: f32 = 392.498;
/// Daly's masking-function exponent b.
pub const B: f32 = 4.0;
/// Slope s of the masking function (Daly: 0.65–1).
pub const SLOPE: f32 = 0.7;

/// Smallest `cos θ` the MIP-level heuristic uses: grazing views count as 1/16, four
/// levels coarser than head-on.
pub const MIN_COS: f32 = 1.0 / 16.0;

/// Image height assumed until the first frame tells (see [`MaskingView::of`]).
pub const DEFAULT_PIXELS_HIGH: u32 = 720;

/// Daly's contrast-masking function: the threshold elevation caused by a masker of
/// contrast `m` in threshold units (`m = 1`: the masker itself is just visible). 1 for
/// `m ≤ 0` or not a number.
#[inline]
pub fn threshold_elevation(m: f32) -> f32 {
    if m.is_nan() || m <= 0.0 {
        return 1.0;
    }
    let x = K1 * (K2 * m).powf(SLOPE);
    (1.0 + x.powf(B)).powf(1.0 / B)
}

/// The MIP level one pixel of angle `pixel_rad` \[rad\] sees on a surface `distance_m`
/// away, viewed at `cos_theta` from its normal, textured at `texels_per_m`: log₂ of the
/// pixel's footprint in texels; 0 when a texel covers more than a pixel or the inputs
/// make no footprint, infinite for an infinite one.
#[inline]
pub fn mip_level(distance_m: f32, cos_theta: f32, pixel_rad: f32, texels_per_m: f32) -> f32 {
    let cos = cos_theta.abs().max(MIN_COS);
    let footprint = distance_m * pixel_rad / cos * texels_per_m;
    if footprint > 1.0 {
        footprint.log2()
    } else {
        0.0
    }
}

/// Mean threshold elevation per MIP level of `texture` for mesh elements `element_texels`
/// texels a side (see the module doc), masker contrast counted in multiples of
/// `contrast_threshold`. Entry `l` is level `l` (level 0 the full resolution); the last
/// entry, the 1×1 level, is 1. An empty (or one-texel) texture gives `[1]`.
pub fn elevation_per_level(
    texture: &Texture,
    element_texels: f32,
    contrast_threshold: f32,
) -> Vec<f32> {
    let (w, h) = (texture.width as usize, texture.height as usize);
    if w == 0 || h == 0 || texture.texels.len() < w * h || (w == 1 && h == 1) {
        return vec![1.0];
    }
    let l_e = if element_texels > 1.0 {
        element_texels.log2()
    } else {
        0.0
    };
    let scale = if contrast_threshold > 0.0 {
        1.0 / contrast_threshold
    } else {
        0.0
    };
    // Bands finer than ⌊l_e⌋ are never read: reduced, not measured.
    let first_band = l_e.floor().min(64.0) as usize;
    let measure = |b: usize| (b >= first_band).then_some(scale);
    let texel = |x: usize, y: usize| {
        let y = luminance(texture.texels[y * w + x]);
        if y.is_finite() { y.max(0.0) } else { 0.0 }
    };
    let (mut level, mut lw, mut lh, te) = reduce(w, h, texel, measure(0));
    let mut band = vec![te];
    while lw > 1 || lh > 1 {
        let (next, nw, nh, te) = reduce(lw, lh, |x, y| level[y * lw + x], measure(band.len()));
        band.push(te);
        (level, lw, lh) = (next, nw, nh);
    }
    band.push(1.0);
    let band_at = |x: f32| {
        let last = (band.len() - 1) as f32;
        let x = x.clamp(0.0, last);
        let i = x.floor() as usize;
        let f = x - i as f32;
        match band.get(i + 1) {
            Some(&next) => band[i] * (1.0 - f) + next * f,
            None => band[i],
        }
    };
    (0..band.len())
        .map(|l| band_at((l as f32).max(l_e)))
        .collect()
}

/// One step down the pyramid from a `w`×`h` level read by `texel`: the next level (2×2
/// box means; blocks of one or two texels on odd sides), and, when `scale` is given,
/// the mean over the blocks of the threshold elevation of their band contrast times
/// `scale` (else 1). Returns the level, its width and height, and the mean T_e.
fn reduce(
    w: usize,
    h: usize,
    texel: impl Fn(usize, usize) -> f32,
    scale: Option<f32>,
) -> (Vec<f32>, usize, usize, f32) {
    let (nw, nh) = (w.div_ceil(2), h.div_ceil(2));
    let mut next = Vec::with_capacity(nw * nh);
    let mut sum_te = 0.0f64;
    for py in 0..nh {
        for px in 0..nw {
            let mut v = [0.0f32; 4];
            let mut n = 0;
            for y in 2 * py..(2 * py + 2).min(h) {
                for x in 2 * px..(2 * px + 2).min(w) {
                    v[n] = texel(x, y);
                    n += 1;
                }
            }
            let mean = v[..n].iter().sum::<f32>() / n as f32;
            next.push(mean);
            if let Some(scale) = scale {
                let contrast = if mean > 0.0 {
                    let var = v[..n].iter().map(|y| (y - mean).powi(2)).sum::<f32>() / n as f32;
                    var.sqrt() / mean
                } else {
                    0.0
                };
                sum_te += threshold_elevation(contrast * scale) as f64;
            }
        }
    }
    let te = if scale.is_some() {
        (sum_te / (nw * nh) as f64) as f32
    } else {
        1.0
    };
    (next, nw, nh, te)
}

/// What the MIP-level heuristic needs of the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaskingView {
    /// The eye's world position.
    pub eye: Vec3,
    /// Angle one pixel subtends at the image centre \[rad\].
    pub pixel_rad: f32,
}

impl MaskingView {
    /// The view of `frustum`'s camera rendering `pixels_high` rows.
    pub fn of(frustum: &Frustum, pixels_high: u32) -> Self {
        Self {
            eye: frustum.camera_from_world.inverse().translation.into(),
            pixel_rad: 2.0 * frustum.tan_y / pixels_high.max(1) as f32,
        }
    }
}

/// One texture's masking table.
#[derive(Clone, Debug, PartialEq)]
struct TextureTable {
    /// Width × height \[texels\] of its full-resolution level.
    texels: f32,
    /// T_e per MIP level (see [`elevation_per_level`]).
    elevation: Vec<f32>,
}

/// Mean threshold elevation per base-colour texture and MIP level, built once per
/// scene ([`TextureMasking::new`]), and the pilot increment Δp/T_e it gives a hit
/// ([`TextureMasking::increment`]). See the module doc for the model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureMasking {
    /// Per scene texture: its table, or None where T_e = 1 everywhere.
    tables: Vec<Option<TextureTable>>,
}

/// Area of the triangle with corners `a`, `b`, `c` in its plane (2D).
#[inline]
fn area_2d(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    0.5 * (b - a).perp_dot(c - a).abs()
}

/// Area of the triangle with corners `a`, `b`, `c`.
#[inline]
fn area_3d(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

/// Texture-space area \[texels\] of triangle `t` of `mesh` under `mat`'s base-colour UV
/// transform, for a `texels`-texel texture: 0 without UVs.
fn texel_area(
    mesh: &illume_scene::Mesh,
    t: usize,
    mat: &illume_scene::Material,
    texels: f32,
) -> f32 {
    if mesh.uvs.len() != mesh.positions.len() {
        return 0.0;
    }
    let Some(&[i0, i1, i2]) = mesh.indices.get(t) else {
        return 0.0;
    };
    let uv = |i: u32| mesh.uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO);
    let uv_scale = mat
        .base_color_transform
        .map_or(1.0, |tr| (tr.scale.x * tr.scale.y).abs());
    let a = area_2d(uv(i0), uv(i1), uv(i2)) * uv_scale * texels;
    if a.is_finite() { a } else { 0.0 }
}

impl TextureMasking {
    /// No masking: every increment is Δp.
    pub fn disabled() -> Self {
        Self::default()
    }

    /// Tables for every base-colour texture of `scene` that a triangle maps with area,
    /// for the element grids `elements` (laid out for `scene`), masker contrast counted
    /// in multiples of `contrast_threshold` (see the module doc). Textures are measured
    /// in parallel.
    pub fn new(scene: &Scene, elements: &Elements, contrast_threshold: f32) -> Self {
        // Per texture: texel area and elements over the triangles mapping it.
        let mut mapped = vec![(0.0f64, 0.0f64); scene.textures.len()];
        let mut instances_of = vec![0u32; scene.meshes.len()];
        for inst in &scene.instances {
            if let Some(n) = instances_of.get_mut(inst.mesh.index()) {
                *n += 1;
            }
        }
        for (m, mesh) in scene.meshes.iter().enumerate() {
            let (Some(&count), Some(grid)) = (instances_of.get(m), elements.grids.get(m)) else {
                continue;
            };
            if count == 0 {
                continue;
            }
            for (t, material) in mesh.triangle_materials.iter().enumerate() {
                let Some(mat) = scene.materials.get(material.index()) else {
                    continue;
                };
                let Some(tex) = mat.base_color_texture else {
                    continue;
                };
                let Some(texture) = scene.textures.get(tex.index()) else {
                    continue;
                };
                let texels = texture.width as f32 * texture.height as f32;
                let area = texel_area(mesh, t, mat, texels);
                let k = grid.k.get(t).copied().unwrap_or(1) as f64;
                if area > 0.0 {
                    let entry = &mut mapped[tex.index()];
                    entry.0 += area as f64 * count as f64;
                    entry.1 += k * k * count as f64;
                }
            }
        }
        let tables = scene
            .textures
            .par_iter()
            .zip(mapped.par_iter())
            .map(|(texture, &(area, count))| {
                if !(area > 0.0 && count > 0.0) || texture.width == 0 || texture.height == 0 {
                    return None;
                }
                let element_texels = (area / count).sqrt() as f32;
                Some(TextureTable {
                    texels: texture.width as f32 * texture.height as f32,
                    elevation: elevation_per_level(texture, element_texels, contrast_threshold),
                })
            })
            .collect();
        Self { tables }
    }

    /// T_e per MIP level of `texture` (None: 1 everywhere).
    pub fn levels(&self, texture: TextureId) -> Option<&[f32]> {
        self.tables
            .get(texture.index())?
            .as_ref()
            .map(|t| t.elevation.as_slice())
    }

    /// T_e of `texture` at MIP level `level`, interpolated between levels and clamped to
    /// the pyramid (1 for a texture without a table).
    pub fn elevation(&self, texture: TextureId, level: f32) -> f32 {
        let Some(te) = self.levels(texture) else {
            return 1.0;
        };
        let last = te.len().saturating_sub(1) as f32;
        let x = if level.is_nan() {
            0.0
        } else {
            level.clamp(0.0, last)
        };
        let i = x.floor() as usize;
        let f = x - i as f32;
        match (te.get(i), te.get(i + 1)) {
            (Some(&a), Some(&b)) => a * (1.0 - f) + b * f,
            (Some(&a), None) => a,
            _ => 1.0,
        }
    }

    /// The increment Δp/T_e of a pilot whose first changed segment ends at `hit` in
    /// `scene` (the scene the hit was traced in: its instance, triangle and material are
    /// looked up there), seen from `view`: Δp where the surface is untextured or the
    /// texture has no table or the triangle's UVs or area degenerate.
    pub fn increment(&self, scene: &Scene, hit: &PhotonHit, view: &MaskingView) -> f32 {
        if self.tables.is_empty() {
            return DELTA_P;
        }
        let Some(inst) = scene.instances.get(hit.instance.index()) else {
            return DELTA_P;
        };
        let Some(mesh) = scene.meshes.get(inst.mesh.index()) else {
            return DELTA_P;
        };
        let t = hit.triangle as usize;
        let Some(mat) = mesh
            .triangle_materials
            .get(t)
            .and_then(|m| scene.materials.get(m.index()))
        else {
            return DELTA_P;
        };
        let Some(tex) = mat.base_color_texture else {
            return DELTA_P;
        };
        let Some(Some(table)) = self.tables.get(tex.index()) else {
            return DELTA_P;
        };
        let texel_area = texel_area(mesh, t, mat, table.texels);
        let [p0, p1, p2] = mesh.indices[t].map(|i| {
            inst.world_from_object
                .transform_point3(mesh.positions[i as usize])
        });
        let world_area = area_3d(p0, p1, p2);
        if !(texel_area > 0.0 && world_area > 0.0) {
            return DELTA_P;
        }
        let texels_per_m = (texel_area / world_area).sqrt();
        let to_eye = view.eye - hit.position;
        let distance = to_eye.length();
        let cos_theta = if distance > 0.0 {
            hit.geometric_normal.dot(to_eye) / distance
        } else {
            1.0
        };
        let level = mip_level(distance, cos_theta, view.pixel_rad, texels_per_m);
        DELTA_P / self.elevation(tex, level).max(1.0)
    }
}
