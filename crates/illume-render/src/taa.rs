//! Temporal anti-aliasing of interactive frames ([`RenderSettings::temporal_aa`]).
//!
//! A technique's frame samples each pixel at one point, so edges are stair-stepped where
//! the reference (box-filtered pixels) shows coverage. With temporal anti-aliasing each
//! frame samples its pixels at the next offset of the R₂ sequence
//! ([`illume_core::sampling::r2_point`]), and the image shown blends the frame into the
//! history of the frames before it (Karis 2014, "High quality temporal supersampling";
//! Yang et al. 2020's survey): an exponential mean over jittered samples, which on a
//! still view converges to the box filter.
//!
//! Per pixel with a surface:
//! - **Reprojection.** The pixel's surface point, moved back by its instance's motion
//!   since the last frame (each instance's transform is kept), is projected into the
//!   last frame's camera, shifted by the frame's sub-pixel offset so that the history
//!   stays centred on pixel centres, and the history is read there by a 4 × 4
//!   Catmull-Rom filter (bilinear reads soften the image a little more at every frame of
//!   motion); texels beyond the border are read at the border, and a point that was
//!   outside the last frame takes the frame as it is.
//! - **Rejection.** Where a history texel within one of the point saw another instance
//!   and either instance moved since the last frame, the pixel takes the frame as it is
//!   (a moving object's trail and the surfaces it uncovers). Between still objects the
//!   instance is not compared: a history texel on a silhouette holds a blend of both
//!   sides but records one, so comparing instances there drops the edges' history at
//!   every frame (tried: edges no better than without anti-aliasing).
//! - **Clamp.** The history is clamped to the range of the frame's 3 × 3 neighbourhood
//!   (per channel): where the history saw other light (a moved light, a pool that
//!   turned over) or a surface the camera's motion uncovered, its colour lies outside
//!   what the frame shows around the pixel and is pulled back within a frame.
//! - **Blend.** `shown = history + α (frame − history)` with α =
//!   [`RenderSettings::temporal_aa_blend`].
//!
//! Pixels without a surface (the sky, the background) take the frame as it is. The
//! error left: the clamp keeps some aliasing on thin features, the silhouettes of moving
//! objects are not anti-aliased (their history is rejected), and resampling the history
//! softens detail a little under motion (measured in BENCHMARKS.md, "temporal
//! anti-aliasing", against each frame's box filter).

use crate::RenderSettings;
use glam::Vec3A;
use illume_core::image::RgbImage;
use illume_core::{Affine3A, Rgb, Vec2, Vec3};
use illume_transport::GBuffer;
use rayon::prelude::*;

/// What the next frame reprojects: the image shown, and what it was made from.
#[derive(Clone, Debug)]
struct History {
    /// The image shown, as aligned 4-lane vectors (a history read is 16 taps: one
    /// SIMD multiply-add each instead of three scalar ones).
    image: Vec<Vec3A>,
    width: u32,
    height: u32,
    camera: illume_scene::Camera,
    /// Instance transforms of that frame.
    transforms: Vec<Affine3A>,
    /// Each pixel's instance (`u32::MAX`: none).
    instances: Vec<u32>,
}

/// Temporal anti-aliasing state: the history of a renderer's frames.
#[derive(Debug, Default)]
pub struct TemporalAa {
    history: Option<History>,
    /// Offsets taken since the history started (picks the next one).
    frame: u32,
}

impl TemporalAa {
    /// The offset in the pixel the next frame of `camera` should sample: the R₂
    /// sequence's next point when the camera moved since the last frame (the G-buffer is
    /// rebuilt anyway), else the centre (a kept G-buffer costs nothing, a new offset
    /// would rebuild all of it; the blend then converges to the centre's frame, and the
    /// window's still refinement takes over once the view rests).
    pub fn next_offset(&mut self, camera: &illume_scene::Camera) -> Vec2 {
        match &self.history {
            Some(h) if h.camera == *camera => Vec2::splat(0.5),
            _ => {
                self.frame = self.frame.wrapping_add(1);
                illume_core::sampling::r2_point(self.frame % 1024)
            }
        }
    }

