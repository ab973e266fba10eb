//! Visibility (beyond the paper, [`VisibilityMode`] `all` or `stochastic`): a shadow ray
//! tests each VSL (or a subset chosen ∝ contribution) from each pixel, removing the
//! paper's Figure 7 over-illumination.

use crate::settings::VisibilityMode;
use crate::shade::{ShadePass, far_weight};
use illume_core::sampling::{Pcg32, SampleStream, mix64};
use illume_core::{Ray, Rgb, Vec3, channel_mean};
use illume_transport::GBufferPixel;

/// Σ Φ·G·V of each of a tile's pixels (`tile_pixels`, G-buffer indices) over the
/// culled VSLs `kept`, in pixel order; counts the shadow rays into `shadow_rays`.
pub(crate) fn shadowed_sums(
    pass: &ShadePass,
    tile_pixels: &[u32],
    kept: &[u32],
    shadow_rays: &mut u64,
) -> Vec<(u32, Rgb)> {
    let mut contrib: Vec<(u32, Rgb)> = Vec::with_capacity(kept.len());
    let mut cdf: Vec<f32> = Vec::with_capacity(kept.len());
    tile_pixels
        .iter()
        .map(|&idx| {
            let px = pass.gbuffer.pixels[idx as usize]
                .as_ref()
                .expect("gathered pixels exist");
            unshadowed_terms(pass, px, kept, &mut contrib);
            let sum = visible_sum(pass, px, idx, &contrib, &mut cdf, shadow_rays);
            (idx, sum)
        })
        .collect()
}

/// The non-zero unshadowed contributions Φ·G (pairs of VSL and value) of the VSLs
/// `kept` at pixel `px`, into `contrib`.
fn unshadowed_terms(
    pass: &ShadePass,
    px: &GBufferPixel,
    kept: &[u32],
    contrib: &mut Vec<(u32, Rgb)>,
) {
    let field = pass.field;
    let x = px.hit.position;
    let n = px.hit.facing_normal();
    contrib.clear();
    for &s in kept.iter() {
        let (mut wgt, front) = field.geometry(s as usize, x, n);
        if let Some(nf) = pass.near {
            let d2 = field.positions[s as usize].distance_squared(x);
            wgt *= far_weight(d2, field.area_m2[s as usize], nf.scale2);
        }
        let phi = if front {
            field.front_w[s as usize]
        } else {
            field.back_w[s as usize]
        };
        let c = phi * wgt;
        if c.max_element() > 0.0 {
            contrib.push((s, c));
        }
    }
}

/// Σ Φ·G·V at pixel `px` (G-buffer index `idx`) over `contrib`: every term tested
/// (`all`, or no more terms than `visibility_rays`), else `visibility_rays` terms chosen
/// ∝ their mean-channel contribution, estimate = total/k · Σ V (`cdf` is scratch).
fn visible_sum(
    pass: &ShadePass,
    px: &GBufferPixel,
    idx: u32,
    contrib: &[(u32, Rgb)],
    cdf: &mut Vec<f32>,
    shadow_rays: &mut u64,
) -> Rgb {
    let settings = pass.settings;
    let x = px.hit.position;
    let visible = |s: u32, rays: &mut u64| -> bool {
        let to = pass.field.positions[s as usize] - x;
        unoccluded(pass, px, to, rays)
    };
    let mut sum = Rgb::ZERO;
    if settings.visibility == VisibilityMode::All
        || contrib.len() <= settings.visibility_rays as usize
    {
        for &(s, c) in contrib {
            if visible(s, shadow_rays) {
                sum += c;
            }
        }
    } else {
        // Choose VSLs ∝ mean-channel contribution: estimate = total/k · Σ V.
        cdf.clear();
        let mut total = 0.0f32;
        for &(_, c) in contrib {
            total += channel_mean(c);
            cdf.push(total);
        }
        let k = settings.visibility_rays;
        let mut rng = Pcg32::new(mix64(pass.frame_seed ^ settings.seed), idx as u64);
        for _ in 0..k {
            let u = rng.next_1d() * total;
            let j = cdf.partition_point(|&v| v <= u).min(contrib.len() - 1);
            let (s, c) = contrib[j];
            if visible(s, shadow_rays) {
                let p = channel_mean(c) / total;
                sum += c / (p * k as f32);
            }
        }
    }
    sum
}

/// True when nothing blocks the segment from pixel `px` along `to` (the offset to a
/// VSL; a VSL within 1 mm is visible without a ray); counts the ray into `rays`.
fn unoccluded(pass: &ShadePass, px: &GBufferPixel, to: Vec3, rays: &mut u64) -> bool {
    let dist = to.length();
    if dist < 1e-3 {
        return true;
    }
    let dir = to / dist;
    *rays += 1;
    let t_max = dist * 0.999 - 1e-4;
    !pass.world.tracer.occluded(
        &Ray::segment(px.hit.spawn_origin(dir), dir, t_max),
        illume_scene::MASK_DEFAULT,
    )
}
