//! Step 3 of a frame, **shading**: Eq. 1 over the usable records, each contributing by
//! Eq. 17 (Eq. 4 moved along its temporal gradient by t − t_k); indirect radiance =
//! ρ/π·E. Each record counts the pixels that used it (for deletion, [`crate::expiry`]).
//!
//! **Glossy surfaces** ([`crate::radiance`]): the BRDF's Lambertian part ρ_d/π·E comes
//! from irradiance records; the specular part from radiance records (hemispherical
//! harmonics; a record made at a glossy pixel carries both, from one gather, and its
//! replacements too) where the roughness is at least `traced_roughness_max`, from
//! `traced_rays` rays per pixel below it. Surfaces rougher than `glossy_roughness_max`
//! are shaded Lambertian with the BRDF's approximate albedo.
//!
//! Pixels no record reaches because the work budget left records out of the frame
//! ([`crate::budget`]) take the mean light of their neighbours on the same surface.
//! `show_records` marks the records on the image (the paper's Fig. 1c).

use crate::radiance::{GlossyShading, diffuse_albedo};
use crate::record::{WeightedSum, interpolation_weight, usable};
use crate::state::RadianceCache;
use crate::temporal::contribution;
use illume_core::image::RgbImage;
use illume_core::{Frame, INV_PI, Rgb, Vec3};
use illume_transport::metal_rough::{DIELECTRIC_F0, MetalRough};
use illume_transport::{GBuffer, GBufferPixel, World};
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// How a pixel's surface is shaded (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Surface {
    /// ρ/π·E only: Lambertian, or rougher than `glossy_roughness_max` (ρ the BRDF's
    /// approximate albedo).
    Diffuse(Rgb),
    /// ρ_d/π·E plus the specular part, from radiance records (`traced` false) or rays.
    Glossy {
        diffuse: Rgb,
        brdf: MetalRough,
        traced: bool,
    },
}

/// A pixel's shading before the budget fill.
#[derive(Clone, Copy, Debug)]
struct ShadedPixel {
    surface: Surface,
    /// E from the records; `None`: no usable record.
    irradiance: Option<Rgb>,
    /// The specular part; `None`: a glossy pixel no radiance record reaches.
    specular: Option<Rgb>,
}

impl ShadedPixel {
    /// The indirect radiance leaving the pixel: ρ/π·E, plus the specular part on glossy
    /// surfaces (what is missing counts as zero).
    fn radiance(&self) -> Rgb {
        let e = self.irradiance.unwrap_or(Rgb::ZERO);
        match &self.surface {
            Surface::Diffuse(rho) => *rho * INV_PI * e,
            Surface::Glossy { diffuse, .. } => {
                *diffuse * INV_PI * e + self.specular.unwrap_or(Rgb::ZERO)
            }
        }
    }
}

/// The shading point and normal of a pixel, or `None` where nothing reflects: the normal
/// is the shading normal turned to the side the camera sees.
pub(crate) fn shading_point(p: &GBufferPixel) -> Option<(Vec3, Vec3)> {
    let hit = &p.hit;
    if !hit.reflects || hit.albedo == Rgb::ZERO {
        return None;
    }
    let n = if hit.front_face {
        hit.shading_normal
    } else {
        -hit.shading_normal
    };
    Some((hit.position, n))
}

/// Least cosine between the view direction and the normal a glossy pixel's specular
/// part is evaluated about ([`facing_view`]).
const MIN_VIEW_COS: f32 = 0.05;

/// `n` (unit, on the side the camera sees) bent towards the unit direction to the camera
/// `wo` just enough that the camera sees its front (cosine ≥ [`MIN_VIEW_COS`] before
/// normalising); `n` itself where it already does. At the silhouette of a smooth-shaded
/// mesh the interpolated normal can face away from a camera that sees the triangle's
/// front: the BRDF is zero for such a view, and a metal (no diffuse part, no direct
/// light there either) came out as a black pixel — 4 at 320×240 on `builtin:glossy-box`'s
/// gold sphere (issue 35 goal 5). Bending the normal is the usual repair (as Blender
/// Cycles' "ensure valid reflection" does for its reflections).
pub(crate) fn facing_view(n: Vec3, wo: Vec3) -> Vec3 {
    let c = n.dot(wo);
    if c >= MIN_VIEW_COS {
        return n;
    }
    (n + (MIN_VIEW_COS - c) * wo).normalize()
}

