//! Denoising guided by the surfaces (beyond the papers; issue 36): an edge-aware
//! à-trous wavelet filter on an image or a key of precomputed light, guided by the
//! surface every texel sees (Dammertz, Sewtz, Hanika & Lensch,
//! *Edge-avoiding À-Trous wavelet transform for fast global illumination filtering*,
//! HPG 2010), with the variance-guided luminance weight of SVGF (Schied et al., HPG
//! 2017). Pure Rust, no library.
//!
//! Two users: precomputed's keys (its paper's keys came from Mental Ray's photon map and
//! final gather, smooth by construction; ours are path traced, and their noise is what the
//! PCA and the adaptive schedule then see as change), and the reference's denoised still
//! (`illume render --technique reference --denoise`). It lives here, below the
//! techniques, because both need it. The filter, per key (or image):
//!
//! 1. **Demodulate**: divide each texel by its albedo (averaged over the pixel's 2×2
//!    sub-pixel hits, floored at [`ALBEDO_FLOOR`]), so texture detail never blurs;
//!    multiply back at the end.
//! 2. **Variance**: the key is rendered in two halves of its samples; `(half − all)²`
//!    estimates the variance of the mean per texel (luminance of the demodulated value),
//!    smoothed over the 5×5 neighbours on the same surface.
//! 3. **À-trous passes** ([`PASSES`], steps 1, 2, 4 texels): a 5×5 B3-spline kernel
//!    whose weights are cut by the normal (`max(0, n·n')^`[`NORMAL_POWER`]), the distance
//!    of the neighbour from the texel's tangent plane (`exp(−d/footprint)`: other surfaces
//!    at other depths), the region (a cube face, an atlas chart) and the luminance
//!    difference against [`SIGMA_LUMINANCE`] standard deviations of the difference
//!    (the two texels' 3×3-smoothed variances summed: symmetric, so a bright outlier
//!    spreads its energy rather than losing it), variances which each pass propagates.
//!    Each texel moves towards a neighbour by their weight over the larger of their two
//!    total weights ([`filter_texel`]): the weights being symmetric, what one texel
//!    gains the other loses, so a pass keeps every region's sum of demodulated texels
//!    (a plain normalised mean lost the bright outliers' energy, issue 36).
//!
//! Texels that see nothing, and atlas probes, are left as they are. The filter is a pure
//! function of the key and its guide: with common random numbers across keys
//! (precomputed's `precompute::key_seed`) what noise is left is also common to every key.

use illume_core::image::RgbImage;
use illume_core::{Rgb, Vec2, Vec3, luminance};
use illume_transport::{GBuffer, World};
use rayon::prelude::*;

/// À-trous passes: the kernel's reach doubles each pass (±2, ±4, ±8 texels); five
/// (±32) flattened the light's gradients of a 32×24 key beyond the reference's tolerance.
pub const PASSES: u32 = 3;
/// Exponent of the normal weight `max(0, n·n')^p` (SVGF's 128 is for noisy normals of
/// rasterised detail; ours are exact, 64 keeps corners apart).
pub const NORMAL_POWER: i32 = 64;
/// Luminance edge-stopping: neighbours within this many standard deviations of the
/// texel's noise count fully (SVGF's σ_l = 4).
pub const SIGMA_LUMINANCE: f32 = 4.0;
/// Albedo below this is not divided out (it would only amplify noise).
pub const ALBEDO_FLOOR: f32 = 0.02;

/// The B3-spline kernel of one axis.
const KERNEL: [f32; 5] = [1.0 / 16.0, 0.25, 0.375, 0.25, 1.0 / 16.0];

/// What one texel of a key sees: the filter's guide.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideTexel {
    /// The surface point \[m\].
    pub position: Vec3,
    /// Its unit normal (facing the viewer).
    pub normal: Vec3,
    /// Its albedo (1 for atlas texels, whose values are albedo-free already).
    pub albedo: Rgb,
    /// The texel's size on the surface \[m\]: the scale of the plane-distance weight.
    pub footprint: f32,
    /// Texels filter only with texels of their own region (a cube face, an atlas chart).
    pub region: u32,
}

/// The guide of one key image: a texel per key texel, `None` where nothing is seen.
#[derive(Clone, Debug, PartialEq)]
pub struct Guide {
    /// Texels across.
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// Row by row.
    pub texels: Vec<Option<GuideTexel>>,
}

