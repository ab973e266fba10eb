//! Every emitter of a scene in one list, chosen in proportion to power, with
//! next-event sampling (a point on a light seen from a surface point) and emission
//! sampling (a photon's origin, direction and flux) for every light type.
//!
//! Entries are the analytic lights (point, spot, directional) and every emissive
//! triangle (area lights, world space, one-sided unless the material is double-sided).
//! The selection weight of an entry is the channel mean of its power:
//! point 4πI, spot I·Ω_spot (glTF falloff integrated), directional E·πR² (R = scene
//! bounding-sphere radius), triangle πLeA (×2 when double-sided).
//!
//! The sky ([`illume_scene::Sky`]) is not among the entries that next-event estimation
//! selects: it is sampled on its own ([`LightSet::sample_sky`], cosine-weighted about the
//! surface normal, so an unoccluded Lambertian surface under a uniform sky gets exactly
//! ρ·L from every sample) and seen by escaping rays ([`LightSet::sky_radiance`]). Photon
//! emission selects it by power (L·4π·πR²) beside the other emitters.

use illume_core::sampling::{
    AliasTable, SampleStream, concentric_disk, cosine_hemisphere, uniform_sphere, uniform_triangle,
};
use illume_core::{Frame, PI, Ray, Rgb, Vec3, channel_mean, offset_ray_origin};
use illume_scene::{InstanceId, LightId, LightKind, Scene, spot_falloff};
use std::collections::HashMap;

/// One emitter.
#[derive(Clone, Debug)]
pub enum Emitter {
    /// A point light at `position` with intensity I [W/sr].
    Point {
        /// Which scene light.
        light: LightId,
        /// World position.
        position: Vec3,
        /// Radiant intensity [W/sr].
        intensity: Rgb,
    },
    /// A spot light with glTF falloff.
    Spot {
        /// Which scene light.
        light: LightId,
        /// World position.
        position: Vec3,
        /// Unit direction of the axis.
        axis: Vec3,
        /// Axis intensity [W/sr].
        intensity: Rgb,
        /// cos of the inner cone half-angle.
        cos_inner: f32,
        /// cos of the outer cone half-angle.
        cos_outer: f32,
    },
    /// A directional light shining along `direction`.
    Directional {
        /// Which scene light.
        light: LightId,
        /// Unit direction light travels in.
        direction: Vec3,
        /// Irradiance on a perpendicular surface [W/m²].
        irradiance: Rgb,
    },
    /// An emissive triangle, world space.
    Triangle {
        /// The instance it belongs to.
        instance: InstanceId,
        /// Triangle index in the instance's mesh.
        triangle: u32,
        /// World corners (counter-clockwise = front).
        corners: [Vec3; 3],
        /// Unit front normal.
        normal: Vec3,
        /// Area \[m²\].
        area: f32,
        /// Emitted radiance Le [W/(m²·sr)].
        radiance: Rgb,
        /// Emits from both faces.
        double_sided: bool,
        /// An emissive texture and the triangle's texture coordinates: the radiance at
        /// a point is `radiance × texture(uv)`.
        texture: Option<(
            std::sync::Arc<illume_scene::Texture>,
            [illume_core::Vec2; 3],
        )>,
        /// The mesh's alpha-mask holes when this triangle has them: nothing is emitted
        /// from a hole.
        cutout: Option<std::sync::Arc<illume_scene::MeshCutout>>,
    },
}

/// A light sample for next-event estimation at a surface point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the surface point to the light.
    pub wi: Vec3,
    /// Distance to the sampled light point (∞ for directional lights).
    pub distance: f32,
    /// Incident radiance over the sample's pdf, including the selection probability:
    /// the estimator is `f · weight · cosθ_surface` (for delta lights `weight` is I/d² or
    /// E divided by the selection probability).
    pub weight: Rgb,
    /// Solid-angle pdf of the sample including selection (0 for delta lights: no MIS).
    pub pdf: f32,
}

impl LightSample {
    /// The shadow ray of this sample from `origin` (a point just off the surface): to
    /// just short of the light point, or to infinity for a directional sample.
    #[inline]
    pub fn shadow_ray(&self, origin: Vec3) -> Ray {
        let t_max = if self.distance.is_finite() {
            (self.distance - 2e-4 * (1.0 + self.distance)).max(0.0)
        } else {
            f32::INFINITY
        };
        Ray::segment(origin, self.wi, t_max)
    }
}

/// A photon leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    /// Origin and unit direction.
    pub ray: Ray,
    /// Flux carried \[W\] per channel, for one photon out of one (divide by the photon
    /// count of the batch).
    pub flux: Rgb,
}

/// All emitters of a scene with power-proportional selection.
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    emitters: Vec<Emitter>,
    powers: Vec<Rgb>,
    table: Option<AliasTable>,
    triangle_index: HashMap<(u32, u32), u32>,
    scene_center: Vec3,
    scene_radius: f32,
    total_power: Rgb,
    analytic_count: usize,
    area_table: Option<AliasTable>,
    /// Per emitter, the frame emission directions are sampled in (spot axis, light
    /// direction, triangle front normal; unused for points), built once rather than per
    /// photon.
    emission_frames: Vec<Frame>,
    /// The scene's sky, if any.
    sky: Option<illume_scene::Sky>,
    /// The sky's power (photon emission), zero without a sky.
    sky_power: Rgb,
    /// Photon-emission selection over the emitters then the sky (only with a sky; the
    /// NEE table serves emission otherwise).
    emission_table: Option<AliasTable>,
}

