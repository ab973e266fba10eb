//! Near field (beyond the paper,
//! [`near_field_rays`](crate::PhotonStreamSettings::near_field_rays) > 0): close to a
//! point, the light of the surfaces around it is gathered by rays instead of summed
//! from VSLs (the estimator and its bias are in [`crate::shade`]'s module doc).

use crate::placement::VslSet;
use crate::shade::{VslField, far_weight};
use illume_core::sampling::{Pcg32, SampleStream, cosine_hemisphere, mix64};
use illume_core::{Frame, Ray, Rgb, Vec2};
use illume_transport::{GBuffer, World};

/// What the near-field gather reads besides the field: the VSLs (to find a hit's cell),
/// the rays per pixel and the window's squared scale.
#[derive(Clone, Copy)]
pub(crate) struct NearField<'a> {
    pub(crate) vsls: &'a VslSet,
    pub(crate) rays: u32,
    pub(crate) scale2: f32,
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
        let phi = if front_face {
            field.front_w[s]
        } else {
            field.back_w[s]
        };
        sum += phi * ((1.0 - w) / area.max(1e-12));
    }
    sum * inv_n
}
