//! The photon-path generator shared by every photon technique.
//!
//! A photon path is a pure function of its [`SampleStream`]: emission uses dimensions
//! 0–4 (light choice, position, direction), then each bounce uses three (Russian
//! roulette, direction). Re-tracing photon *i* with the same stream (a PCG stream keyed
//! by *i*, or the Halton point *i*) therefore gives the same path bit for bit, whatever
//! the thread count or order — selective photon tracing re-traces paths to subtract
//! their old energy.

use crate::lights::EmissionSample;
use crate::metal_rough::MetalRough;
use crate::surface::PhotonHit;
use crate::world::World;
use illume_core::sampling::{ONE_MINUS_EPSILON, SampleStream, cosine_hemisphere};
use illume_core::{Frame, Ray, Rgb, Vec2, Vec3, channel_mean};

/// Settings of photon paths.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonPathSettings {
    /// Longest path in bounces (impacts after the first); a safety net behind Russian
    /// roulette. Default 32.
    pub max_bounces: u32,
    /// Instances visible to photons (`ray_mask & instance.mask != 0`).
    pub mask: u32,
    /// Read base-colour textures through copies box-filtered to at most
    /// [`PHOTON_TEXTURE_SIDE`](crate::hit_tables::PHOTON_TEXTURE_SIDE) texels a side, one
    /// texel per impact ([`HitTables::sample_filtered`](crate::hit_tables::HitTables::sample_filtered)):
    /// each region keeps its mean albedo, so photon estimates gathered over regions
    /// larger than a filtered texel are unchanged in expectation, and large textures stop
    /// costing a cache miss per impact. False (default): full resolution, the albedo
    /// the renderer sees.
    pub filtered_textures: bool,
    /// Reuse the Russian-roulette number as the first coordinate of the bounce direction
    /// (Shirley et al.'s remapping, as selective photon tracing's §4.1 does: a surviving
    /// `u < p` continues as `u / p`), so each bounce reads two sample dimensions instead
    /// of three. Quasi-random paths then keep one more bounce coherent for the same
    /// Halton bases. False (default): three dimensions per bounce.
    pub remap_roulette: bool,
}

impl Default for PhotonPathSettings {
    fn default() -> Self {
        Self {
            max_bounces: 32,
            mask: illume_scene::MASK_DEFAULT,
            filtered_textures: false,
            remap_roulette: false,
        }
    }
}

/// One photon impact on a surface's reflecting side.
#[derive(Clone, Copy, Debug)]
pub struct PhotonImpact {
    /// The surface hit (positions, normals, albedo, instance, triangle).
    pub hit: PhotonHit,
    /// Unit direction the photon travelled in.
    pub incoming: Vec3,
    /// Flux arriving with the photon \[W\] (per photon out of one; divide by the batch's
    /// photon count).
    pub flux: Rgb,
    /// 0 for the first impact after leaving the light, 1 after one reflection, …
    pub bounce: u32,
}

/// What happened to a photon path.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhotonPathStats {
    /// Impacts reported.
    pub impacts: u32,
    /// Rays traced (impacts plus escapes).
    pub rays: u32,
}

/// A photon path in flight, resumable: the ray of its next segment, the flux it carries
/// and the bounces it has made. With the sampler's state, it is everything the rest of
/// the path depends on, so a copy (and a copy of the sampler) can continue in another
/// world — selective photon tracing traces a path's shared prefix once, then continues
/// it twice from the first segment that met a change, with negative energy in the old
/// scene and positive energy in the new one.
///
/// [`trace_photon`] is [`PhotonPath::emit`] followed by [`PhotonPath::run`].
#[derive(Clone, Copy, Debug)]
pub struct PhotonPath {
    /// The next segment (origin, unit direction).
    pub ray: Ray,
    /// Flux the photon carries \[W\] (per photon out of one).
    pub flux: Rgb,
    /// Impacts made so far (the next impact's [`PhotonImpact::bounce`]).
    pub bounce: u32,
}

impl PhotonPath {
    /// A path leaving a light along `emission`.
    #[inline]
    pub fn emitted(emission: EmissionSample) -> Self {
        Self {
            ray: emission.ray,
            flux: emission.flux,
            bounce: 0,
        }
    }

    /// A photon leaving a light of `world` chosen by power (sample dimensions 0–4, see
    /// [`LightSet::sample_emission`](crate::lights::LightSet::sample_emission)); None
    /// when the world has no light.
    #[inline]
    pub fn emit(world: &World, sampler: &mut impl SampleStream) -> Option<Self> {
        world.lights.sample_emission(sampler).map(Self::emitted)
    }

    /// True while the path may trace another segment (`bounce ≤ max_bounces`).
    #[inline]
    pub fn alive(&self, settings: &PhotonPathSettings) -> bool {
        self.bounce <= settings.max_bounces
    }

