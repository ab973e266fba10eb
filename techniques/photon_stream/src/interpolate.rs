//! Shading stride (beyond the paper,
//! [`shading_stride`](crate::PhotonStreamSettings::shading_stride) > 1): the VSL sum is
//! evaluated on a grid of pixels `stride` apart and interpolated between them on the
//! same surface; pixels with no such neighbour are shaded exactly ([`crate::shade`]).

use crate::shade::{shades, zeros};
use illume_core::image::RgbImage;
use illume_core::{INV_PI, Rgb, Vec3};
use illume_transport::GBuffer;
use rayon::prelude::*;

/// A shaded grid pixel as interpolation reads it.
#[derive(Clone, Copy, Default)]
struct Anchor {
    position: Vec3,
    normal: Vec3,
    gathered: Rgb,
    usable: bool,
}

/// Radiance of every pixel: grid pixels from `on_grid` (Σ Φ·G of grid cell
/// `(y / stride) · ⌈w / stride⌉ + x / stride`), the pixels between from the
/// up to four grid pixels (`stride` apart) around each, weighted bilinearly, using only
/// neighbours on the same surface: facing normals within ≈ 25° (cos ≥ 0.9) and the
/// neighbour's point within `stride` pixel footprints of the pixel's tangent plane
/// (depth discontinuities fail). Returns the image, how many pixels were interpolated,
/// and the pixels no neighbour could fill (left black, to be shaded exactly).
/// `directional`: glossy pixels take their directional albedo
/// ([`illume_transport::GBufferPixel::display_albedo`]).
pub(crate) fn interpolate(
    gbuffer: &GBuffer,
    on_grid: &[Rgb],
    stride: u32,
    yfov_rad: f32,
    directional: bool,
) -> (RgbImage, u64, Vec<u32>) {
    let (w, h) = (gbuffer.width, gbuffer.height);
    // World size of one pixel at unit distance (the camera's vertical field of view
    // spread over the image height; a pixel is square).
    let footprint = 2.0 * (yfov_rad * 0.5).tan() / h.max(1) as f32;
    // The grid pixels, compact (a G-buffer entry is ~100 bytes; each is read by up to
    // eight neighbours).
    let (aw, ah) = (w.div_ceil(stride), h.div_ceil(stride));
    let anchors: Vec<Anchor> = (0..aw * ah)
        .into_par_iter()
        .with_min_len(256)
        .map(|k| {
            let j = ((k / aw) * stride * w + (k % aw) * stride) as usize;
            match gbuffer.pixels[j].as_ref().filter(|p| shades(p)) {
                Some(p) => Anchor {
                    position: p.hit.position,
                    normal: p.hit.facing_normal(),
                    gathered: on_grid[k as usize],
                    usable: true,
                },
                None => Anchor::default(),
            }
        })
        .collect();
    let mut img = RgbImage::from_vec(w, h, zeros((w * h) as usize)).expect("w × h pixels");
    let rows: Vec<(u64, Vec<u32>)> = img
        .pixels_mut()
        .par_chunks_mut(w as usize)
        .enumerate()
        .map(|(y, row)| {
            let y = y as u32;
            let (mut interpolated, mut missing) = (0u64, Vec::new());
            let (ay, fy) = (y / stride, (y % stride) as f32 / stride as f32);
            let on_row = y.is_multiple_of(stride);
            for (x, out) in row.iter_mut().enumerate() {
                let x = x as u32;
                let i = y * w + x;
                illume_core::prefetch(&gbuffer.pixels, i as usize + illume_core::PREFETCH_AHEAD);
                let Some(p) = gbuffer.pixels[i as usize].as_ref().filter(|p| shades(p)) else {
                    continue;
                };
                let f = p.display_albedo(directional) * INV_PI;
                if on_row && x.is_multiple_of(stride) {
                    *out = f * on_grid[(ay * aw + x / stride) as usize];
                    continue;
                }
                let (ax, fx) = (x / stride, (x % stride) as f32 / stride as f32);
                let n = p.hit.facing_normal();
                let tol = stride as f32 * footprint * p.hit.t;
                let (mut sum, mut weight) = (Rgb::ZERO, 0.0f32);
                for (dx, dy, wx, wy) in [
                    (0, 0, 1.0 - fx, 1.0 - fy),
                    (1, 0, fx, 1.0 - fy),
                    (0, 1, 1.0 - fx, fy),
                    (1, 1, fx, fy),
                ] {
                    let (qx, qy) = (ax + dx, ay + dy);
                    if qx >= aw || qy >= ah {
                        continue;
                    }
                    let q = &anchors[(qy * aw + qx) as usize];
                    if !q.usable
                        || q.normal.dot(n) < 0.9
                        || n.dot(q.position - p.hit.position).abs() > tol
                    {
                        continue;
                    }
                    // Bilinear weight, floored so that a pixel on a grid line still
                    // borrows from the far neighbours when its near ones are unusable.
                    let wgt = (wx * wy).max(1e-3);
                    sum += q.gathered * wgt;
                    weight += wgt;
                }
                if weight > 0.0 {
                    *out = f * (sum / weight);
                    interpolated += 1;
                } else {
                    missing.push(i);
                }
            }
            (interpolated, missing)
        })
        .collect();
    let interpolated = rows.iter().map(|r| r.0).sum();
    let missing = rows.into_iter().flat_map(|r| r.1).collect();
    (img, interpolated, missing)
}