/// Texel weights of `map` for importance sampling: the mean luminance of the bilinear
/// lookup over each texel's footprint — the separable [1, 6, 1]/8 filter of the texel and
/// its neighbours, so the density is positive wherever a lookup can be (bilinear lookups
/// spread a texel half a texel into its neighbours) and otherwise follows the radiance
/// closely — times sinθ of its row (texels shrink towards the poles).
fn env_weights(map: &illume_scene::EnvMap) -> Vec<f32> {
    let (w, h) = (map.width as i64, map.height as i64);
    let lum = |x: i64, y: i64| {
        let t = map.texels[(y.clamp(0, h - 1) * w + x.rem_euclid(w)) as usize];
        illume_core::luminance(t).max(0.0)
    };
    const TAP: [f32; 3] = [0.125, 0.75, 0.125];
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let sin = ((y as f32 + 0.5) / h as f32 * PI).sin();
        for x in 0..w {
            let mut m = 0f32;
            for (dy, wy) in (-1..=1).zip(TAP) {
                for (dx, wx) in (-1..=1).zip(TAP) {
                    m += wx * wy * lum(x + dx, y + dy);
                }
            }
            out.push(m * sin);
        }
    }
    out
}

/// Texel selection of an environment map, by filtered luminance × sinθ ([`env_weights`]):
/// built in place ([`AliasTable::from_vec`]; a map at the size cap has tens of millions of
/// texels) once per image and shared by every light set and scaled copy of it
/// ([`illume_scene::EnvSampling`]). `None` for a black map or a zero scale (night).
fn env_table(map: &illume_scene::EnvMap) -> Option<&AliasTable> {
    if map.scale <= 0.0 {
        return None;
    }
    map.sampling
        .get_or_build(|| AliasTable::from_vec(env_weights(map)))
}

