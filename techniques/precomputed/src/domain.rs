//! Where key images live (Bahnsen et al. §3.1, Fig. 4) and how each domain renders a key
//! and the sky image:
//!
//! - `screen`: the fixed camera's image, `width × height` pixels (the paper's
//!   implementation). Rendered by the reference path tracer.
//! - `cube`: six square faces of `face` pixels around the camera's position, stacked
//!   top to bottom in the order +X, −X, +Y, −Y, +Z, −Z (each face a 90° pinhole camera
//!   looking along its axis). The camera may turn in place; its position is fixed.
//!   Rendered by the reference path tracer, one face at a time.
//! - `atlas`: the world-space lightmap and probe grid of [`crate::atlas`]; each texel is
//!   a path-traced gather from its surface point with albedo 1. Any camera.
//!
//! All three store one RGB value per texel in a key image, so the PCA, the file, the
//! shards and the adaptive schedule treat them alike.

use crate::PrecomputedError;
use crate::atlas::{Atlas, PROBE_AXES};
use crate::settings::{Denoise, Domain, PrecomputedSettings};
use illume_core::image::RgbImage;
use illume_core::sampling::{Pcg32, SampleStream, mix64};
use illume_core::{Affine3A, Mat3, Ray, Rgb, Vec2, Vec3};
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_render::denoise::{Guide, GuideTexel};
use illume_transport::path::{PathRadiance, PathSettings, continue_path};
use illume_transport::{SurfaceHit, World};
use rayon::prelude::*;

/// A domain with its sizes.
#[derive(Clone, Debug, PartialEq)]
pub enum Layout {
    /// The camera's image.
    Screen {
        /// Pixels across.
        width: u32,
        /// Pixels down.
        height: u32,
    },
    /// Six faces around the camera's position.
    Cube {
        /// Pixels along a face's side.
        face: u32,
    },
    /// The lightmap and probes.
    Atlas(Box<Atlas>),
}

/// Which light a rendered image holds, as the reference path tracer splits it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Light reflected ≥ 2 times (a key).
    Indirect,
    /// All reflected light (the sky image).
    All,
    /// Light reflected once (the sky image's direct share, section `sky.direct`).
    Direct,
}

impl Part {
    /// This part of a path's radiance.
    fn of(self, out: &PathRadiance) -> Rgb {
        match self {
            Self::Indirect => out.indirect,
            Self::All => out.direct + out.indirect,
            Self::Direct => out.direct,
        }
    }
}

/// The cube faces' axes: (forward, up) of each face's camera.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// The rotation of cube face `f`'s camera (camera space: −Z forward, +Y up, +X right).
fn face_rotation(f: usize) -> Mat3 {
    let (forward, up) = CUBE_FACES[f];
    Mat3::from_cols(forward.cross(up), up, -forward)
}

impl Layout {
    /// The layout `settings` ask for, in `world` (its static scene and camera), for an
    /// image of `size` pixels (screen; cube: the face side when `cube_face` is 0).
    pub fn new(
        world: &World,
        settings: &PrecomputedSettings,
        size: (u32, u32),
    ) -> Result<Self, PrecomputedError> {
        Ok(match settings.domain {
            Domain::Screen => Self::Screen {
                width: size.0,
                height: size.1,
            },
            Domain::Cube => Self::Cube {
                face: cube_face(settings.cube_face, size.1, world.scene.camera.yfov_rad)?,
            },
            Domain::Atlas => Self::Atlas(Box::new(Atlas::build(
                &world.scene,
                settings.atlas_density,
                settings.probe_spacing,
            )?)),
        })
    }