/// The albedo a non-Lambertian surface shaded as Lambertian gets: ρ_d plus the
/// specular lobe's normal-incidence reflectance, (1 − m)·F0 + m·base.
pub(crate) fn lambertian_albedo(brdf: &MetalRough) -> Rgb {
    diffuse_albedo(brdf)
        + Rgb::splat((1.0 - brdf.metallic) * DIELECTRIC_F0)
        + brdf.base_color * brdf.metallic
}

/// Largest distance of a neighbouring pixel's point from a pixel's tangent plane that
/// the budget fill crosses, in units of R_min (`r_min_fraction` of the scene's
/// diagonal): a pixel takes light from its own surface (however grazing the view), not
/// across a depth jump between parallel surfaces.
pub(crate) const FILL_PLANE_R_MIN: f32 = 1.0;

/// Smallest cosine between neighbouring pixels' normals that the budget fill's second
/// round crosses (60°): pixels the first round (normals within acos(1 − a²)) left
/// without light, on curved surfaces or small faces, take it across creases.
pub(crate) const FILL_CREASE_COS: f32 = 0.5;

/// Fills `values` where `wants` and no value, pass after pass, with the mean of the
/// 3×3 neighbours that have one and lie on the same surface (points at most
/// `max_step_m` from the pixel's tangent plane, normals with a cosine of at least
/// `min_cos`): the image-space
/// counterpart of the reprojection's hole filling, for pixels the work budget left
/// without records. Returns the pixels filled and those still without a value.
pub(crate) fn fill_from_neighbours(
    gbuffer: &GBuffer,
    values: &mut [Option<Rgb>],
    wants: &[bool],
    max_step_m: f32,
    min_cos: f32,
) -> (u64, u64) {
    let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
    let point = |i: usize| gbuffer.pixels[i].as_ref().and_then(shading_point);
    let mut filled = 0u64;
    for _ in 0..w.max(h) {
        let before: Vec<Option<Rgb>> = values.to_vec();
        let new: Vec<(usize, Rgb)> = (0..w * h)
            .into_par_iter()
            .filter(|&i| wants[i] && before[i].is_none())
            .filter_map(|i| {
                let (p, n) = point(i)?;
                let (x, y) = (i % w, i / w);
                let (mut sum, mut count) = (Rgb::ZERO, 0u32);
                for ny in y.saturating_sub(1)..(y + 2).min(h) {
                    for nx in x.saturating_sub(1)..(x + 2).min(w) {
                        let j = ny * w + nx;
                        let (Some(v), Some((q, m))) = (before[j], point(j)) else {
                            continue;
                        };
                        if (q - p).dot(n).abs() <= max_step_m && m.dot(n) >= min_cos {
                            sum += v;
                            count += 1;
                        }
                    }
                }
                (count > 0).then(|| (i, sum * (1.0 / count as f32)))
            })
            .collect();
        if new.is_empty() {
            break;
        }
        filled += new.len() as u64;
        for (i, v) in new {
            values[i] = Some(v);
        }
    }
    let unfilled = (0..w * h)
        .filter(|&i| wants[i] && values[i].is_none())
        .count() as u64;
    (filled, unfilled)
}

impl RadianceCache {
    /// How the surface of `hit` is shaded.
    pub(crate) fn surface(&self, hit: &illume_transport::SurfaceHit) -> Surface {
        let brdf = hit.brdf();
        if brdf.is_lambertian() {
            return Surface::Diffuse(brdf.base_color);
        }
        if brdf.roughness > self.settings.glossy_roughness_max {
            return Surface::Diffuse(lambertian_albedo(&brdf));
        }
        Surface::Glossy {
            diffuse: diffuse_albedo(&brdf),
            brdf,
            traced: brdf.roughness < self.settings.traced_roughness_max,
        }
    }

    /// True when the pixel's surface needs radiance records.
    pub(crate) fn needs_radiance(&self, hit: &illume_transport::SurfaceHit) -> bool {
        matches!(self.surface(hit), Surface::Glossy { traced: false, .. })
    }