    /// Forgets the history (the next frame is shown as it is).
    pub fn reset(&mut self) {
        self.history = None;
        self.frame = 0;
    }

    /// The image to show for `frame`, rendered from `gbuffer` (sampled at
    /// `gbuffer.offset`) of `scene`; keeps it as the next frame's history.
    pub fn resolve(
        &mut self,
        gbuffer: &GBuffer,
        frame: &RgbImage,
        settings: &RenderSettings,
        scene: &illume_scene::Scene,
    ) -> RgbImage {
        let (w, h) = (gbuffer.width, gbuffer.height);
        let alpha = settings.temporal_aa_blend.clamp(1e-3, 1.0);
        let transforms: Vec<Affine3A> = scene
            .instances
            .iter()
            .map(|i| i.world_from_object)
            .collect();
        let shown = match &self.history {
            Some(hist)
                if hist.width == w
                    && hist.height == h
                    && hist.transforms.len() == transforms.len()
                    && alpha < 1.0 =>
            {
                blend(gbuffer, frame, hist, (&scene.camera, &transforms), alpha)
            }
            _ => frame.clone(),
        };
        let camera = scene.camera.clone();
        // The instances of a G-buffer kept whole (camera and objects still) are the last
        // frame's.
        let kept = gbuffer.reused_pixels == u64::from(w) * u64::from(h);
        let instances = match self.history.take() {
            Some(old) if kept && old.instances.len() == (w * h) as usize => old.instances,
            _ => {
                let surfaces = Surfaces::of(gbuffer, &scene.camera);
                (0..(w * h) as usize)
                    .into_par_iter()
                    .with_min_len(4096)
                    .map(|i| surfaces.instance(i))
                    .collect()
            }
        };
        // A copy on every core (a serial copy of 5.8 MB at 800×600 left one idle).
        let image = shown
            .pixels()
            .par_iter()
            .with_min_len(4096)
            .map(|&p| Vec3A::from(p))
            .collect();
        self.history = Some(History {
            image,
            width: w,
            height: h,
            camera,
            transforms,
            instances,
        });
        shown
    }
}

/// What the blend reads of a frame's G-buffer: each pixel's instance and surface point,
/// from the rasterizer's visibility buffer when there is one (12 bytes a pixel, the point
/// rebuilt from `1/w` along the pixel's ray), else from the entries (≈ 130 bytes).
enum Surfaces<'a> {
    Raster {
        samples: &'a [illume_transport::raster::VisibilitySample],
        /// The camera's origin, and the world direction of pixel (x, y)'s sample at view
        /// depth 1, `corner + x·right + y·down` (the frame's own [`CameraRays`] at its
        /// offset, as the rasterizer's surfaces use them).
        ///
        /// [`CameraRays`]: illume_transport::CameraRays
        origin: Vec3,
        corner: Vec3,
        right: Vec3,
        down: Vec3,
        width: usize,
    },
    Entries(&'a [Option<illume_transport::GBufferPixel>], usize),
}

impl<'a> Surfaces<'a> {
    fn of(gbuffer: &'a GBuffer, camera: &illume_scene::Camera) -> Self {
        let (w, h) = (gbuffer.width, gbuffer.height);
        match gbuffer.visibility() {
            Some(v) => {
                let rays =
                    illume_transport::CameraRays::new(camera, w, h).with_offset(gbuffer.offset);
                let row = rays.row(0);
                Self::Raster {
                    samples: &v.pixels,
                    origin: rays.origin(),
                    corner: row.direction(0),
                    right: row.step(),
                    down: rays.row_step(),
                    width: w as usize,
                }
            }
            None => Self::Entries(&gbuffer.pixels, w as usize),
        }
    }

    /// The instance pixel `i` sees, `u32::MAX` for none.
    #[inline]
    fn instance(&self, i: usize) -> u32 {
        match self {
            Self::Raster { samples, .. } => samples[i].instance,
            Self::Entries(pixels, _) => pixels[i].as_ref().map_or(u32::MAX, |p| p.hit.instance.0),
        }
    }