    /// The domain's name in files and settings.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Screen { .. } => "screen",
            Self::Cube { .. } => "cube",
            Self::Atlas(_) => "atlas",
        }
    }

    /// Width and height of a key image.
    pub fn image_size(&self) -> (u32, u32) {
        match self {
            Self::Screen { width, height } => (*width, *height),
            Self::Cube { face } => (*face, 6 * face),
            Self::Atlas(a) => a.image_size(),
        }
    }

    /// Renders light of `world` into a key image: light reflected ≥ 2 times (`indirect`)
    /// or all reflected light (`!indirect`, for the sky image), `spp` samples per texel,
    /// then `denoise`d ([`illume_render::denoise`]).
    pub fn render(
        &self,
        world: &World,
        spp: u32,
        seed: u64,
        indirect: bool,
        denoise: Denoise,
    ) -> RgbImage {
        let part = if indirect { Part::Indirect } else { Part::All };
        let mut images = self.render_parts(world, spp, seed, &[part], denoise);
        images.pop().expect("one image a part")
    }

    /// As [`Layout::render`], one image per part of `parts`, all from the same paths
    /// (so [`Part::Direct`] and [`Part::All`] of one call differ by exactly the light
    /// reflected ≥ 2 times, never by noise), each `denoise`d alike.
    pub fn render_parts(
        &self,
        world: &World,
        spp: u32,
        seed: u64,
        parts: &[Part],
        denoise: Denoise,
    ) -> Vec<RgbImage> {
        match self {
            Self::Screen { width, height } => {
                render_camera(world, (*width, *height), spp, seed, parts, denoise)
            }
            Self::Cube { face } => {
                let mut pixels = vec![Vec::with_capacity(6 * (*face as usize).pow(2)); parts.len()];
                for f in 0..6 {
                    let mut camera = world.scene.camera.clone();
                    camera.world_from_camera = Affine3A::from_mat3_translation(
                        face_rotation(f),
                        camera.world_from_camera.translation.into(),
                    );
                    camera.yfov_rad = std::f32::consts::FRAC_PI_2;
                    let seed = mix64(seed ^ (0xc0be_0000 + f as u64));
                    let mut scene = world.scene.clone();
                    scene.camera = camera;
                    let w = world.with_scene(scene);
                    let images = render_camera(&w, (*face, *face), spp, seed, parts, denoise);
                    for (p, image) in pixels.iter_mut().zip(&images) {
                        p.extend_from_slice(image.pixels());
                    }
                }
                pixels
                    .into_iter()
                    .map(|p| RgbImage::from_vec(*face, 6 * face, p).expect("six faces"))
                    .collect()
            }
            Self::Atlas(atlas) => render_atlas(world, atlas, spp, seed, parts, denoise),
        }
    }
}

/// Most pixels along a cube face's side: six faces of 3344² hold 67.1 M texels, the
/// atlas's cap ([`crate::atlas::MAX_TEXELS`], 2²⁶: a key of them is 805 MB of f32 RGB,
/// and the PCA keeps every key in memory).
pub const MAX_CUBE_FACE: u32 = 3344;

/// A cube face's side: `asked`, or (0) the side whose texels match the density of a
/// `height`-pixel image with vertical field of view `yfov` at its centre. Either above
/// [`MAX_CUBE_FACE`] (a narrow field of view makes the automatic side huge) is refused,
/// naming the setting and the value.
pub fn cube_face(asked: u32, height: u32, yfov: f32) -> Result<u32, PrecomputedError> {
    let too_big = |reason: String| PrecomputedError::InvalidSetting {
        field: "cube_face",
        reason,
    };
    if asked > MAX_CUBE_FACE {
        return Err(too_big(format!(
            "{asked} pixels is more than {MAX_CUBE_FACE} (six faces of it would exceed {} texels a key)",
            crate::atlas::MAX_TEXELS
        )));
    }
    if asked > 0 {
        return Ok(asked);
    }
    let side = (height as f32 / (0.5 * yfov).tan()).round();
    if !(side.is_finite() && side <= MAX_CUBE_FACE as f32) {
        return Err(too_big(format!(
            "0 (automatic) gives {side} pixels for {height} rows at a {:.3}° field of view, more than {MAX_CUBE_FACE}: set cube_face to at most {MAX_CUBE_FACE}",
            yfov.to_degrees()
        )));
    }
    Ok((side as u32).max(1))
}