    /// The surface the next segment ends on, among instances visible to `mask`, traced
    /// with `tracer` (`world`'s, [`Tracer::scoped`](illume_accel::Tracer::scoped)). None
    /// when it escapes. The hit may be on a side that does not reflect (the path then
    /// ends there, absorbed).
    #[inline]
    pub fn trace(
        &self,
        world: &World,
        tracer: &mut illume_accel::ScopedTracer<'_>,
        mask: u32,
        settings: &PhotonPathSettings,
    ) -> Option<PhotonHit> {
        world.trace_photon_hit(tracer, &self.ray, mask, settings.filtered_textures)
    }

    /// The impact at `hit` (which must reflect), and the path moved on past it. On a
    /// Lambertian surface: Russian roulette on the mean albedo (survival probability `p`,
    /// flux scaled by ρ/p), then a cosine-distributed direction. On any other
    /// (metallic > 0 or roughness < 1): a direction sampled from the glTF
    /// metallic-roughness BRDF the reference path tracer uses ([`MetalRough::sample`],
    /// two more sample dimensions), then roulette on the mean of its weight `f·cosθ/pdf`
    /// — photons leave glossy surfaces as light does, not as from a Lambertian one
    /// (Dmitriev et al. 2002: "arbitrary surface reflectance functions are properly
    /// processed"). Returns the impact and whether the path continues.
    #[inline]
    pub fn scatter(
        &mut self,
        hit: PhotonHit,
        sampler: &mut impl SampleStream,
        settings: &PhotonPathSettings,
    ) -> (PhotonImpact, bool) {
        let impact = PhotonImpact {
            hit,
            incoming: self.ray.dir,
            flux: self.flux,
            bounce: self.bounce,
        };
        let u_rr = sampler.next_1d();
        let brdf = MetalRough {
            base_color: hit.albedo,
            metallic: hit.metallic,
            roughness: hit.roughness,
        };
        if !brdf.is_lambertian() {
            return (impact, self.scatter_by(&brdf, &hit, u_rr, sampler));
        }
        let p = channel_mean(hit.albedo).min(1.0);
        let survives = p > 0.0 && u_rr < p;
        let u_dir = if !settings.remap_roulette {
            sampler.next_2d()
        } else if survives {
            Vec2::new((u_rr / p).min(ONE_MINUS_EPSILON), sampler.next_1d())
        } else {
            Vec2::ZERO
        };
        let next = survives
            .then(|| diffuse_direction(hit.facing_normal(), u_dir))
            // Below the geometric surface (a shading-normal artefact): absorbed.
            .filter(|wi| wi.dot(hit.facing_geometric_normal()) > 0.0);
        self.bounce += 1;
        if let Some(wi) = next {
            // Lambertian reflection sampled by cosine: the path weight f·cosθ/pdf is ρ.
            self.flux *= hit.albedo / p;
            self.ray = Ray::new(hit.spawn_origin(wi), wi);
        }
        (impact, next.is_some())
    }

    /// [`PhotonPath::scatter`] on a surface that is not Lambertian: the next segment by
    /// `brdf` at `hit`, roulette number `u_rr`; true when the path continues.
    #[inline(never)]
    fn scatter_by(
        &mut self,
        brdf: &MetalRough,
        hit: &PhotonHit,
        u_rr: f32,
        sampler: &mut impl SampleStream,
    ) -> bool {
        let frame = Frame::from_normal(hit.facing_normal());
        let wo = frame.to_local(-self.ray.dir);
        let u_lobe = sampler.next_1d();
        let u = sampler.next_2d();
        self.bounce += 1;
        let next = brdf
            .sample(wo, u_lobe, u)
            .and_then(|s| {
                let p = channel_mean(s.weight).min(1.0);
                (p > 0.0 && u_rr < p).then(|| (frame.to_world(s.wi), s.weight / p))
            })
            // Below the geometric surface (a shading-normal artefact): absorbed.
            .filter(|(wi, _)| wi.dot(hit.facing_geometric_normal()) > 0.0);
        match next {
            Some((wi, weight)) => {
                self.flux *= weight;
                self.ray = Ray::new(hit.spawn_origin(wi), wi);
                true
            }
            None => false,
        }
    }

