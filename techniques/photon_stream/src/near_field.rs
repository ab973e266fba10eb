//! Near field (beyond the paper,
//! [`near_field_rays`](crate::PhotonStreamSettings::near_field_rays) > 0): close to a
//! point, the light of the surfaces around it is gathered by rays instead of summed
//! from VSLs (the estimator and its bias are in [`crate::shade`]'s module doc).
//!
//! **First bounce at the hit** ([`gather_direct`](crate::PhotonStreamSettings::gather_direct)):
//! a hit's exitance is then ρ(y)·E_direct(y) + Φ_s/A_s, the first term by one light
//! sample (and one sky sample when there is a sky) with a shadow ray, the second from
//! photons' second and later impacts only. The light arriving straight from the lights is
//! what varies most sharply (shadow boundaries), and it no longer averages over a cell.

use crate::placement::VslSet;
use crate::shade::{VslField, far_weight};
use illume_core::sampling::{Pcg32, SampleStream, cosine_hemisphere, mix64};
use illume_core::{Frame, Ray, Rgb, Vec2};
use illume_transport::{GBuffer, World};

/// What the near-field gather reads besides the field: the VSLs (to find a hit's cell),
/// the rays per pixel, the window's squared scale, and whether hits take their first
/// bounce by next-event estimation (with photons' albedo: `filtered_textures`).
#[derive(Clone, Copy)]
pub(crate) struct NearField<'a> {
    pub(crate) vsls: &'a VslSet,
    pub(crate) rays: u32,
    pub(crate) scale2: f32,
    pub(crate) direct: bool,
    pub(crate) filtered_textures: bool,
}

/// Adds the near-field share to each gathered pixel of `out` (pixel index, Σ Φ·G).
/// Returns the rays traced.
pub(crate) fn add_near_field(
    world: &World,
    gbuffer: &GBuffer,
    field: &VslField,
    nf: NearField,
    seed: u64,
    out: &mut [(u32, Rgb)],
) -> u64 {
    // The same lattice shifts every frame (not the frame's seed): what gather noise is
    // left stays put on the screen instead of shimmering from frame to frame.
    let seed = mix64(seed ^ 0x6e65_6172);
    world.tracer.scoped(|tracer| {
        for (idx, sum) in out.iter_mut() {
            let px = gbuffer.pixels[*idx as usize]
                .as_ref()
                .expect("gathered pixels exist");
            *sum += near_gather(world, tracer, field, nf, &px.hit, seed, *idx);
        }
    });
    (out.len() as u64) * nf.rays as u64
}

/// The near-field share at `hit` (module doc), in the units of the VSL sum (Σ Φ·G,
/// before ρ/π): (π/N) Σ_k (1 − w(r_k)) Φ_k/(π A_k) over N cosine-distributed rays.
fn near_gather(
    world: &World,
    tracer: &mut illume_accel::ScopedTracer<'_>,
    field: &VslField,
    nf: NearField,
    hit: &illume_transport::SurfaceHit,
    seed: u64,
    pixel: u32,
) -> Rgb {
    /// The rank-1 lattice's generator: the golden ratio's fractional part (a Fibonacci
    /// lattice, the best-spread rank-1 set in 2D for any N).
    const ALPHA: f32 = 0.618_034;
    let n = hit.facing_normal();
    let ng = hit.facing_geometric_normal();
    let frame = Frame::from_normal(n);
    let mut rng = Pcg32::new(seed, pixel as u64);
    let shift = rng.next_2d();
    let inv_n = 1.0 / nf.rays as f32;
    let mut sum = Rgb::ZERO;
    for k in 0..nf.rays {
        let u = Vec2::new(
            ((k as f32 + 0.5) * inv_n + shift.x).fract(),
            (k as f32 * ALPHA + shift.y).fract(),
        );
        let dir = frame.to_world(cosine_hemisphere(u));
        if dir.dot(ng) <= 0.0 {
            continue; // below the geometric surface: no light from there
        }
        let ray = Ray::new(hit.spawn_origin(dir), dir);
        if nf.direct {
            sum += exitance_with_direct(world, tracer, field, nf, &ray, &mut rng);
            continue;
        }
        // A side that does not reflect (the back of a one-sided surface) or a black one
        // received no photon: its VSL side has no power, nothing to test here.
        let Some((y, position_object, front_face)) =
            world.trace_side(tracer, &ray, illume_scene::MASK_DEFAULT)
        else {
            continue;
        };
        let Some(s) = nf.vsls.nearest_on(y.instance, y.triangle, position_object) else {
            continue;
        };
        let s = s as usize;
        let area = field.area_m2[s];
        // The ray is unit, so the hit is y.t from the (offset) origin.
        let w = far_weight(y.t * y.t, area, nf.scale2);
        if w >= 1.0 {
            continue;
        }
        sum += side_flux(field, s, front_face) * ((1.0 - w) / area.max(1e-12));
    }
    sum * inv_n
}

/// The exitance a gather ray `ray` reads at its hit with
/// [`gather_direct`](crate::PhotonStreamSettings::gather_direct) (everything gathered, so
/// the window's weight is 0): the cell's Φ_s/A_s on the side facing the ray (photons'
/// later impacts) plus ρ(y)·E_direct(y) by one light sample and one sky sample.
fn exitance_with_direct(
    world: &World,
    tracer: &mut illume_accel::ScopedTracer<'_>,
    field: &VslField,
    nf: NearField,
    ray: &Ray,
    rng: &mut Pcg32,
) -> Rgb {
    let mask = illume_scene::MASK_DEFAULT;
    let Some(y) = world.trace_photon_hit(tracer, ray, mask, nf.filtered_textures) else {
        return Rgb::ZERO;
    };
    if !y.reflects {
        return Rgb::ZERO;
    }
    let mut m = Rgb::ZERO;
    if let Some(s) = nf
        .vsls
        .nearest_on(y.instance, y.triangle, y.position_object)
    {
        let s = s as usize;
        m += side_flux(field, s, y.front_face) / field.area_m2[s].max(1e-12);
    }
    let n = y.facing_normal();
    let mut irradiance = Rgb::ZERO;
    let lights = &world.lights;
    for sample in [
        lights.sample_incident(y.position, rng),
        lights.sample_sky(n, rng),
    ]
    .into_iter()
    .flatten()
    {
        let cos = sample.wi.dot(n);
        if cos <= 0.0 {
            continue;
        }
        // The shared shadow ray (a shadow terminator's too, as the reference's).
        if world
            .photon_shadow_ray(&y, &sample)
            .is_some_and(|ray| !tracer.occluded(&ray, mask))
        {
            irradiance += sample.weight * cos;
        }
    }
    m + y.albedo * irradiance
}

/// The flux leaving VSL `s` on the side a hit arrived from (`front_face`).
#[inline]
fn side_flux(field: &VslField, s: usize, front_face: bool) -> Rgb {
    if front_face {
        field.front_w[s]
    } else {
        field.back_w[s]
    }
}