/// The reference path tracer's images of `world`'s camera, one per part of `parts`;
/// `denoise`d under the camera's guide, the variance from the first half of the samples
/// (the samples and their sum are those of one call: the undenoised image is the same
/// bit for bit).
fn render_camera(
    world: &World,
    size: (u32, u32),
    spp: u32,
    seed: u64,
    parts: &[Part],
    denoise: Denoise,
) -> Vec<RgbImage> {
    let mut r = ReferenceRenderer::new(
        ReferenceSettings {
            spp,
            seed,
            ..Default::default()
        },
        size.0,
        size.1,
    );
    let pick = |r: &ReferenceRenderer| -> Vec<RgbImage> {
        let images = r.images();
        parts
            .iter()
            .map(|part| match part {
                Part::Indirect => images.indirect.clone(),
                Part::All => images.full.clone(),
                Part::Direct => images.direct.clone(),
            })
            .collect()
    };
    let filtering = denoise == Denoise::Atrous;
    let half = (filtering && spp >= 2).then(|| {
        r.add_samples(world, spp / 2);
        pick(&r)
    });
    r.add_samples(world, spp - r.samples());
    let images = pick(&r);
    if !filtering {
        return images;
    }
    let guide = illume_render::denoise::Guide::camera(world, size.0, size.1, 0);
    images
        .iter()
        .enumerate()
        .map(|(i, image)| {
            illume_render::denoise::atrous(image, half.as_ref().map(|h| &h[i]), &guide)
        })
        .collect()
}

/// A white Lambertian version of `hit` (albedo 1, no emission): what a lightmap texel
/// or a probe direction gathers with.
fn white(mut hit: SurfaceHit) -> SurfaceHit {
    hit.albedo = Rgb::ONE;
    hit.metallic = 0.0;
    hit.roughness = 1.0;
    hit.emission = Rgb::ZERO;
    hit.reflects = true;
    hit
}

/// The surface at lightmap texel point `p`, seen from its side's normal.
fn texel_hit(world: &World, p: &crate::atlas::TexelPoint) -> SurfaceHit {
    let scene = &world.scene;
    let inst = &scene.instances[p.instance.index()];
    let mesh = &scene.meshes[inst.mesh.index()];
    let corners = mesh
        .triangle(p.triangle as usize)
        .map(|c| inst.world_from_object.transform_point3(c));
    let b = p.barycentrics;
    let position = corners[0] * (1.0 - b.x - b.y) + corners[1] * b.x + corners[2] * b.y;
    let mut n = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize_or(Vec3::Y);
    if inst.world_from_object.matrix3.determinant() < 0.0 {
        n = -n;
    }
    if p.side == 1 {
        n = -n;
    }
    // A ray arriving against the side's normal: the hit is on that side.
    let ray = Ray::new(position + n * 1e-3, -n);
    let hit = illume_accel::Hit {
        t: 1e-3,
        instance: p.instance,
        triangle: p.triangle,
        barycentrics: b,
    };
    white(world.surface(&ray, &hit))
}

/// Per part of `parts`: the mean of `spp` gathers from `hit` (seeded per sample and
/// texel `index`; the same paths for every part), and the mean of the first half of them
/// (for the denoiser's variance).
fn gather(
    world: &World,
    hit: SurfaceHit,
    spp: u32,
    seed: u64,
    index: u64,
    parts: &[Part],
) -> Vec<(Rgb, Rgb)> {
    let path = PathSettings::default();
    let wo = hit.facing_normal();
    let mut sum = vec![[0f64; 3]; parts.len()];
    let mut half = sum.clone();
    for s in 0..spp {
        if s == spp / 2 {
            half.clone_from(&sum);
        }
        let mut rng = Pcg32::new(mix64(seed.wrapping_add(s as u64)), index);
        let mut out = PathRadiance::default();
        continue_path(world, hit, wo, &mut rng, &path, &mut out);
        for (part, sum) in parts.iter().zip(sum.iter_mut()) {
            let v = part.of(&out);
            for c in 0..3 {
                sum[c] += v[c] as f64;
            }
        }
    }
    let mean = |sum: [f64; 3], n: u32| {
        let n = n.max(1) as f64;
        Rgb::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        )
    };
    sum.into_iter()
        .zip(half)
        .map(|(s, h)| (mean(s, spp), mean(h, spp / 2)))
        .collect()
}