    /// Step 3: Eq. 1 with Eq. 17 at every pixel, times ρ/π, plus the specular part of
    /// glossy pixels; counts each record's uses. When the work budget left records out
    /// of this frame, pixels no record reaches take their neighbours' light
    /// ([`fill_from_neighbours`]).
    pub(crate) fn shade(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let w = gbuffer.width.max(1) as usize;
        for u in &self.uses {
            u.store(0, Ordering::Relaxed);
        }
        let this = &*self;
        let mut shaded: Vec<Option<ShadedPixel>> = gbuffer
            .pixels
            .par_iter()
            .enumerate()
            .map(|(i, p)| this.shade_pixel(world, i, p.as_ref()?))
            .collect();
        if self.counters.skipped > 0 {
            self.fill_unreached(gbuffer, &mut shaded);
        }
        let mut img = RgbImage::filled(gbuffer.width, gbuffer.height, Rgb::ZERO);
        img.pixels_mut()
            .par_iter_mut()
            .zip(shaded.par_iter())
            .for_each(|(out, s)| {
                if let Some(s) = s {
                    *out = s.radiance();
                }
            });
        debug_assert_eq!(img.pixels().len(), w * gbuffer.height as usize);
        img
    }

    /// Pixel `i` (`px`) of the G-buffer: its surface, E from the usable records (Eq. 1
    /// with Eq. 17) and the specular part; counts the records' uses. `None` where
    /// nothing reflects.
    fn shade_pixel(&self, world: &World, i: usize, px: &GBufferPixel) -> Option<ShadedPixel> {
        let (accuracy, smooth) = (self.settings.accuracy, self.settings.smooth_weights);
        let frame = self.frame;
        let (p, n) = shading_point(px)?;
        let surface = self.surface(&px.hit);
        let mut sum = WeightedSum::default();
        self.octree.for_each_containing(p, |id| {
            if let Some(s) = &self.slots[id as usize] {
                let error = s.record.ward_error(p, n);
                if usable(error, accuracy) {
                    sum.add(
                        interpolation_weight(error, accuracy, smooth),
                        contribution(&s.record, p, n, frame),
                    );
                    self.uses[id as usize].fetch_add(1, Ordering::Relaxed);
                }
            }
        });
        // The specular part is seen from `to_camera`: at a silhouette the interpolated
        // normal may face away from it (`facing_view`).
        let n_view = facing_view(n, px.to_camera);
        let specular = match surface {
            Surface::Diffuse(_) => Some(Rgb::ZERO),
            Surface::Glossy {
                brdf, traced: true, ..
            } => Some(GlossyShading::traced(
                world,
                p,
                n_view,
                &brdf,
                px.to_camera,
                self.settings.traced_rays,
                self.settings.seed,
                i as u64,
                &self.record_settings.path,
            )),
            Surface::Glossy {
                brdf,
                traced: false,
                ..
            } => self.specular_from_records(p, n_view, &brdf, px.to_camera, frame),
        };
        Some(ShadedPixel {
            surface,
            irradiance: sum.result(),
            specular,
        })
    }

    /// The budget fill: pixels of `shaded` without E (or without their specular part)
    /// take their neighbours' ([`fill_from_neighbours`]), on the same surface first,
    /// then across creases and curvature (normals within 60°) for what that left.
    /// Counts `pixels_filled` and `pixels_unfilled`.
    fn fill_unreached(&mut self, gbuffer: &GBuffer, shaded: &mut [Option<ShadedPixel>]) {
        let accuracy = self.settings.accuracy;
        let max_step_m = FILL_PLANE_R_MIN * self.record_settings.r_min_m;
        let min_cos = 1.0 - accuracy * accuracy;
        let (mut e, mut specular): (Vec<_>, Vec<_>) = shaded
            .iter()
            .map(|s| s.map_or((None, None), |s| (s.irradiance, s.specular)))
            .unzip();
        let wants_e: Vec<bool> = shaded.iter().map(Option::is_some).collect();
        let wants_specular: Vec<bool> = shaded
            .iter()
            .map(|s| {
                matches!(
                    s,
                    Some(ShadedPixel {
                        surface: Surface::Glossy { traced: false, .. },
                        ..
                    })
                )
            })
            .collect();
        let mut filled = 0;
        let mut unfilled = 0;
        for cos in [min_cos, FILL_CREASE_COS] {
            (filled, unfilled) = {
                let (f, u) = fill_from_neighbours(gbuffer, &mut e, &wants_e, max_step_m, cos);
                (filled + f, u)
            };
            fill_from_neighbours(gbuffer, &mut specular, &wants_specular, max_step_m, cos);
        }
        for ((s, e), sp) in shaded.iter_mut().zip(e).zip(specular) {
            if let Some(s) = s {
                (s.irradiance, s.specular) = (e, sp);
            }
        }
        self.counters.filled = filled;
        self.counters.unfilled = unfilled;
    }