    /// The surface point pixel (x, y) sees (asked only where it sees one).
    #[inline]
    fn position(&self, x: usize, y: usize) -> Vec3 {
        match self {
            Self::Raster {
                samples,
                origin,
                corner,
                right,
                down,
                width,
            } => {
                let direction = *corner + *right * x as f32 + *down * y as f32;
                *origin + direction / samples[y * width + x].inverse_depth
            }
            Self::Entries(pixels, width) => pixels[y * width + x]
                .as_ref()
                .map_or(Vec3::ZERO, |p| p.hit.position),
        }
    }
}

/// For still objects in a rasterized frame: the pixel's point in the last frame's view,
/// `1/w`-scaled, is `a·(1/w) + b0 + x·bx + y·by` (the current camera's ray of pixel
/// (x, y) at view depth 1, [`Surfaces::position`], carried into the last view once a
/// frame), so a pixel costs nine multiply-adds and one division.
struct Direct {
    a: Vec3,
    b0: Vec3,
    bx: Vec3,
    by: Vec3,
}

impl Direct {
    fn new(surfaces: &Surfaces<'_>, projection: &Projection) -> Option<Self> {
        let Surfaces::Raster {
            origin,
            corner,
            right,
            down,
            ..
        } = surfaces
        else {
            return None;
        };
        let v = &projection.view_from_world;
        Some(Self {
            a: v.transform_point3(*origin),
            b0: v.transform_vector3(*corner),
            bx: v.transform_vector3(*right),
            by: v.transform_vector3(*down),
        })
    }

    /// Pixel coordinates in the last frame of the point pixel (x, y) sees.
    #[inline]
    fn project(
        &self,
        x: usize,
        y: usize,
        surfaces: &Surfaces<'_>,
        projection: &Projection,
    ) -> Option<Vec2> {
        let Surfaces::Raster { samples, width, .. } = surfaces else {
            return None;
        };
        let inverse_depth = samples[y * width + x].inverse_depth;
        let v = self.a * inverse_depth + self.b0 + self.bx * x as f32 + self.by * y as f32;
        projection.screen(v)
    }
}

/// The last frame's camera as a projection to continuous pixel coordinates (pixel i's
/// centre at i + 0.5, y down), the projection of [`illume_transport::CameraRays`].
struct Projection {
    view_from_world: Affine3A,
    sx: f32,
    sy: f32,
    width: f32,
    height: f32,
}