/// Whether most of a few rays from `origin` about `normal` hit back faces within
/// `reach`: the point is inside other geometry (a floor under a wall, a probe in a
/// column).
fn buried(world: &World, origin: Vec3, normal: Option<Vec3>, reach: f32, index: u64) -> bool {
    const RAYS: u32 = 16;
    let mut rng = Pcg32::new(0x6275_7269_6564, index);
    let mut back = 0;
    for _ in 0..RAYS {
        let d = match normal {
            Some(n) => illume_core::Frame::from_normal(n)
                .to_world(illume_core::sampling::cosine_hemisphere(rng.next_2d())),
            None => illume_core::sampling::uniform_sphere(rng.next_2d()),
        };
        let ray = Ray::segment(origin, d, reach);
        if let Some(h) = world.tracer.intersect(&ray, illume_scene::MASK_DEFAULT) {
            let s = world.surface(&ray, &h);
            if !s.front_face && !world.scene.materials[s.material.index()].double_sided {
                back += 1;
            }
        }
    }
    back * 2 > RAYS
}

/// A valid lightmap texel's guide and, per part, (all samples' mean, first half's mean).
type Gathered = (GuideTexel, Vec<(Rgb, Rgb)>);

/// Renders the atlas, one image per part of `parts`: lightmap texels (valid ones
/// gathered and `denoise`d within their chart, buried ones then copied from the nearest
/// valid texel of their chart), then the probes (never filtered: six directions of one
/// point are not neighbours).
fn render_atlas(
    world: &World,
    atlas: &Atlas,
    spp: u32,
    seed: u64,
    parts: &[Part],
    denoise: Denoise,
) -> Vec<RgbImage> {
    let (w, h) = atlas.image_size();
    let texels = atlas.lightmap_texels();
    let reach = 2.0 / atlas.density;
    let gathered: Vec<Option<Gathered>> = (0..texels)
        .into_par_iter()
        .with_min_len(64)
        .map(|i| {
            let p = atlas.point(i)?;
            let hit = texel_hit(world, &p);
            let origin = hit.spawn_origin(hit.facing_geometric_normal());
            if buried(world, origin, Some(hit.facing_normal()), reach, i as u64) {
                return None;
            }
            let means = gather(world, hit, spp, seed, i as u64, parts);
            let rect = atlas
                .slot(p.instance, p.triangle, p.side == 1)
                .map_or([0; 4], |s| s.rect);
            let guide = GuideTexel {
                position: hit.position,
                normal: hit.facing_normal(),
                albedo: Rgb::ONE,
                footprint: 1.0 / atlas.density,
                // A chart's top-left texel names it (charts never overlap).
                region: rect[1].wrapping_mul(atlas.width).wrapping_add(rect[0]),
            };
            Some((guide, means))
        })
        .collect();
    let guide = (denoise == Denoise::Atrous && texels > 0).then(|| Guide {
        width: atlas.width,
        height: atlas.height,
        texels: gathered.iter().map(|g| g.as_ref().map(|g| g.0)).collect(),
    });
    // Probes: six white gathers each; buried probes black (their flag says so).
    let template = (0..texels)
        .find_map(|i| atlas.point(i))
        .map(|p| texel_hit(world, &p));
    let flags = probe_flags(world, atlas);
    let probe_values: Vec<Vec<Rgb>> = (0..6 * atlas.probes.count())
        .into_par_iter()
        .with_min_len(6)
        .map(|j| {
            let black = vec![Rgb::ZERO; parts.len()];
            let Some(template) = template else {
                return black;
            };
            let (probe, axis) = (j / 6, j % 6);
            let position = atlas.probes.position(probe);
            if flags[probe] < 0.5 {
                return black;
            }
            let n = PROBE_AXES[axis];
            let hit = SurfaceHit {
                position,
                geometric_normal: n,
                shading_normal: n,
                front_face: true,
                ..template
            };
            gather(world, hit, spp, seed, (texels + j) as u64, parts)
                .into_iter()
                .map(|m| m.0)
                .collect()
        })
        .collect();
    (0..parts.len())
        .map(|k| {
            let mut values: Vec<Option<Rgb>> = gathered
                .iter()
                .map(|g| g.as_ref().map(|g| g.1[k].0))
                .collect();
            if let Some(guide) = &guide {
                let lightmap = |half: bool| {
                    let pick = |m: &(Rgb, Rgb)| if half { m.1 } else { m.0 };
                    RgbImage::from_vec(
                        atlas.width,
                        atlas.height,
                        gathered
                            .iter()
                            .map(|g| g.as_ref().map_or(Rgb::ZERO, |g| pick(&g.1[k])))
                            .collect(),
                    )
                    .expect("lightmap size")
                };
                let half = (spp >= 2).then(|| lightmap(true));
                let filtered =
                    illume_render::denoise::atrous(&lightmap(false), half.as_ref(), guide);
                for (v, f) in values.iter_mut().zip(filtered.pixels()) {
                    if v.is_some() {
                        *v = Some(*f);
                    }
                }
            }
            dilate(atlas, &mut values);
            let mut pixels: Vec<Rgb> = values.into_iter().map(|v| v.unwrap_or(Rgb::ZERO)).collect();
            pixels.extend(probe_values.iter().map(|p| p[k]));
            pixels.resize(w as usize * h as usize, Rgb::ZERO);
            RgbImage::from_vec(w, h, pixels).expect("atlas image size")
        })
        .collect()
}