    /// The specular part at `p` (normal `n`, view `wo`) from the usable radiance
    /// records: their coefficients moved to `p` (translation and temporal gradients),
    /// rotated into the point's frame, averaged with Ward's weights, shaded with f_s's
    /// BRDF×cos coefficients. `None` where no radiance record is usable.
    pub(crate) fn specular_from_records(
        &self,
        p: Vec3,
        n: Vec3,
        brdf: &MetalRough,
        wo: Vec3,
        frame: u32,
    ) -> Option<Rgb> {
        let to = Frame::from_normal(n);
        let len = self.glossy.basis().len();
        let mut acc = vec![Rgb::ZERO; len];
        let mut total = 0.0f32;
        let mut moved = vec![Rgb::ZERO; len];
        self.octree.for_each_containing(p, |id| {
            let Some(s) = &self.slots[id as usize] else {
                return;
            };
            let Some(data) = &s.radiance else { return };
            let error = s.record.ward_error(p, n);
            if !usable(error, self.settings.accuracy) {
                return;
            }
            let offset = p - s.record.position;
            let dt = frame as f32 - s.record.frame as f32;
            for (((m, c), g), t) in moved
                .iter_mut()
                .zip(&data.coefficients)
                .zip(&data.translation_gradient)
                .zip(&data.temporal_gradient)
            {
                *m = *c + g.dot(offset) + *t * dt;
            }
            let from = Frame::from_normal(s.record.normal);
            let rotated = self.glossy.rotate(&moved, &from, &to);
            let weight = interpolation_weight(
                error.max(1e-6),
                self.settings.accuracy,
                self.settings.smooth_weights,
            );
            for (a, r) in acc.iter_mut().zip(&rotated) {
                *a += *r * weight;
            }
            total += weight;
        });
        if total <= 0.0 {
            return None;
        }
        let b = self
            .glossy
            .specular_coefficients_tabulated(brdf, to.to_local(wo));
        Some((crate::hsh::shade(&b, &acc) * (1.0 / total)).max(Rgb::ZERO))
    }

    /// Marks each live record the camera sees on `img` (`show_records`, the paper's
    /// Fig. 1c): the pixel its position projects to, coloured from red (a lifespan of
    /// one frame) to green (`max_age_frames`), as in the paper, at 8 × the image's mean luminance. A
    /// record counts as seen when its pixel's surface is not nearer the camera than the
    /// record by more than 2 R_min.
    pub(crate) fn draw_records(&self, world: &World, gbuffer: &GBuffer, img: &mut RgbImage) {
        let camera = &world.scene.camera;
        let camera_from_world = camera.world_from_camera.inverse();
        let eye = Vec3::from(camera.world_from_camera.translation);
        let (w, h) = (gbuffer.width, gbuffer.height);
        let tan_half_y = (camera.yfov_rad * 0.5).tan();
        let aspect = w as f32 / h.max(1) as f32;
        let level = 8.0 * illume_core::luminance(img.mean()).max(1e-6);
        let max_age = self.settings.max_age_frames.max(2) as f32;
        let slack = 2.0 * self.record_settings.r_min_m;
        for slot in self.slots.iter().flatten() {
            let r = &slot.record;
            let q = camera_from_world.transform_point3(r.position);
            if q.z >= 0.0 {
                continue;
            }
            let ndc_x = q.x / (-q.z * tan_half_y * aspect);
            let ndc_y = q.y / (-q.z * tan_half_y);
            if !(ndc_x.abs() < 1.0 && ndc_y.abs() < 1.0) {
                continue;
            }
            let x = (((ndc_x + 1.0) * 0.5 * w as f32) as u32).min(w - 1);
            let y = (((1.0 - ndc_y) * 0.5 * h as f32) as u32).min(h - 1);
            let Some(px) = gbuffer.get(x, y) else {
                continue;
            };
            if (px.hit.position - eye).length() < (r.position - eye).length() - slack {
                continue;
            }
            let t = ((r.lifespan_frames as f32 - 1.0) / (max_age - 1.0)).clamp(0.0, 1.0);
            *img.get_mut(x, y) = Rgb::new(1.0 - t, t, 0.0) * level;
        }
    }
}