impl Guide {
    /// The guide of `world`'s camera image at `width × height`: position and normal of
    /// the hit through each pixel's centre, albedo averaged over 2×2 sub-pixel hits (the
    /// key averages its samples over the pixel too; a sub-pixel that sees nothing counts
    /// as albedo 0). All in region `region`.
    pub fn camera(world: &World, width: u32, height: u32, region: u32) -> Self {
        let centre = GBuffer::render(world, width, height, Vec2::splat(0.5));
        let corners: Vec<GBuffer> = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
            .into_iter()
            .map(|(x, y)| GBuffer::render(world, width, height, Vec2::new(x, y)))
            .collect();
        let eye = world.scene.camera.world_from_camera.translation;
        let eye = Vec3::new(eye.x, eye.y, eye.z);
        // A pixel's angular size (vertical field of view over rows).
        let angle = 2.0 * (0.5 * world.scene.camera.yfov_rad).tan() / height.max(1) as f32;
        let texels = (0..centre.pixels.len())
            .map(|i| {
                let p = centre.pixels[i].as_ref()?;
                let albedo = corners
                    .iter()
                    .map(|g| g.pixels[i].as_ref().map_or(Rgb::ZERO, |q| q.hit.albedo))
                    .fold(Rgb::ZERO, |a, b| a + b)
                    * 0.25;
                Some(GuideTexel {
                    position: p.hit.position,
                    normal: p.hit.facing_normal(),
                    albedo,
                    footprint: (p.hit.position - eye).length().max(1e-4) * angle,
                    region,
                })
            })
            .collect();
        Self {
            width,
            height,
            texels,
        }
    }

    /// `self` with `other`'s rows below (cube faces stacked).
    pub fn stack(mut self, other: Guide) -> Self {
        debug_assert_eq!(self.width, other.width);
        self.height += other.height;
        self.texels.extend(other.texels);
        self
    }
}

/// `image` (the mean of all samples) filtered under `guide`. `half`: the mean of the
/// first half of the same samples, for the variance (without it, e.g. at 1 sample per
/// texel, the luminance weight is off and only the surface guides). Sizes must agree
/// (otherwise the image is returned as it is).
pub fn atrous(image: &RgbImage, half: Option<&RgbImage>, guide: &Guide) -> RgbImage {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let n = w * h;
    if guide.texels.len() != n || half.is_some_and(|x| x.pixels().len() != n) {
        return image.clone();
    }
    let albedo = |g: &GuideTexel| g.albedo.max(Rgb::splat(ALBEDO_FLOOR));
    let demodulate = |v: &Rgb, g: &Option<GuideTexel>| match g {
        Some(g) => *v / albedo(g),
        None => *v,
    };
    let mut values: Vec<Rgb> = image
        .pixels()
        .iter()
        .zip(&guide.texels)
        .map(|(v, g)| demodulate(v, g))
        .collect();
    let raw_variance: Vec<f32> = match half {
        Some(half) => half
            .pixels()
            .iter()
            .zip(&values)
            .zip(&guide.texels)
            .map(|((x, all), g)| (luminance(demodulate(x, g)) - luminance(*all)).powi(2))
            .collect(),
        None => vec![f32::INFINITY; n],
    };
    let mut variance = smooth(&raw_variance, guide, 2, 1);
    for pass in 0..PASSES {
        let step = 1usize << pass;
        let blurred = smooth(&variance, guide, 1, 1);
        let totals: Vec<f32> = (0..n)
            .into_par_iter()
            .with_min_len(256)
            .map(|p| {
                let mut total = 0f32;
                neighbours(p, step, (w, h), guide, &values, &blurred, |_, x| total += x);
                total
            })
            .collect();
        let (v, var): (Vec<Rgb>, Vec<f32>) = (0..n)
            .into_par_iter()
            .with_min_len(256)
            .map(|p| {
                let maps = (&variance[..], &blurred[..], &totals[..]);
                filter_texel(p, step, (w, h), guide, &values, maps)
            })
            .unzip();
        values = v;
        variance = var;
    }
    let pixels = values
        .iter()
        .zip(&guide.texels)
        .map(|(v, g)| match g {
            Some(g) => *v * albedo(g),
            None => *v,
        })
        .collect();
    RgbImage::from_vec(image.width(), image.height(), pixels).expect("one value per texel")
}

/// The weight of the surface at `q` seen from `p` (normal and tangent-plane distance), 0
/// across regions; symmetric in `p` and `q`.
fn surface_weight(p: &GuideTexel, q: &GuideTexel) -> f32 {
    if p.region != q.region {
        return 0.0;
    }
    let facing = p.normal.dot(q.normal).max(0.0).powi(NORMAL_POWER);
    // Symmetric in p and q (the filter conserves energy only with symmetric weights):
    // the larger of the two tangent-plane distances, each in its own texel's size.
    let d = q.position - p.position;
    let plane = (p.normal.dot(d).abs() / p.footprint.max(1e-6))
        .max(q.normal.dot(d).abs() / q.footprint.max(1e-6));
    facing * (-plane).exp()
}