/// Whether probe `i` is inside geometry (left out of lookups).
pub fn probe_buried(world: &World, atlas: &Atlas, i: usize) -> bool {
    buried(
        world,
        atlas.probes.position(i),
        None,
        atlas.probes.spacing,
        0x7072_6f62_0000 + i as u64,
    )
}

/// The probes' flags (1 valid, 0 buried), as stored in an atlas file.
pub fn probe_flags(world: &World, atlas: &Atlas) -> Vec<f32> {
    (0..atlas.probes.count())
        .into_par_iter()
        .map(|i| {
            if probe_buried(world, atlas, i) {
                0.0
            } else {
                1.0
            }
        })
        .collect()
}

/// Gives every `None` texel the value of a `Some` neighbour, growing outwards a ring at a
/// time (4-neighbours, never across rows of another chart: texels of one chart only take
/// values through texels of that chart, as charts are rectangles and lookups clamp to
/// them, values leaking across a chart's border would never be read anyway).
fn dilate(atlas: &Atlas, values: &mut [Option<Rgb>]) {
    let (w, h) = (atlas.width as usize, atlas.height as usize);
    loop {
        let mut changed = false;
        let snapshot = values.to_vec();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if snapshot[i].is_some() || atlas.point(i).is_none() {
                    continue;
                }
                let mut sum = Rgb::ZERO;
                let mut n = 0;
                let neighbours = [
                    (x > 0).then(|| i - 1),
                    (x + 1 < w).then(|| i + 1),
                    (y > 0).then(|| i - w),
                    (y + 1 < h).then(|| i + w),
                ];
                for j in neighbours.into_iter().flatten() {
                    if same_chart(atlas, i, j)
                        && let Some(v) = snapshot[j]
                    {
                        sum += v;
                        n += 1;
                    }
                }
                if n > 0 {
                    values[i] = Some(sum * (1.0 / n as f32));
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}

/// Whether texels `i` and `j` sample the same chart (same instance and side, and the
/// same slot rectangle).
fn same_chart(atlas: &Atlas, i: usize, j: usize) -> bool {
    match (atlas.point(i), atlas.point(j)) {
        (Some(a), Some(b)) => {
            let ra = atlas
                .slot(a.instance, a.triangle, a.side == 1)
                .map(|s| s.rect);
            let rb = atlas
                .slot(b.instance, b.triangle, b.side == 1)
                .map(|s| s.rect);
            ra.is_some() && ra == rb
        }
        _ => false,
    }
}

/// Bilinear lookup in the cube image `values` (faces stacked) along direction `d`.
pub fn cube_lookup(values: &[Rgb], face: u32, d: Vec3) -> Rgb {
    cube_texels(face, d)
        .iter()
        .map(|&(t, w)| values[t] * w)
        .fold(Rgb::ZERO, |a, b| a + b)
}

/// The four texels (index in the stacked faces, bilinear weight) along direction `d`
/// (weights 0 for a zero direction).
pub fn cube_texels(face: u32, d: Vec3) -> [(usize, f32); 4] {
    let a = d.abs();
    let f = if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 { 0 } else { 1 }
    } else if a.y >= a.z {
        if d.y > 0.0 { 2 } else { 3 }
    } else if d.z > 0.0 {
        4
    } else {
        5
    };
    let (forward, up) = CUBE_FACES[f];
    let right = forward.cross(up);
    let depth = d.dot(forward);
    if depth <= 0.0 {
        return [(0, 0.0); 4];
    }
    let ndc = Vec2::new(d.dot(right), d.dot(up)) / depth;
    let n = face as f32;
    // Pixel (x, y)'s centre is at ndc ((x + 0.5)/n·2 − 1, 1 − (y + 0.5)/n·2).
    let x = ((ndc.x + 1.0) * 0.5 * n - 0.5).clamp(0.0, n - 1.0);
    let y = ((1.0 - ndc.y) * 0.5 * n - 0.5).clamp(0.0, n - 1.0);
    let (ix, iy) = (x.floor() as usize, y.floor() as usize);
    let (tx, ty) = (x - ix as f32, y - iy as f32);
    let last = face as usize - 1;
    let (jx, jy) = ((ix + 1).min(last), (iy + 1).min(last));
    let base = f * (face as usize).pow(2);
    let at = |x: usize, y: usize| base + y * face as usize + x;
    [
        (at(ix, iy), (1.0 - tx) * (1.0 - ty)),
        (at(jx, iy), tx * (1.0 - ty)),
        (at(ix, jy), (1.0 - tx) * ty),
        (at(jx, jy), tx * ty),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_faces_are_right_handed_cameras() {
        for (f, (forward, _)) in CUBE_FACES.iter().enumerate() {
            let m = face_rotation(f);
            assert!((m.determinant() - 1.0).abs() < 1e-6);
            // The camera looks along −Z: its forward is the face's axis.
            assert!((m * Vec3::NEG_Z - *forward).length() < 1e-6);
        }
    }

    #[test]
    fn cube_lookup_finds_the_texel_a_face_camera_renders() {
        // Each texel holds its own index; the direction through a face pixel's centre
        // reads that pixel back.
        let face = 8u32;
        let values: Vec<Rgb> = (0..6 * 64).map(|i| Rgb::splat(i as f32)).collect();
        for f in 0..6 {
            let mut camera = illume_scene::Camera {
                name: String::new(),
                yfov_rad: std::f32::consts::FRAC_PI_2,
                node: illume_scene::NodeId(0),
                world_from_camera: Affine3A::IDENTITY,
            };
            camera.world_from_camera = Affine3A::from_mat3(face_rotation(f));
            let rays = illume_transport::CameraRays::new(&camera, face, face);
            for (x, y) in [(0, 0), (3, 5), (7, 7), (6, 1)] {
                let d = rays.ray(x, y, Vec2::splat(0.5)).dir;
                let got = cube_lookup(&values, face, d).x;
                let expect = (f as u32 * 64 + y * face + x) as f32;
                assert!(
                    (got - expect).abs() < 1e-3,
                    "face {f} ({x},{y}): {got} vs {expect}"
                );
            }
        }
    }

    /// Issue 38: the cube's side is capped, asked or automatic, and the error names the
    /// setting and the value; the automatic side of an ordinary camera is unchanged.
    #[test]
    fn cube_face_is_capped() {
        let fov = 70f32.to_radians();
        assert_eq!(cube_face(0, 600, fov).unwrap(), 857);
        assert_eq!(cube_face(24, 600, fov).unwrap(), 24);
        assert_eq!(cube_face(MAX_CUBE_FACE, 600, fov).unwrap(), MAX_CUBE_FACE);
        for (asked, height, yfov, value) in [
            (MAX_CUBE_FACE + 1, 600, fov, "3345 pixels"),
            (u32::MAX, 600, fov, "4294967295 pixels"),
            // 600 rows at 0.01°: 6.9 M pixels a side.
            (0, 600, 0.01f32.to_radians(), "0 (automatic)"),
            (0, 600, 0.0, "inf pixels"),
        ] {
            let e = cube_face(asked, height, yfov)
                .expect_err("above the cap")
                .to_string();
            assert!(
                e.contains("precomputed.cube_face") && e.contains(value) && e.contains("3344"),
                "{e}"
            );
        }
    }
}