impl LightSet {
    /// Collects the emitters of `scene` at its current time.
    pub fn new(scene: &Scene) -> Self {
        let bounds = scene.bounds();
        let scene_center = if bounds.is_empty() {
            Vec3::ZERO
        } else {
            bounds.center()
        };
        let scene_radius = bounds.bounding_radius().max(1e-3);
        let mut emitters = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            let light = LightId(i as u32);
            let position = l.position();
            emitters.push(match l.kind {
                LightKind::Point { intensity } => Emitter::Point {
                    light,
                    position,
                    intensity,
                },
                LightKind::Spot {
                    intensity,
                    inner_cone_rad,
                    outer_cone_rad,
                } => Emitter::Spot {
                    light,
                    position,
                    axis: l.direction(),
                    intensity,
                    cos_inner: inner_cone_rad.min(outer_cone_rad).cos(),
                    cos_outer: outer_cone_rad.cos(),
                },
                LightKind::Directional { irradiance } => Emitter::Directional {
                    light,
                    direction: l.direction(),
                    irradiance,
                },
            });
        }
        // Holes of alpha-masked emitters, per mesh (built when first needed).
        let mut cutouts: Vec<Option<Option<std::sync::Arc<illume_scene::MeshCutout>>>> =
            vec![None; scene.meshes.len()];
        for (ii, inst) in scene.instances.iter().enumerate() {
            // Emitters are what ordinary rays see: removed instances (mask 0) and
            // technique-only copies (phantoms) emit nothing.
            if inst.mask & illume_scene::MASK_DEFAULT == 0 {
                continue;
            }
            let mesh = &scene.meshes[inst.mesh.index()];
            for (t, m) in mesh.triangle_materials.iter().enumerate() {
                let mat = &scene.materials[m.index()];
                if !mat.is_emissive() {
                    continue;
                }
                let corners = mesh
                    .triangle(t)
                    .map(|p| inst.world_from_object.transform_point3(p));
                // A mirroring instance keeps its object-space front (glTF winding rule).
                let mirror = if inst.world_from_object.matrix3.determinant() < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                let c = (corners[1] - corners[0]).cross(corners[2] - corners[0]) * mirror;
                let area = 0.5 * c.length();
                if area <= 0.0 {
                    continue;
                }
                let texture = mat.emissive_texture.map(|tex| {
                    let uvs = if mesh.uvs.is_empty() {
                        [illume_core::Vec2::ZERO; 3]
                    } else {
                        // The transform is affine: transforming the corners transforms
                        // every interpolated point.
                        mesh.indices[t].map(|v| mat.emissive_uv(mesh.uvs[v as usize]))
                    };
                    (scene.textures[tex.index()].clone(), uvs)
                });
                let cutout = cutouts[inst.mesh.index()]
                    .get_or_insert_with(|| {
                        illume_scene::MeshCutout::new(scene, inst.mesh).map(std::sync::Arc::new)
                    })
                    .clone()
                    .filter(|c| c.is_tested(t as u32));
                emitters.push(Emitter::Triangle {
                    instance: InstanceId(ii as u32),
                    triangle: t as u32,
                    corners,
                    normal: c.normalize(),
                    area,
                    radiance: mat.emission,
                    double_sided: mat.double_sided,
                    texture,
                    cutout,
                });
            }
        }
        let powers: Vec<Rgb> = emitters.iter().map(|e| power(e, scene_radius)).collect();
        let table = AliasTable::new(&powers.iter().map(|p| channel_mean(*p)).collect::<Vec<_>>());
        let triangle_index = emitters
            .iter()
            .enumerate()
            .filter_map(|(i, e)| match e {
                Emitter::Triangle {
                    instance, triangle, ..
                } => Some(((instance.0, *triangle), i as u32)),
                _ => None,
            })
            .collect();
        let sky_power = scene.sky_power(scene_radius);
        let total_power = powers.iter().copied().sum::<Rgb>() + sky_power;
        let emission_table = scene.sky.as_ref().and_then(|_| {
            let mut weights: Vec<f32> = powers.iter().map(|p| channel_mean(*p)).collect();
            weights.push(channel_mean(sky_power));
            AliasTable::new(&weights)
        });
        let analytic_count = scene.lights.len();
        let area_table = AliasTable::new(
            &powers[analytic_count..]
                .iter()
                .map(|p| channel_mean(*p))
                .collect::<Vec<_>>(),
        );
        let emission_frames = emitters
            .iter()
            .map(|e| {
                Frame::from_normal(match e {
                    Emitter::Point { .. } => Vec3::Z,
                    Emitter::Spot { axis, .. } => *axis,
                    Emitter::Directional { direction, .. } => *direction,
                    Emitter::Triangle { normal, .. } => *normal,
                })
            })
            .collect();
        // Built now rather than by the first sample (once per image: see `env_table`).
        if let Some(illume_scene::Sky::Equirect(map)) = &scene.sky {
            env_table(map);
        }
        Self {
            emission_frames,
            emitters,
            powers,
            table,
            triangle_index,
            scene_center,
            scene_radius,
            total_power,
            analytic_count,
            area_table,
            sky: scene.sky.clone(),
            sky_power,
            emission_table,
        }
    }

    /// An environment map's sample: a direction from the texel table and a uniform
    /// position in the texel (three numbers in all); `None` for a degenerate (polar)
    /// direction or a black map.
    fn sample_env(
        &self,
        map: &illume_scene::EnvMap,
        u_texel: f32,
        u: illume_core::Vec2,
    ) -> Option<(Vec3, f32)> {
        // Millions of texels: the texel from two numbers (`u_texel`, `u.x`), and the
        // point's x in the texel from what the table leaves of them.
        let (k, _, x) = env_table(map)?.sample_fine(illume_core::Vec2::new(u_texel, u.x));
        let (i, j) = (k as u32 % map.width, k as u32 / map.width);
        let uv = illume_core::Vec2::new(
            (i as f32 + x) / map.width as f32,
            (j as f32 + u.y) / map.height as f32,
        );
        let wi = map.direction(uv);
        // The density at the sampled direction (the texel's pmf over its solid angle).
        let pdf = self.env_pdf(map, wi);
        (pdf > 0.0).then_some((wi, pdf))
    }

    /// Solid-angle pdf of [`LightSet::sample_env`] for `wi`.
    fn env_pdf(&self, map: &illume_scene::EnvMap, wi: Vec3) -> f32 {
        let Some(table) = env_table(map) else {
            return 0.0;
        };
        // Clamped at the poles, where the Jacobian sinθ vanishes: the density there is
        // large but finite, the same for sampling and for MIS.
        let sin = (1.0 - wi.y * wi.y).max(0.0).sqrt().max(1e-6);
        let uv = map.uv(wi);
        let i = ((uv.x * map.width as f32) as u32).min(map.width - 1);
        let j = ((uv.y * map.height as f32) as u32).min(map.height - 1);
        let texels = (map.width * map.height) as f32;
        table.pmf((j * map.width + i) as usize) * texels / (2.0 * PI * PI * sin)
    }

    /// The sky, if the scene has one.
    pub fn sky(&self) -> Option<&illume_scene::Sky> {
        self.sky.as_ref()
    }

    /// Radiance a ray travelling along unit `dir` sees when it leaves the scene (zero
    /// without a sky).
    #[inline]
    pub fn sky_radiance(&self, dir: Vec3) -> Rgb {
        self.sky.as_ref().map_or(Rgb::ZERO, |s| s.radiance(dir))
    }

    /// Samples the sky for next-event estimation at a point with unit normal `normal`
    /// (the side light arrives on). A uniform sky: a cosine-weighted direction about the
    /// normal (pdf cosθ/π; one 2-D number). An environment map: a texel by luminance ×
    /// sinθ, then a uniform point in it (one 1-D and one 2-D number), whatever the
    /// normal. The weight is L/pdf; `None` without a sky or for a degenerate sample.
    /// Visibility (a ray to infinity) is the caller's job.
    pub fn sample_sky(&self, normal: Vec3, sampler: &mut impl SampleStream) -> Option<LightSample> {
        let (wi, pdf) = match self.sky.as_ref()? {
            illume_scene::Sky::Uniform { .. } => {
                let local = cosine_hemisphere(sampler.next_2d());
                if local.z <= 0.0 {
                    return None;
                }
                let wi = Frame::from_normal(normal).to_world(local).normalize();
                (wi, local.z * std::f32::consts::FRAC_1_PI)
            }
            illume_scene::Sky::Equirect(map) => {
                let u_texel = sampler.next_1d();
                self.sample_env(map, u_texel, sampler.next_2d())?
            }
        };
        Some(LightSample {
            wi,
            distance: f32::INFINITY,
            weight: self.sky_radiance(wi) / pdf,
            pdf,
        })
    }

    /// Solid-angle pdf of [`LightSet::sample_sky`] choosing `wi` at a point with unit
    /// `normal` (for MIS when a BSDF-sampled ray escapes).
    #[inline]
    pub fn sky_pdf(&self, normal: Vec3, wi: Vec3) -> f32 {
        match &self.sky {
            None => 0.0,
            Some(illume_scene::Sky::Uniform { .. }) => {
                normal.dot(wi).max(0.0) * std::f32::consts::FRAC_1_PI
            }
            Some(illume_scene::Sky::Equirect(map)) => self.env_pdf(map, wi),
        }
    }

    /// The emitters.
    pub fn emitters(&self) -> &[Emitter] {
        &self.emitters
    }

    /// Power of each emitter \[W\] per channel.
    pub fn powers(&self) -> &[Rgb] {
        &self.powers
    }

    /// Total emitted power \[W\] per channel.
    pub fn total_power(&self) -> Rgb {
        self.total_power
    }

    /// True when nothing emits (no emitter and no sky).
    pub fn is_empty(&self) -> bool {
        self.table.is_none() && self.emission_table.is_none()
    }

    /// Probability that emitter `i` is selected.
    pub fn selection_pmf(&self, i: usize) -> f32 {
        self.table.as_ref().map_or(0.0, |t| t.pmf(i))
    }

    /// Picks an emitter in proportion to power: `(index, probability)`.
    pub fn select(&self, u: f32) -> Option<(usize, f32)> {
        self.table.as_ref().map(|t| t.sample(u))
    }

    /// Solid-angle pdf with which [`LightSet::sample_incident`] would have produced the
    /// point `light_point` on emissive triangle (`instance`, `triangle`) seen from
    /// `from` (for MIS when a BSDF-sampled ray hits an emitter).
    pub fn pdf_triangle_hit(
        &self,
        instance: InstanceId,
        triangle: u32,
        from: Vec3,
        light_point: Vec3,
    ) -> f32 {
        let Some(&i) = self.triangle_index.get(&(instance.0, triangle)) else {
            return 0.0;
        };
        let Emitter::Triangle { normal, area, .. } = &self.emitters[i as usize] else {
            return 0.0;
        };
        let d = light_point - from;
        let dist2 = d.length_squared();
        let cos_l = normal.dot(d.normalize()).abs();
        if cos_l <= 0.0 {
            return 0.0;
        }
        self.selection_pmf(i as usize) * dist2 / (cos_l * area)
    }

    /// Samples incident light at `p` (next-event estimation): picks an emitter by power,
    /// then a point on it. `None` when the sample carries nothing (outside a spot cone,
    /// back of a one-sided emitter, empty light set). Visibility is the caller's job.
    pub fn sample_incident(&self, p: Vec3, sampler: &mut impl SampleStream) -> Option<LightSample> {
        let (i, pmf) = self.select(sampler.next_1d())?;
        let u = sampler.next_2d();
        let (mut s, is_delta) = self.incident_from(i, p, u)?;
        s.weight /= pmf;
        s.pdf = if is_delta { 0.0 } else { s.pdf * pmf };
        Some(s)
    }

    /// Indices of the analytic (point, spot, directional) emitters: they come first.
    pub fn analytic_range(&self) -> std::ops::Range<usize> {
        0..self.analytic_count
    }

    /// Samples incident light at `p` from emissive triangles only, chosen by power (the
    /// renderer handles analytic lights exactly and area lights with this).
    pub fn sample_area_incident(
        &self,
        p: Vec3,
        sampler: &mut impl SampleStream,
    ) -> Option<LightSample> {
        let table = self.area_table.as_ref()?;
        let (k, pmf) = table.sample(sampler.next_1d());
        let u = sampler.next_2d();
        let (mut s, _) = self.incident_from(self.analytic_count + k, p, u)?;
        s.weight /= pmf;
        s.pdf *= pmf;
        Some(s)
    }

    /// True when the scene has emissive triangles.
    pub fn has_area_lights(&self) -> bool {
        self.area_table.is_some()
    }

    /// Incident light at `p` from emitter `i` (no selection probability applied); for a
    /// triangle, `u` picks the point. Returns the sample and whether it is a delta light.
    pub fn incident_from(
        &self,
        i: usize,
        p: Vec3,
        u: illume_core::Vec2,
    ) -> Option<(LightSample, bool)> {
        Some(match &self.emitters[i] {
            Emitter::Point {
                position,
                intensity,
                ..
            } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                (
                    LightSample {
                        wi: d / dist,
                        distance: dist,
                        weight: *intensity / dist2,
                        pdf: 0.0,
                    },
                    true,
                )
            }
            Emitter::Spot {
                position,
                axis,
                intensity,
                cos_inner,
                cos_outer,
                ..
            } => {
                let d = *position - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let f = spot_falloff(axis.dot(-wi), *cos_inner, *cos_outer);
                if f <= 0.0 {
                    return None;
                }
                (
                    LightSample {
                        wi,
                        distance: dist,
                        weight: *intensity * (f / dist2),
                        pdf: 0.0,
                    },
                    true,
                )
            }
            Emitter::Directional {
                direction,
                irradiance,
                ..
            } => (
                LightSample {
                    wi: -*direction,
                    distance: f32::INFINITY,
                    weight: *irradiance,
                    pdf: 0.0,
                },
                true,
            ),
            Emitter::Triangle {
                corners,
                normal,
                area,
                radiance,
                double_sided,
                texture,
                cutout,
                triangle,
                ..
            } => {
                let b = uniform_triangle(u);
                let radiance = &textured_radiance(*radiance, texture, cutout, *triangle, b);
                let q = corners[0] * (1.0 - b.x - b.y) + corners[1] * b.x + corners[2] * b.y;
                let d = q - p;
                let dist2 = d.length_squared();
                let dist = dist2.sqrt();
                let wi = d / dist;
                let cos_l = -normal.dot(wi);
                if cos_l <= 0.0 && !double_sided {
                    return None;
                }
                let cos_l = cos_l.abs();
                if cos_l <= 1e-7 {
                    return None;
                }
                let pdf = dist2 / (cos_l * area);
                (
                    LightSample {
                        wi,
                        distance: dist,
                        weight: *radiance / pdf,
                        pdf,
                    },
                    false,
                )
            }
        })
    }

    /// Samples a photon leaving an emitter chosen by power. The flux is the total power
    /// divided by the photon's pdf, so the mean over photons of `flux` is the scene's
    /// total power; photons from point, spot and area lights all carry the same power
    /// (importance sampling matches each emitter's profile exactly).
    pub fn sample_emission(&self, sampler: &mut impl SampleStream) -> Option<EmissionSample> {
        let (i, pmf) = match &self.emission_table {
            Some(t) => t.sample(sampler.next_1d()),
            None => self.select(sampler.next_1d())?,
        };
        let u_pos = sampler.next_2d();
        let u_dir = sampler.next_2d();
        self.emit_from(i, pmf, u_pos, u_dir, sampler)
    }

    /// Which emission coordinates emitter `i` reads (`i` = [`LightSet::emitters`]'s
    /// length is the sky): `(position, direction)`. Point and spot lights read only a
    /// direction, directional lights only a position on the disk facing them; area lights
    /// and the sky read both (an environment map two more numbers from the sampler).
    /// Techniques that map sample dimensions to Halton bases draw only these.
    pub fn emission_coordinates(&self, i: usize) -> (bool, bool) {
        match self.emitters.get(i) {
            Some(Emitter::Point { .. } | Emitter::Spot { .. }) => (false, true),
            Some(Emitter::Directional { .. }) => (true, false),
            Some(Emitter::Triangle { .. }) | None => (true, true),
        }
    }

    /// The sky's photon-emission power \[W\] (zero without a sky).
    pub fn sky_power(&self) -> Rgb {
        self.sky_power
    }

    /// A photon leaving emitter `i` (`i` = [`LightSet::emitters`]'s length: the sky),
    /// chosen with probability `pmf`, from the emission coordinates `u_pos` (a point on
    /// an area light or on the disk a directional light or the sky crosses) and `u_dir`
    /// (a direction); an environment-mapped sky draws two more numbers from `sampler`.
    /// [`LightSet::sample_emission`] is this after choosing `i` by power. The flux is
    /// the emitter's power over `pmf` (textured emitters: the sampled point's).
    pub fn emit_from(
        &self,
        i: usize,
        pmf: f32,
        u_pos: illume_core::Vec2,
        u_dir: illume_core::Vec2,
        sampler: &mut impl SampleStream,
    ) -> Option<EmissionSample> {
        if i == self.emitters.len() {
            // The sky: a direction the light comes from (uniform over the sphere, or by
            // the environment map's texel table), an origin uniform on the disk of the
            // scene's bounding sphere facing it, outside the scene.
            let disk_area = PI * self.scene_radius * self.scene_radius;
            let (from, flux) = match self.sky.as_ref()? {
                illume_scene::Sky::Uniform { .. } => (uniform_sphere(u_dir), self.sky_power / pmf),
                illume_scene::Sky::Equirect(map) => {
                    let (from, pdf) = self.sample_env(map, u_dir.x, sampler.next_2d())?;
                    (from, self.sky_radiance(from) * disk_area / (pdf * pmf))
                }
            };
            let dir = -from;
            let f = Frame::from_normal(dir);
            let d = concentric_disk(u_pos) * self.scene_radius;
            let origin =
                self.scene_center - dir * (2.0 * self.scene_radius) + f.s * d.x + f.t * d.y;
            return Some(EmissionSample {
                ray: Ray::new(origin, dir),
                flux,
            });
        }
        let power = self.powers[i];
        let mut textured_flux = None;
        let ray = match &self.emitters[i] {
            Emitter::Point { position, .. } => Ray::new(*position, uniform_sphere(u_dir)),
            Emitter::Spot {
                position,
                cos_inner,
                cos_outer,
                ..
            } => Ray::new(
                *position,
                self.emission_frames[i]
                    .to_world(sample_spot_direction(u_dir, *cos_inner, *cos_outer)),
            ),
            Emitter::Directional { direction, .. } => {
                let d = concentric_disk(u_pos) * self.scene_radius;
                let f = self.emission_frames[i];
                let origin = self.scene_center - *direction * (2.0 * self.scene_radius)
                    + f.s * d.x
                    + f.t * d.y;
                Ray::new(origin, *direction)
            }
            Emitter::Triangle {
                corners,
                normal,
                double_sided,
                texture,
                cutout,
                triangle,
                radiance,
                area,
                ..
            } => {
                let b = uniform_triangle(u_pos);
                if texture.is_some() || cutout.is_some() {
                    // The flux of this point's radiance (the selection used the mean).
                    let point_power = textured_radiance(*radiance, texture, cutout, *triangle, b)
                        * PI
                        * *area
                        * if *double_sided { 2.0 } else { 1.0 };
                    textured_flux = Some(point_power / pmf);
                }
                let q = corners[0] * (1.0 - b.x - b.y) + corners[1] * b.x + corners[2] * b.y;
                let mut u = u_dir;
                let mut n = *normal;
                let mut frame = self.emission_frames[i];
                if *double_sided {
                    // Pick a side with probability 1/2, reusing the first number.
                    if u.x < 0.5 {
                        u.x *= 2.0;
                    } else {
                        u.x = (u.x - 0.5) * 2.0;
                        n = -n;
                        frame = Frame::from_normal(n);
                    }
                }
                let dir = frame.to_world(cosine_hemisphere(u)).normalize();
                Ray::new(offset_ray_origin(q, n, dir), dir)
            }
        };
        Some(EmissionSample {
            ray,
            flux: textured_flux.unwrap_or(power / pmf),
        })
    }
}