/// The à-trous weights of texel `p`'s 5×5 neighbours `step` apart (itself included):
/// kernel × surface × luminance, each `(q, weight)` with weight > 0 handed to `each`.
/// Symmetric: `q`'s weight seen from `p` is `p`'s seen from `q`.
fn neighbours(
    p: usize,
    step: usize,
    (w, h): (usize, usize),
    guide: &Guide,
    values: &[Rgb],
    blurred_variance: &[f32],
    mut each: impl FnMut(usize, f32),
) {
    let Some(gp) = guide.texels[p].as_ref() else {
        return;
    };
    let (x, y) = ((p % w) as isize, (p / w) as isize);
    let lp = luminance(values[p]);
    for (j, ky) in KERNEL.iter().enumerate() {
        let qy = y + (j as isize - 2) * step as isize;
        if qy < 0 || qy >= h as isize {
            continue;
        }
        for (i, kx) in KERNEL.iter().enumerate() {
            let qx = x + (i as isize - 2) * step as isize;
            if qx < 0 || qx >= w as isize {
                continue;
            }
            let q = qy as usize * w + qx as usize;
            let Some(gq) = guide.texels[q].as_ref() else {
                continue;
            };
            // The difference of two noisy texels has the variance of both.
            let sigma =
                SIGMA_LUMINANCE * (blurred_variance[p] + blurred_variance[q]).sqrt() + 1e-12;
            let lum = if sigma.is_finite() {
                (-(lp - luminance(values[q])).abs() / sigma).exp()
            } else {
                1.0
            };
            let weight = kx * ky * surface_weight(gp, gq) * lum;
            if weight > 0.0 {
                each(q, weight);
            }
        }
    }
}

/// One à-trous pass at texel `p`, given every texel's total weight `totals`
/// ([`neighbours`] summed): `p` moves towards each neighbour `q` by
/// `w(p,q) / max(W_p, W_q)` of their difference, and the variance of the result.
///
/// Where the totals agree this is the à-trous weighted mean `Σ w·v_q / W_p`. The plain
/// mean (normalised by `W_p` alone) loses energy on Monte Carlo noise: a bright outlier
/// has few neighbours of its luminance (small `W_q`) and keeps most of its value, while
/// its energy reaches the many quiet texels around it only divided by their large
/// totals, so the rare bright samples that carry much of the light were partly dropped
/// (−1 to −3 % per cube face of 24² texels at 48 spp, −6.6 % of the light in a view;
/// issue 36). With the symmetric normaliser whatever `p` gains from `q`, `q` loses to
/// `p`: each pass keeps the sum of the (demodulated) texels of every region exactly.
fn filter_texel(
    p: usize,
    step: usize,
    size: (usize, usize),
    guide: &Guide,
    values: &[Rgb],
    (variance, blurred_variance, totals): (&[f32], &[f32], &[f32]),
) -> (Rgb, f32) {
    let (vp, mut own, mut moved, mut var) = (values[p], 1f32, Rgb::ZERO, 0f32);
    neighbours(
        p,
        step,
        size,
        guide,
        values,
        blurred_variance,
        |q, weight| {
            if q != p {
                let a = weight / totals[p].max(totals[q]);
                own -= a;
                moved += (values[q] - vp) * a;
                var += a * a * variance[q];
            }
        },
    );
    (vp + moved, var + own * own * variance[p])
}