impl Projection {
    fn new(camera: &illume_scene::Camera, width: u32, height: u32) -> Self {
        let tan_half_y = (camera.yfov_rad * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        Self {
            view_from_world: camera.world_from_camera.inverse(),
            sx: 1.0 / (tan_half_y * aspect),
            sy: 1.0 / tan_half_y,
            width: width as f32,
            height: height as f32,
        }
    }

    /// Pixel coordinates of world point `p`; `None` behind the camera.
    fn project(&self, p: Vec3) -> Option<Vec2> {
        self.screen(self.view_from_world.transform_point3(p))
    }

    /// Pixel coordinates of view-space point `v` (or any positive multiple of it);
    /// `None` behind the camera.
    #[inline]
    fn screen(&self, v: Vec3) -> Option<Vec2> {
        if v.z >= -1e-12 {
            return None;
        }
        let inv = -1.0 / v.z;
        let ndc = Vec2::new(v.x * self.sx * inv, v.y * self.sy * inv);
        Some(Vec2::new(
            (ndc.x + 1.0) * 0.5 * self.width,
            (1.0 - ndc.y) * 0.5 * self.height,
        ))
    }
}

/// Catmull-Rom weights of the taps at −1, 0, 1, 2 for a position `t` ∈ [0, 1) past
/// tap 0 (they sum to 1).
fn catmull_rom(t: f32) -> [f32; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [
        -0.5 * t + t2 - 0.5 * t3,
        1.0 - 2.5 * t2 + 1.5 * t3,
        0.5 * t + 2.0 * t2 - 1.5 * t3,
        -0.5 * t2 + 0.5 * t3,
    ]
}

/// The blended image (module doc).
fn blend(
    gbuffer: &GBuffer,
    frame: &RgbImage,
    hist: &History,
    (camera, transforms): (&illume_scene::Camera, &[Affine3A]),
    alpha: f32,
) -> RgbImage {
    let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
    let projection = Projection::new(&hist.camera, gbuffer.width, gbuffer.height);
    // Each instance's motion back to the last frame (none for an instance that stayed:
    // `then · now⁻¹` rounds away from the identity).
    let back: Vec<Option<Affine3A>> = transforms
        .iter()
        .zip(&hist.transforms)
        .map(|(now, then)| (now != then).then(|| *then * now.inverse()))
        .collect();
    let moved = |i: u32| back.get(i as usize).is_some_and(Option::is_some);
    let any_moved = back.iter().any(Option::is_some);
    let pixels: Vec<Vec3A> = frame
        .pixels()
        .par_iter()
        .with_min_len(4096)
        .map(|&p| Vec3A::from(p))
        .collect();
    let history = &hist.image;
    // The history texel position the pixel centre maps to, given where the frame sampled
    // (`gbuffer.offset`) and where the history's pixels are centred.
    let shift = Vec2::splat(0.5) - gbuffer.offset;
    let still = hist.camera == *camera;
    let (wi, hi_) = (w as i64, h as i64);
    let surfaces = Surfaces::of(gbuffer, camera);
    let direct = Direct::new(&surfaces, &projection);
    // A moving object's trail: a history texel within one of (x, y) saw another
    // instance, and it or this one moved since (the clamp alone lets a silhouette's
    // colours through, and a texel's colour may hold a surface its last sample missed).
    let trail = |instance: u32, x: i64, y: i64| {
        let mine = moved(instance);
        for ny in (y - 1).max(0)..=(y + 1).min(hi_ - 1) {
            let row = &hist.instances[ny as usize * w..][..w];
            for &other in &row[(x - 1).max(0) as usize..=(x + 1).min(wi - 1) as usize] {
                if other != instance && (mine || moved(other)) {
                    return true;
                }
            }
        }
        false
    };
    // The history at pixel (x, y) of the frame, before the clamp; `None` where it has
    // none to give.
    let recall = |x: usize, y: usize| -> Option<Vec3A> {
        if still && !any_moved {
            // Nothing moved: the G-buffer is the last frame's (kept whole), so each pixel's
            // history texel is its own, and the last frame's instances say which pixels
            // have a surface (no need to read the 100-byte G-buffer entries).
            return (hist.instances[y * w + x] != u32::MAX).then(|| history[y * w + x]);
        }
        let instance = surfaces.instance(y * w + x);
        let moved_by = back.get(instance as usize)?;
        let position = || surfaces.position(x, y);
        let motion = moved_by.map(|m| m.transform_point3(position()));
        if motion.is_none() && still {
            // Camera and object still: the sample's point is where it was, and the
            // history texel is the pixel's own (its centre-relative offset cancels).
            if any_moved && trail(instance, x as i64, y as i64) {
                return None;
            }
            return Some(history[y * w + x]);
        }
        let q = match (&motion, &direct) {
            // A still object seen through the rasterizer: its point in the last frame's
            // view straight from the pixel and `1/w` (one division, no transforms).
            (None, Some(d)) => d.project(x, y, &surfaces, &projection)?,
            _ => projection.project(motion.unwrap_or_else(position))?,
        };
        // The history position (texel j's centre at j + 0.5); outside the last frame
        // (beyond half a texel of its border), nothing.
        let at = q + shift - Vec2::splat(0.5);
        if !(at.x >= -0.5 && at.y >= -0.5 && at.x <= w as f32 - 0.5 && at.y <= h as f32 - 0.5) {
            return None;
        }
        if any_moved && trail(instance, (at.x + 0.5) as i64, (at.y + 0.5) as i64) {
            return None;
        }
        // floor() for values ≥ −1 without a libm call.
        let (x0, y0) = ((at.x + 1.0) as i64 - 1, (at.y + 1.0) as i64 - 1);
        // A 4 × 4 Catmull-Rom read: bilinear reads blur a little more at every frame of
        // motion, which the blend then keeps.
        let (wx, wy) = (catmull_rom(at.x - x0 as f32), catmull_rom(at.y - y0 as f32));
        let columns = [-1, 0, 1, 2].map(|d| (x0 + d).clamp(0, wi - 1) as usize);
        let mut sum = Vec3A::ZERO;
        for (dy, wy) in (-1..=2).zip(wy) {
            let row = &history[(y0 + dy).clamp(0, hi_ - 1) as usize * w..][..w];
            let mut line = Vec3A::ZERO;
            for (&cx, wx) in columns.iter().zip(wx) {
                line += row[cx] * wx;
            }
            sum += line * wy;
        }
        Some(sum)
    };
    let mut out = vec![Rgb::ZERO; w * h];
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(y, row_out)| {
            let rows = [y.saturating_sub(1), y, (y + 1).min(h - 1)].map(|r| &pixels[r * w..][..w]);
            for (x, out) in row_out.iter_mut().enumerate() {
                let current = rows[1][x];
                let Some(remembered) = recall(x, y) else {
                    *out = current.into();
                    continue;
                };
                // The frame's 3 × 3 neighbourhood range.
                let (l, r) = (x.saturating_sub(1), (x + 1).min(w - 1));
                let (mut lo, mut hi) = (current, current);
                for row in rows {
                    for c in [row[l], row[x], row[r]] {
                        lo = lo.min(c);
                        hi = hi.max(c);
                    }
                }
                let remembered = remembered.clamp(lo, hi);
                *out = (remembered + (current - remembered) * alpha).into();
            }
        });
    RgbImage::from_vec(gbuffer.width, gbuffer.height, out).expect("w × h pixels")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_from_the_visibility_buffer_are_the_entries_points() {
        let scene = illume_scene::builtin::load("cornell-spot").expect("builtin");
        let world = illume_transport::World::new(scene);
        let mut g = GBuffer::empty();
        let offset = Vec2::new(0.2, 0.7);
        g.rasterize_into_at(
            &world,
            48,
            36,
            illume_transport::TextureFilter::Trilinear,
            offset,
        );
        let raster = Surfaces::of(&g, &world.scene.camera);
        assert!(matches!(raster, Surfaces::Raster { .. }));
        let entries = Surfaces::Entries(&g.pixels, 48);
        let mut compared = 0;
        for y in 0..36 {
            for x in 0..48 {
                let i = y * 48 + x;
                let Some(p) = g.pixels[i].as_ref() else {
                    continue;
                };
                if raster.instance(i) != p.hit.instance.0 {
                    continue; // a silhouette pixel a BVH ray filled
                }
                let (a, b) = (raster.position(x, y), entries.position(x, y));
                // `1/w` is interpolated over corners snapped to 1/256 pixel: at grazing
                // angles that moves the point by ≈ 10⁻⁴ of the distance, a hundredth of a
                // pixel on screen.
                assert!(
                    (a - b).length() < 1e-3 * (1.0 + p.hit.t),
                    "({x}, {y}): {a} against {b}"
                );
                compared += 1;
            }
        }
        assert!(compared > 48 * 36 * 9 / 10, "{compared}");
    }

    #[test]
    fn the_projection_inverts_the_camera_rays() {
        let scene = illume_scene::builtin::load("cornell-spot").expect("builtin");
        let (w, h) = (64u32, 48u32);
        let rays = illume_transport::CameraRays::new(&scene.camera, w, h);
        let p = Projection::new(&scene.camera, w, h);
        for (x, y, o) in [
            (0u32, 0u32, (0.5f32, 0.5f32)),
            (17, 30, (0.1, 0.9)),
            (63, 47, (0.99, 0.01)),
        ] {
            let o = Vec2::from(o);
            let ray = rays.ray(x, y, o);
            let q = p.project(ray.origin + ray.dir * 3.0).expect("in front");
            let want = Vec2::new(x as f32, y as f32) + o;
            assert!((q - want).abs().max_element() < 1e-3, "{q} against {want}");
            assert!(p.project(ray.origin - ray.dir * 3.0).is_none(), "behind");
        }
    }
}