    /// Follows the path to its end in `world` (visible instances: `settings.mask`),
    /// calling `on_impact` for every impact on a reflecting side and counting into
    /// `stats`.
    #[inline]
    pub fn run(
        mut self,
        world: &World,
        tracer: &mut illume_accel::ScopedTracer<'_>,
        sampler: &mut impl SampleStream,
        settings: &PhotonPathSettings,
        stats: &mut PhotonPathStats,
        mut on_impact: impl FnMut(&PhotonImpact),
    ) {
        while self.alive(settings) {
            stats.rays += 1;
            let Some(hit) = self.trace(world, tracer, settings.mask, settings) else {
                break;
            };
            if !hit.reflects {
                break;
            }
            stats.impacts += 1;
            // The next ray first, the caller's bookkeeping after: the path is one chain
            // of dependent work, and the impact's bookkeeping (independent of it) then
            // overlaps the next traversal instead of delaying its start.
            let (impact, continues) = self.scatter(hit, sampler, settings);
            on_impact(&impact);
            if !continues {
                break;
            }
        }
    }
}

/// Traces one photon: emission from a light chosen by power, then diffuse bounces with
/// Russian roulette on the surface albedo (survival probability = mean albedo, flux
/// scaled by ρ/p, so photons keep near-equal power). Calls `on_impact` for every impact
/// on a reflecting side (front face, or either face of a double-sided material); an
/// impact on the back of a one-sided surface absorbs the photon unreported.
/// `on_impact` runs while the path holds this thread's traversal stack
/// ([`Tracer::scoped`](illume_accel::Tracer::scoped)): rays it traces itself work but
/// each allocates a stack.
pub fn trace_photon(
    world: &World,
    sampler: &mut impl SampleStream,
    settings: &PhotonPathSettings,
    on_impact: impl FnMut(&PhotonImpact),
) -> PhotonPathStats {
    let mut stats = PhotonPathStats::default();
    let Some(path) = PhotonPath::emit(world, sampler) else {
        return stats;
    };
    // One traversal stack for the whole path.
    world
        .tracer
        .scoped(|tracer| path.run(world, tracer, sampler, settings, &mut stats, on_impact));
    stats
}