/// `values` averaged over the (2r+1)² neighbours `step` apart on the same surface
/// ([`surface_weight`], box kernel).
fn smooth(values: &[f32], guide: &Guide, r: isize, step: isize) -> Vec<f32> {
    let (w, h) = (guide.width as isize, guide.height as isize);
    (0..values.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|p| {
            let Some(gp) = guide.texels[p].as_ref() else {
                return values[p];
            };
            let (x, y) = (p as isize % w, p as isize / w);
            let (mut sum, mut weights) = (0f32, 0f32);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (qx, qy) = (x + dx * step, y + dy * step);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let q = (qy * w + qx) as usize;
                    if let Some(gq) = guide.texels[q].as_ref() {
                        let weight = surface_weight(gp, gq);
                        if weight > 0.0 {
                            sum += weight * values[q];
                            weights += weight;
                        }
                    }
                }
            }
            if weights > 0.0 {
                sum / weights
            } else {
                values[p]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat guide: one plane facing +Z, unit albedo, texel size 1 cm.
    fn plane(w: u32, h: u32) -> Guide {
        Guide {
            width: w,
            height: h,
            texels: (0..w * h)
                .map(|i| {
                    Some(GuideTexel {
                        position: Vec3::new((i % w) as f32 * 0.01, (i / w) as f32 * 0.01, 0.0),
                        normal: Vec3::Z,
                        albedo: Rgb::ONE,
                        footprint: 0.01,
                        region: 0,
                    })
                })
                .collect(),
        }
    }

    /// Noise around a constant is removed and its mean kept; a step between two regions
    /// (or two walls at a corner) stays a step.
    #[test]
    fn noise_goes_edges_stay() {
        let (w, h) = (32u32, 32u32);
        let mut rng = illume_core::sampling::Pcg32::new(7, 1);
        use illume_core::sampling::SampleStream;
        let noisy: Vec<Rgb> = (0..w * h)
            .map(|_| Rgb::splat(1.0 + 0.3 * (rng.next_1d() - 0.5)))
            .collect();
        // The first half of the samples: as far from the mean as the mean is from the
        // truth (var(h₁ − mean) = var(mean)).
        let half: Vec<Rgb> = noisy
            .iter()
            .map(|v| *v + Rgb::splat(0.3 * (rng.next_1d() - 0.5)))
            .collect();
        let image = RgbImage::from_vec(w, h, noisy).unwrap();
        let half = RgbImage::from_vec(w, h, half).unwrap();
        let out = atrous(&image, Some(&half), &plane(w, h));
        let spread = |v: &[Rgb]| {
            let m = v.iter().map(|p| p.x).sum::<f32>() / v.len() as f32;
            (v.iter().map(|p| (p.x - m).powi(2)).sum::<f32>() / v.len() as f32).sqrt()
        };
        let (after, before) = (spread(out.pixels()), spread(image.pixels()));
        assert!(after < 0.25 * before, "noise {before} → {after}");
        assert!((out.mean().x - image.mean().x).abs() < 0.01);

        // Left half one wall (normal +Z, value 1), right half another (normal +X, value 3).
        let mut guide = plane(w, h);
        let step: Vec<Rgb> = (0..w * h)
            .map(|i| Rgb::splat(if i % w < w / 2 { 1.0 } else { 3.0 }))
            .collect();
        for (i, t) in guide.texels.iter_mut().enumerate() {
            if i as u32 % w >= w / 2 {
                t.as_mut().unwrap().normal = Vec3::X;
            }
        }
        let image = RgbImage::from_vec(w, h, step.clone()).unwrap();
        let out = atrous(&image, None, &guide);
        for (a, b) in out.pixels().iter().zip(&step) {
            assert!((a.x - b.x).abs() < 1e-3, "{a} vs {b}");
        }
    }

    /// The filter moves light, never loses it: on skewed noise (rare bright samples, as
    /// a path tracer's) the sum of a region's texels is kept to float precision, and the
    /// noise still falls. A mean normalised by the texel's own weights alone lost 3 %.
    #[test]
    fn energy_is_kept_on_skewed_noise() {
        use illume_core::sampling::SampleStream;
        let (w, h) = (24u32, 24u32);
        let mut rng = illume_core::sampling::Pcg32::new(11, 3);
        // One sample in 16 is 30× the rest; the half image is an independent draw.
        let mut draw = || {
            let mut sum = 0.0;
            for _ in 0..8 {
                sum += if rng.next_1d() < 1.0 / 16.0 {
                    30.0
                } else {
                    1.0
                };
            }
            Rgb::splat(sum / 8.0)
        };
        let noisy: Vec<Rgb> = (0..w * h).map(|_| draw()).collect();
        let half: Vec<Rgb> = (0..w * h).map(|_| draw()).collect();
        let image = RgbImage::from_vec(w, h, noisy).unwrap();
        let half = RgbImage::from_vec(w, h, half).unwrap();
        let out = atrous(&image, Some(&half), &plane(w, h));
        let (before, after) = (image.mean().x, out.mean().x);
        assert!(
            (after - before).abs() < 1e-4 * before,
            "mean {before} → {after}"
        );
        let spread = |v: &[Rgb]| {
            let m = v.iter().map(|p| p.x).sum::<f32>() / v.len() as f32;
            (v.iter().map(|p| (p.x - m).powi(2)).sum::<f32>() / v.len() as f32).sqrt()
        };
        assert!(spread(out.pixels()) < 0.5 * spread(image.pixels()));
    }

    /// Texture detail survives: a checkerboard albedo under constant light comes back
    /// exactly (demodulated, the light is flat).
    #[test]
    fn albedo_detail_is_kept() {
        let (w, h) = (16u32, 16u32);
        let mut guide = plane(w, h);
        for (i, t) in guide.texels.iter_mut().enumerate() {
            let checker = ((i as u32 % w) + (i as u32 / w)).is_multiple_of(2);
            t.as_mut().unwrap().albedo = Rgb::splat(if checker { 0.8 } else { 0.2 });
        }
        let image = RgbImage::from_vec(
            w,
            h,
            guide
                .texels
                .iter()
                .map(|t| t.unwrap().albedo * 0.5)
                .collect(),
        )
        .unwrap();
        let out = atrous(&image, Some(&image), &guide);
        for (a, b) in out.pixels().iter().zip(image.pixels()) {
            assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
        }
    }
}
