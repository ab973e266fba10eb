//! The path kernel shared by every technique that needs radiance arriving along a ray:
//! unidirectional path tracing with next-event estimation and multiple importance
//! sampling (power heuristic) between light sampling and BSDF sampling, split by bounce
//! count. The reference technique renders with it; radiance caching fills its records
//! with it.

use crate::bsdf::{lambert_pdf, lambert_sample, russian_roulette};
use crate::{SurfaceHit, World};
use illume_core::sampling::SampleStream;
use illume_core::{Frame, INV_PI, Ray, Rgb, Vec3};

/// Path length settings for [`radiance`] and [`continue_path`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSettings {
    /// Reflections after which Russian roulette may end a path (unbiased: survivors are
    /// re-weighted). Lower = faster, noisier deep bounces. Default 3.
    pub rr_start_depth: u32,
    /// Hard cap on reflections: paths end after this many, with the light their last
    /// sampled direction finds still counted, so `1` gives exact direct light (biased
    /// only when paths would have gone on; at the default they practically never do, as
    /// roulette ends them long before). Default 1024.
    pub max_depth: u32,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self {
            rr_start_depth: 3,
            max_depth: 1024,
        }
    }
}

/// Radiance of one path split by how many reflections it took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathRadiance {
    /// Emission seen directly (no reflection).
    pub emitted: Rgb,
    /// Light reflected once.
    pub direct: Rgb,
    /// Light reflected two or more times.
    pub indirect: Rgb,
}

impl PathRadiance {
    /// Everything.
    pub fn total(&self) -> Rgb {
        self.emitted + self.direct + self.indirect
    }

    fn add(&mut self, bounces: u32, value: Rgb) {
        match bounces {
            0 => self.emitted += value,
            1 => self.direct += value,
            _ => self.indirect += value,
        }
    }
}

#[inline]
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Radiance arriving along `ray` (a camera ray, or any other), split by bounce count.
pub fn radiance(
    world: &World,
    ray: &Ray,
    sampler: &mut impl SampleStream,
    settings: &PathSettings,
) -> PathRadiance {
    match world.trace(ray, illume_scene::MASK_DEFAULT) {
        Some(hit) => {
            let mut out = PathRadiance {
                emitted: hit.emission,
                ..Default::default()
            };
            continue_path(world, hit, -ray.dir, sampler, settings, &mut out);
            out
        }
        None => PathRadiance {
            emitted: world.lights.sky_radiance(ray.dir),
            ..Default::default()
        },
    }
}

/// Radiance leaving `first` towards `wo` (the unit direction back along the ray that
/// found it), reflected one or more times (`direct` and `indirect`; `first`'s own
/// emission is not added). Each vertex samples the light (next-event estimation) and its
/// BRDF (the glTF metallic-roughness model, [`crate::metal_rough`]; exactly the
/// Lambertian kernel with its cosine sampling for Lambertian surfaces), combined by the
/// power heuristic.
pub fn continue_path(
    world: &World,
    first: SurfaceHit,
    wo: Vec3,
    sampler: &mut impl SampleStream,
    settings: &PathSettings,
    out: &mut PathRadiance,
) {
    let mut hit = first;
    let mut wo = wo;
    let mut throughput = Rgb::ONE;
    // `bounces` = reflections so far on this path before the current vertex reflects.
    let mut bounces = 0u32;
    loop {
        if hit.is_black() {
            return;
        }
        let n = hit.facing_normal();
        let ng = hit.facing_geometric_normal();
        // Lambertian vertices take exactly the Lambertian kernel (same sample use, same
        // arithmetic: images of Lambertian scenes do not depend on the glossy code).
        let frame = (!hit.is_lambertian()).then(|| Frame::from_normal(n));
        let brdf = hit.brdf();
        let f_lambert = hit.albedo * INV_PI;
        // Light arriving along `ls` (a sample of an emitter or of the sky), weighted by
        // MIS against BSDF sampling (delta lights, pdf 0, get weight 1).
        let shade = |ls: crate::LightSample, out: &mut PathRadiance| {
            let cos = n.dot(ls.wi);
            // Light from below the facet reaches the shading normal only at a shadow
            // terminator (`World::shadow_ray`); BSDF sampling never goes there (below),
            // so next-event estimation alone carries it, at MIS weight 1.
            if cos > 0.0 && world.unoccluded(&hit, &ls) {
                let (f, bsdf_pdf) = match &frame {
                    None => (f_lambert, lambert_pdf(n, ls.wi)),
                    Some(fr) => {
                        let (lo, li) = (fr.to_local(wo), fr.to_local(ls.wi));
                        (brdf.eval(lo, li), brdf.pdf(lo, li))
                    }
                };
                let w = if ls.pdf > 0.0 && ng.dot(ls.wi) > 0.0 {
                    power_heuristic(ls.pdf, bsdf_pdf)
                } else {
                    1.0
                };
                out.add(bounces + 1, throughput * f * ls.weight * (cos * w));
            }
        };
        // Next-event estimation: light reaching this vertex directly.
        if let Some(ls) = world.lights.sample_incident(hit.position, sampler) {
            shade(ls, out);
        }
        // The sky, sampled on its own (cosine-weighted about the normal, or by the
        // environment map), MIS against BSDF sampling. Scenes without a sky draw no
        // numbers here.
        let sky = world.lights.sky().is_some();
        if sky && let Some(ls) = world.lights.sample_sky(n, sampler) {
            shade(ls, out);
        }
        // BSDF sampling.
        let u_rr = sampler.next_1d();
        let (wi, weight, pdf) = match &frame {
            None => {
                let s = lambert_sample(hit.albedo, n, sampler.next_2d());
                (s.wi, s.weight, s.pdf)
            }
            Some(fr) => {
                let u_lobe = sampler.next_1d();
                let Some(s) = brdf.sample(fr.to_local(wo), u_lobe, sampler.next_2d()) else {
                    return;
                };
                (fr.to_world(s.wi).normalize(), s.weight, s.pdf)
            }
        };
        if wi.dot(ng) <= 0.0 {
            return;
        }
        throughput *= weight;
        bounces += 1;
        if bounces >= settings.rr_start_depth {
            match russian_roulette(throughput, u_rr) {
                Some(w) => throughput *= w,
                None => return,
            }
        }
        let ray = Ray::new(hit.spawn_origin(wi), wi);
        let Some(h) = world.tracer.intersect(&ray, illume_scene::MASK_DEFAULT) else {
            if sky {
                let w = power_heuristic(pdf, world.lights.sky_pdf(n, wi));
                out.add(bounces, throughput * world.lights.sky_radiance(wi) * w);
            }
            return;
        };
        let next = world.surface(&ray, &h);
        if next.emission != Rgb::ZERO {
            let light_pdf = world.lights.pdf_triangle_hit(
                next.instance,
                next.triangle,
                hit.position,
                next.position,
            );
            let w = power_heuristic(pdf, light_pdf);
            out.add(bounces, throughput * next.emission * w);
        }
        // The cap ends the path after the emission its last sampled ray found, which
        // completes that reflection's MIS pair: `max_depth = 1` is exact direct light.
        if bounces >= settings.max_depth {
            return;
        }
        wo = -wi;
        hit = next;
    }
}