/// Direction in the spot's local frame (axis = +Z) distributed exactly as glTF's
/// falloff: constant inside the inner cone, `((cosθ − co)/(ci − co))²` in the ramp.
/// The ramp's mass over cosθ is (ci − co)/3, the core's 1 − ci.
pub fn sample_spot_direction(u: illume_core::Vec2, cos_inner: f32, cos_outer: f32) -> Vec3 {
    let core = 1.0 - cos_inner;
    let ramp = (cos_inner - cos_outer).max(0.0) / 3.0;
    let total = core + ramp;
    let x = u.x * total;
    let cos_theta = if x < core || ramp <= 0.0 {
        1.0 - x.min(core)
    } else {
        // pdf in t = (cosθ − co)/(ci − co) ∝ t² ⇒ t = v^(1/3)
        let v = ((x - core) / ramp).clamp(0.0, 1.0);
        cos_outer + (cos_inner - cos_outer) * v.cbrt()
    };
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

fn power(e: &Emitter, scene_radius: f32) -> Rgb {
    match e {
        Emitter::Point { intensity, .. } => *intensity * 4.0 * PI,
        Emitter::Spot {
            intensity,
            cos_inner,
            cos_outer,
            ..
        } => {
            *intensity
                * (2.0 * PI * (1.0 - cos_inner) + 2.0 * PI * (cos_inner - cos_outer).max(0.0) / 3.0)
        }
        Emitter::Directional { irradiance, .. } => *irradiance * PI * scene_radius * scene_radius,
        Emitter::Triangle {
            area,
            radiance,
            double_sided,
            texture,
            ..
        } => {
            // A textured emitter is selected by its texture's mean (exact power is not
            // needed: NEE and photons use the radiance at the sampled point).
            let mean = texture.as_ref().map_or(Rgb::ONE, |(t, _)| t.average());
            *radiance * mean * PI * *area * if *double_sided { 2.0 } else { 1.0 }
        }
    }
}

/// `radiance` at barycentric point `b` (weights of the second and third corners) of
/// triangle emitter `triangle`, times its emissive texture there; 0 in a hole of its
/// alpha mask.
#[inline]
fn textured_radiance(
    radiance: Rgb,
    texture: &Option<(
        std::sync::Arc<illume_scene::Texture>,
        [illume_core::Vec2; 3],
    )>,
    cutout: &Option<std::sync::Arc<illume_scene::MeshCutout>>,
    triangle: u32,
    b: illume_core::Vec2,
) -> Rgb {
    if cutout.as_ref().is_some_and(|c| !c.keeps(triangle, b)) {
        return Rgb::ZERO;
    }
    match texture {
        None => radiance,
        Some((t, uv)) => {
            let at = uv[0] * (1.0 - b.x - b.y) + uv[1] * b.x + uv[2] * b.y;
            radiance * t.sample(at)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::Pcg32;

    /// Chi-square of directions over bins of cosθ (about the spot axis) against the
    /// exact glTF falloff integrals.
    #[test]
    fn spot_emission_sampling_passes_chi_square() {
        let (ci, co) = (25f32.to_radians().cos(), 35f32.to_radians().cos());
        let bins = 40usize;
        let n = 400_000u32;
        let mut counts = vec![0f64; bins];
        let mut rng = Pcg32::new(3, 3);
        let lo = co as f64;
        for _ in 0..n {
            let d = sample_spot_direction(rng.next_2d(), ci, co);
            let k = (((d.z as f64 - lo) / (1.0 - lo)) * bins as f64).clamp(0.0, bins as f64 - 1.0)
                as usize;
            counts[k] += 1.0;
        }
        let total = (1.0 - ci as f64) + (ci as f64 - co as f64) / 3.0;
        let cdf = |c: f64| -> f64 {
            // ∫_co^c falloff(x) dx
            let (ci, co) = (ci as f64, co as f64);
            if c <= ci {
                let t = (c - co) / (ci - co);
                (ci - co) * t.powi(3) / 3.0
            } else {
                (ci - co) / 3.0 + (c - ci)
            }
        };
        let mut chi2 = 0.0;
        for (k, count) in counts.iter().enumerate() {
            let a = lo + (1.0 - lo) * k as f64 / bins as f64;
            let b = lo + (1.0 - lo) * (k + 1) as f64 / bins as f64;
            let e = (cdf(b) - cdf(a)) / total * n as f64;
            if e > 0.0 {
                chi2 += (count - e).powi(2) / e;
            }
        }
        // 39 degrees of freedom: 99.9th percentile ≈ 72.
        assert!(chi2 < 72.0, "chi2 = {chi2}");
    }

    fn chi2_directions(dirs: &[Vec3], frame: Frame, pdf: impl Fn(f32) -> f64, cos_lo: f32) -> f64 {
        // bins over cosθ ∈ [cos_lo, 1] and φ; expected count from numeric integration of pdf(cosθ)·2π/nφ.
        let (nt, np) = (20usize, 8usize);
        let mut counts = vec![0f64; nt * np];
        for d in dirs {
            let l = frame.to_local(*d);
            let it = (((l.z - cos_lo) / (1.0 - cos_lo)) * nt as f32).clamp(0.0, nt as f32 - 1.0)
                as usize;
            let phi = l.y.atan2(l.x).rem_euclid(2.0 * PI);
            let ip = ((phi / (2.0 * PI)) * np as f32).min(np as f32 - 1.0) as usize;
            counts[it * np + ip] += 1.0;
        }
        let n = dirs.len() as f64;
        let mut chi2 = 0.0;
        for it in 0..nt {
            let a = cos_lo as f64 + (1.0 - cos_lo as f64) * it as f64 / nt as f64;
            let b = cos_lo as f64 + (1.0 - cos_lo as f64) * (it + 1) as f64 / nt as f64;
            let steps = 64;
            let mut mass = 0.0;
            for s in 0..steps {
                let c = a + (b - a) * (s as f64 + 0.5) / steps as f64;
                mass += pdf(c as f32) * (b - a) / steps as f64;
            }
            let e = mass * 2.0 * std::f64::consts::PI / np as f64 * n;
            for ip in 0..np {
                chi2 += (counts[it * np + ip] - e).powi(2) / e;
            }
        }
        chi2
    }

    #[test]
    fn a_days_skies_and_light_sets_share_one_map_and_one_table() {
        // Issue 38: the sun's sky at each time of day was a deep copy of the map, and
        // every light set built its own sampling table (12 bytes a texel each).
        let (w, h) = (64u32, 32u32);
        let texels: Vec<Rgb> = (0..w * h)
            .map(|i| Rgb::splat(0.1 + (i % 7) as f32))
            .collect();
        let map = illume_scene::EnvMap {
            name: "test".into(),
            width: w,
            height: h,
            texels: texels.into(),
            scale: 1.0,
            rotation_deg: 0.0,
            sampling: Default::default(),
        };
        let mut scene = illume_scene::load_scene(std::path::Path::new("builtin:sun-room")).unwrap();
        scene.replace_sky(illume_scene::Sky::Equirect(std::sync::Arc::new(map)));
        let mut skies = Vec::new();
        let mut sets = Vec::new();
        for hours in [9.0, 12.0, 16.0] {
            scene.set_time(hours * 3600.0);
            let Some(illume_scene::Sky::Equirect(sky)) = &scene.sky else {
                panic!("an environment map at {hours} h");
            };
            skies.push(sky.clone());
            sets.push(LightSet::new(&scene));
        }
        assert!(skies[0].scale > 0.0 && skies[0].scale != skies[1].scale);
        let table = |i: usize| env_table(&skies[i]).expect("a daytime sky has a table");
        for i in 1..3 {
            assert!(std::sync::Arc::ptr_eq(&skies[0].texels, &skies[i].texels));
            assert!(
                std::ptr::eq(table(0), table(i)),
                "sky {i} built its own table"
            );
        }
        // Each light set samples by that one table, at its own sky's radiance.
        let mut g = Pcg32::new(9, 9);
        for (set, sky) in sets.iter().zip(&skies) {
            let s = set
                .sample_sky(Vec3::Y, &mut g)
                .expect("a sample of the sky");
            let radiance = sky.lookup(sky.uv(s.wi));
            assert!(
                (s.weight * s.pdf - radiance).abs().max_element() < 1e-4 * radiance.max_element()
            );
        }
    }

    #[test]
    fn point_light_emission_passes_chi_square() {
        let mut s = illume_scene::builtin::SceneBuilder::new();
        let node = s.node(
            "l",
            None,
            illume_scene::Trs::from_translation(Vec3::new(1.0, 2.0, 3.0)),
        );
        s.light(
            "p",
            LightKind::Point {
                intensity: Rgb::new(1.0, 2.0, 3.0),
            },
            node,
        );
        let scene = s.finish("test");
        let set = LightSet::new(&scene);
        let mut rng = Pcg32::new(1, 2);
        let mut dirs = Vec::new();
        for _ in 0..200_000 {
            let e = set.sample_emission(&mut rng).unwrap();
            assert!((e.ray.origin - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
            assert!(
                (e.flux - Rgb::new(1.0, 2.0, 3.0) * 4.0 * PI).length() < 1e-3,
                "equal-power photons"
            );
            dirs.push(e.ray.dir);
        }
        let chi2 = chi2_directions(
            &dirs,
            Frame::from_normal(Vec3::Z),
            |_| 1.0 / (4.0 * std::f64::consts::PI),
            -1.0,
        );
        assert!(chi2 < 215.0, "chi2 = {chi2}"); // 159 dof, 99.9th percentile ≈ 215
    }

    #[test]
    fn area_light_emission_passes_chi_square_and_stays_on_triangle() {
        let mut b = illume_scene::builtin::SceneBuilder::new();
        let m = b.material(illume_scene::Material {
            emission: Rgb::new(2.0, 1.0, 0.5),
            double_sided: false,
            ..Default::default()
        });
        let n = Vec3::new(0.2, -1.0, 0.3).normalize();
        let f = Frame::from_normal(n);
        let mesh = b.mesh(illume_scene::builtin::quad(
            Vec3::new(0.0, 2.0, 0.0),
            f.s * 0.3,
            f.t * 0.2,
            m,
        ));
        b.placed("q", mesh, illume_scene::Trs::IDENTITY, false);
        let scene = b.finish("test");
        let set = LightSet::new(&scene);
        let expected_power = Rgb::new(2.0, 1.0, 0.5) * PI * (0.6 * 0.4);
        assert!((set.total_power() - expected_power).length() < 1e-4);
        let mut rng = Pcg32::new(4, 2);
        let mut dirs = Vec::new();
        for _ in 0..200_000 {
            let e = set.sample_emission(&mut rng).unwrap();
            assert!((e.flux - expected_power).length() < 1e-3);
            assert!(
                (e.ray.origin - Vec3::new(0.0, 2.0, 0.0)).dot(n).abs() < 1e-3,
                "origin on the quad's plane"
            );
            dirs.push(e.ray.dir);
        }
        let chi2 = chi2_directions(&dirs, f, |c| c as f64 / std::f64::consts::PI, 0.0);
        assert!(chi2 < 215.0, "chi2 = {chi2}");
    }

    #[test]
    fn directional_emission_covers_the_scene_disk_uniformly() {
        let mut b = illume_scene::builtin::SceneBuilder::new();
        let m = b.material(illume_scene::Material::default());
        let mesh = b.mesh(illume_scene::builtin::unit_box(m, false));
        b.placed("box", mesh, illume_scene::Trs::IDENTITY, false);
        let node = b.node(
            "sun",
            None,
            illume_scene::Trs {
                rotation: illume_core::Quat::from_rotation_x(-1.2),
                ..Default::default()
            },
        );
        b.light(
            "sun",
            LightKind::Directional {
                irradiance: Rgb::splat(3.0),
            },
            node,
        );
        let scene = b.finish("test");
        let set = LightSet::new(&scene);
        let r = scene.bounds().bounding_radius();
        let dir = scene.lights[0].direction();
        let frame = Frame::from_normal(dir);
        // Chi-square of the photon origins' radial distribution over equal-area rings.
        let rings = 20usize;
        let mut counts = vec![0f64; rings];
        let mut rng = Pcg32::new(8, 1);
        let n = 100_000;
        for _ in 0..n {
            let e = set.sample_emission(&mut rng).unwrap();
            assert!((e.ray.dir - dir).length() < 1e-6);
            assert!((e.flux - Rgb::splat(3.0) * PI * r * r).length() < 1e-2);
            let o = e.ray.origin - scene.bounds().center();
            let rho = ((o.dot(frame.s)).powi(2) + (o.dot(frame.t)).powi(2)).sqrt() / r;
            counts[((rho * rho) * rings as f32).min(rings as f32 - 1.0) as usize] += 1.0;
        }
        let e = n as f64 / rings as f64;
        let chi2: f64 = counts.iter().map(|c| (c - e).powi(2) / e).sum();
        assert!(chi2 < 43.8, "chi2 = {chi2}"); // 19 dof, 99.9th percentile ≈ 43.8
    }

    #[test]
    fn incident_sampling_of_area_light_integrates_to_analytic_irradiance() {
        // A small emitting disk-like quad far above a point: E ≈ Le·A·cos·cos/d².
        let mut b = illume_scene::builtin::SceneBuilder::new();
        let m = b.material(illume_scene::Material {
            emission: Rgb::splat(5.0),
            double_sided: false,
            ..Default::default()
        });
        let mesh = b.mesh(illume_scene::builtin::quad(
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::X * 0.05,
            Vec3::Z * 0.05,
            m,
        ));
        b.placed("q", mesh, illume_scene::Trs::IDENTITY, false);
        let scene = b.finish("test");
        let set = LightSet::new(&scene);
        let mut rng = Pcg32::new(1, 9);
        let n = 20_000;
        let mut e = 0.0f64;
        for _ in 0..n {
            let s = set.sample_incident(Vec3::ZERO, &mut rng).unwrap();
            e += (s.weight.x * s.wi.y) as f64;
        }
        let expected = 5.0 * 0.01 / 100.0;
        assert!(
            ((e / n as f64) - expected).abs() / expected < 2e-3,
            "{} vs {expected}",
            e / n as f64
        );
    }
}