/// The direction of [`lambert_sample`](crate::bsdf::lambert_sample) about the unit
/// `normal` for `u`, without renormalising: the frame is orthonormal and the local
/// direction unit, so the result is unit to rounding, and a photon path is one long
/// chain of dependent arithmetic where a square root and a division per bounce show.
#[inline]
fn diffuse_direction(normal: Vec3, u: Vec2) -> Vec3 {
    Frame::from_normal(normal).to_world(cosine_hemisphere(u))
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{HaltonScramble, HaltonStream, Pcg32, mix64};
    use rayon::prelude::*;

    fn path(world: &World, i: u64) -> Vec<(u32, u32, [u32; 3], [u32; 3])> {
        let mut out = Vec::new();
        let mut s = Pcg32::new(mix64(i), i);
        trace_photon(world, &mut s, &PhotonPathSettings::default(), |imp| {
            out.push((
                imp.hit.instance.0,
                imp.hit.triangle,
                imp.hit.position.to_array().map(f32::to_bits),
                imp.flux.to_array().map(f32::to_bits),
            ));
        });
        out
    }

    /// A photon arriving at `theta` from the normal on a plane (+Z) of `albedo`,
    /// `metallic`, `roughness`.
    fn plane_hit(albedo: Rgb, metallic: f32, roughness: f32) -> PhotonHit {
        PhotonHit {
            position: Vec3::ZERO,
            position_object: Vec3::ZERO,
            geometric_normal: Vec3::Z,
            shading_normal: Vec3::Z,
            albedo,
            instance: illume_scene::InstanceId(0),
            triangle: 0,
            barycentrics: Vec2::ZERO,
            front_face: true,
            reflects: true,
            metallic,
            roughness,
        }
    }

    /// The mean flux a photon of flux 1 keeps after one scatter (0 when absorbed), over
    /// `n` photons, and its standard error.
    fn mean_scattered_flux(hit: PhotonHit, theta: f32, n: u32) -> (Rgb, Rgb) {
        let dir = Vec3::new(theta.sin(), 0.0, -theta.cos());
        let settings = PhotonPathSettings::default();
        let mut s = Pcg32::new(7, 11);
        let (mut sum, mut sq) = (Rgb::ZERO, Rgb::ZERO);
        for _ in 0..n {
            let mut path = PhotonPath {
                ray: Ray::new(Vec3::new(-theta.sin(), 0.0, theta.cos()), dir),
                flux: Rgb::ONE,
                bounce: 0,
            };
            let (_, continues) = path.scatter(hit, &mut s, &settings);
            let f = if continues { path.flux } else { Rgb::ZERO };
            sum += f;
            sq += f * f;
        }
        let mean = sum / n as f32;
        let var = (sq / n as f32 - mean * mean).max(Rgb::ZERO);
        (mean, (var / n as f32).powf(0.5))
    }

    /// ∫ f(wo, wi) cosθᵢ dωᵢ over the hemisphere by the midpoint rule in (cosθ, φ):
    /// the energy a surface reflects for light from `wo`, independent of any sampling.
    fn directional_albedo(brdf: &crate::metal_rough::MetalRough, wo: Vec3) -> Rgb {
        let (nc, np) = (600usize, 600usize);
        let mut sum = Rgb::ZERO;
        for i in 0..nc {
            let c = (i as f32 + 0.5) / nc as f32;
            let sin = (1.0 - c * c).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), c);
                sum += brdf.eval(wo, wi) * c;
            }
        }
        // dω = dcosθ·dφ.
        sum * (std::f32::consts::TAU / (nc * np) as f32)
    }

    #[test]
    fn photons_leave_glossy_surfaces_with_the_brdfs_energy() {
        // A white rough metal reflects less than 1 (single scattering): a photon
        // scattered as if it were Lambertian would keep all its flux.
        let theta = 40f32.to_radians();
        let wo = Vec3::new(-theta.sin(), 0.0, theta.cos());
        for (albedo, metallic, roughness) in [
            (Rgb::ONE, 1.0, 0.6),
            (Rgb::new(1.0, 0.78, 0.34), 1.0, 0.3),
            (Rgb::new(0.8, 0.5, 0.2), 0.0, 0.4),
            (Rgb::splat(0.7), 0.5, 0.8),
        ] {
            let hit = plane_hit(albedo, metallic, roughness);
            let brdf = crate::metal_rough::MetalRough {
                base_color: albedo,
                metallic,
                roughness,
            };
            let expected = directional_albedo(&brdf, wo);
            let (mean, se) = mean_scattered_flux(hit, theta, 200_000);
            let err = (mean - expected).abs();
            assert!(
                err.cmple(se * 5.0 + Rgb::splat(2e-3)).all(),
                "{albedo} metallic {metallic} roughness {roughness}: photons keep {mean} \
                 (± {se}), the BRDF reflects {expected}"
            );
        }
        // The white metal loses energy: the test tells a Lambertian scatter apart.
        let white = crate::metal_rough::MetalRough {
            base_color: Rgb::ONE,
            metallic: 1.0,
            roughness: 0.6,
        };
        assert!(directional_albedo(&white, wo).max_element() < 0.95);
        // Lambertian surfaces keep their cosine scatter: the mean flux is the albedo.
        let (mean, se) = mean_scattered_flux(plane_hit(Rgb::splat(0.6), 0.0, 1.0), theta, 50_000);
        assert!(
            ((mean - Rgb::splat(0.6)).abs())
                .cmple(se * 5.0 + Rgb::splat(1e-6))
                .all(),
            "{mean}"
        );
    }

    #[test]
    fn same_index_same_path_regardless_of_threads_and_order() {
        let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
        let sequential: Vec<_> = (0..2000u64).map(|i| path(&world, i)).collect();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let mut parallel_reversed: Vec<_> = pool.install(|| {
            (0..2000u64)
                .rev()
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|i| (i, path(&world, i)))
                .collect()
        });
        parallel_reversed.sort_by_key(|(i, _)| *i);
        for (i, p) in parallel_reversed {
            assert_eq!(p, sequential[i as usize], "photon {i} differs");
        }
        assert!(
            sequential.iter().filter(|p| !p.is_empty()).count() > 1000,
            "most photons hit something"
        );
        // Halton-indexed photons are reproducible too.
        let scramble = HaltonScramble::new(1);
        let halton = |i: u64| {
            let mut v = Vec::new();
            trace_photon(
                &world,
                &mut HaltonStream::scrambled(i, &scramble),
                &PhotonPathSettings::default(),
                |imp| v.push(imp.hit.position.to_array().map(f32::to_bits)),
            );
            v
        };
        for i in [0u64, 1, 17, 1000, 123_456] {
            assert_eq!(halton(i), halton(i));
        }
    }

    #[test]
    fn furnace_photon_flux_follows_the_neumann_series() {
        // Closed sphere, ρ = 0.5: every photon hits; the expected total flux over all
        // impacts per emitted photon is Φ(1 + ρ + ρ² + …) = 2Φ.
        let world = World::new(illume_scene::builtin::furnace(0.5, Rgb::ONE));
        let n = 200_000u64;
        let total: f64 = (0..n)
            .into_par_iter()
            .map(|i| {
                let mut s = Pcg32::new(7, i);
                let mut sum = 0.0f64;
                trace_photon(
                    &world,
                    &mut s,
                    &PhotonPathSettings {
                        max_bounces: 200,
                        ..Default::default()
                    },
                    |imp| sum += imp.flux.x as f64,
                );
                sum
            })
            .sum();
        let phi = world.lights.total_power().x as f64;
        let ratio = total / n as f64 / phi;
        assert!((ratio - 2.0).abs() < 0.02, "ratio {ratio}");
    }
}
