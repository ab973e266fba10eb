//! What a ray hit, in world space.

use crate::hit_tables::HitTables;
use crate::metal_rough::MetalRough;
use illume_accel::{Hit, HitGeometry};
use illume_core::{Frame, INV_PI, Ray, Rgb, Vec2, Vec3, offset_ray_origin, transform_normal};
use illume_scene::{InstanceId, MaterialId, MeshId, Scene};

/// `normal` turned to the side a ray arrived from (`front_face`: the front).
#[inline]
fn on_side(normal: Vec3, front_face: bool) -> Vec3 {
    if front_face { normal } else { -normal }
}

/// A ray's hit point with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// World position.
    pub position: Vec3,
    /// Unit geometric normal of the triangle's front face (counter-clockwise winding).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated), flipped to the geometric normal's side.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Instance hit.
    pub instance: InstanceId,
    /// The mesh the instance places (so mesh elements and texels can be found without
    /// looking the instance up again).
    pub mesh: MeshId,
    /// Triangle within the instance's mesh.
    pub triangle: u32,
    /// Barycentric coordinates (b1, b2) of the hit on `triangle`, weights of its second
    /// and third corners (the first corner's is 1 − b1 − b2).
    pub barycentrics: Vec2,
    /// Material of the triangle.
    pub material: MaterialId,
    /// Base colour at the hit (texture × factor): the diffuse albedo ρ of a Lambertian
    /// surface.
    pub albedo: Rgb,
    /// Metalness at the hit (0 = dielectric, 1 = metal).
    pub metallic: f32,
    /// Perceptual roughness at the hit (GGX α = roughness²).
    pub roughness: f32,
    /// Emitted radiance towards the ray origin (zero from a one-sided emitter's back).
    pub emission: Rgb,
    /// True when the ray arrived on the front face.
    pub front_face: bool,
    /// True when the surface reflects light arriving on this side (front face, or a
    /// double-sided material).
    pub reflects: bool,
    /// Distance along the ray.
    pub t: f32,
}

impl SurfaceHit {
    /// Builds the hit description for `hit` of `ray`.
    pub fn new(scene: &Scene, ray: &Ray, hit: &Hit) -> Self {
        let inst = &scene.instances[hit.instance.index()];
        let mesh = &scene.meshes[inst.mesh.index()];
        let t = hit.triangle as usize;
        let [i0, i1, i2] = mesh.indices[t].map(|i| i as usize);
        let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
        let b0 = 1.0 - b1 - b2;
        let m = &inst.world_from_object;
        let p0 = m.transform_point3(mesh.positions[i0]);
        let p1 = m.transform_point3(mesh.positions[i1]);
        let p2 = m.transform_point3(mesh.positions[i2]);
        let position = p0 * b0 + p1 * b1 + p2 * b2;
        // Counter-clockwise is the front in object space; a mirroring transform
        // (determinant < 0) reverses the winding, so the world cross product is flipped
        // back (glTF: the determinant's sign defines the winding order).
        let mirror = if m.matrix3.determinant() < 0.0 {
            -1.0
        } else {
            1.0
        };
        let geometric_normal = ((p1 - p0).cross(p2 - p0) * mirror).normalize_or(Vec3::Y);
        let front_face = ray.dir.dot(geometric_normal) < 0.0;
        let mut shading_normal = if mesh.normals.is_empty() {
            geometric_normal
        } else {
            let n = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
            let n = transform_normal(m, n);
            if n == Vec3::ZERO { geometric_normal } else { n }
        };
        let uv = if mesh.uvs.is_empty() {
            Vec2::ZERO
        } else {
            mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2
        };
        let material = mesh.triangle_materials[t];
        let mat = &scene.materials[material.index()];
        // A tangent-space normal map turns the interpolated normal (before it is flipped
        // to the geometric side, so that the tangent frame keeps its handedness).
        if let Some(tex) = mat.normal_texture
            && !mesh.tangents.is_empty()
            && !mesh.normals.is_empty()
        {
            let tg = mesh.tangents[i0] * b0 + mesh.tangents[i1] * b1 + mesh.tangents[i2] * b2;
            let sign = if mesh.tangents[i0].w < 0.0 { -1.0 } else { 1.0 };
            shading_normal = normal_mapped(
                scene,
                tex,
                mat,
                shading_normal.normalize_or(geometric_normal),
                m.transform_vector3(tg.truncate()),
                sign,
                uv,
            );
        }
        if shading_normal.dot(geometric_normal) < 0.0 {
            shading_normal = -shading_normal;
        }
        let reflects = front_face || mat.double_sided;
        let albedo = if reflects {
            scene.albedo(material, uv)
        } else {
            Rgb::ZERO
        };
        let emission = if reflects {
            scene.emission(material, uv)
        } else {
            Rgb::ZERO
        };
        let (metallic, roughness) = scene.metal_rough(material, uv);
        Self {
            position,
            geometric_normal,
            shading_normal,
            uv,
            instance: hit.instance,
            mesh: inst.mesh,
            triangle: hit.triangle,
            barycentrics: hit.barycentrics,
            material,
            albedo,
            metallic,
            roughness,
            emission,
            front_face,
            reflects,
            t: hit.t,
        }
    }

    /// True when the surface reflects as a Lambertian one (metallic 0, roughness 1): its
    /// BRDF is exactly `albedo/π`.
    #[inline]
    pub fn is_lambertian(&self) -> bool {
        self.metallic <= 0.0 && self.roughness >= 1.0
    }

    /// True when the surface reflects nothing: it does not reflect on this side, or it
    /// is a black Lambertian one (a black dielectric still has its specular layer).
    #[inline]
    pub fn is_black(&self) -> bool {
        !self.reflects || (self.albedo == Rgb::ZERO && self.is_lambertian())
    }

    /// The BRDF at the hit, for directions in the frame of [`SurfaceHit::facing_normal`].
    #[inline]
    pub fn brdf(&self) -> MetalRough {
        MetalRough {
            base_color: self.albedo,
            metallic: self.metallic,
            roughness: self.roughness,
        }
    }

    /// `f(wo, wi)` \[1/sr\] for world directions `wo` (towards the viewer) and `wi`
    /// (towards the light), both leaving the surface; exactly `albedo/π` for a
    /// Lambertian surface whatever the directions (the caller checks the hemisphere).
    #[inline]
    pub fn eval_brdf(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if self.is_lambertian() {
            return self.albedo * INV_PI;
        }
        let frame = Frame::from_normal(self.facing_normal());
        self.brdf().eval(frame.to_local(wo), frame.to_local(wi))
    }

    /// The directional albedo towards world direction `wo` (leaving the surface): the
    /// radiance reflected towards `wo` per unit uniform incident radiance, so that
    /// `A/π · E` is what an irradiance E arriving uniformly leaves with
    /// ([`MetalRough::directional_albedo`]). Exactly `albedo` for a Lambertian surface.
    #[inline]
    pub fn uniform_albedo(&self, wo: Vec3) -> Rgb {
        if self.is_lambertian() {
            return self.albedo;
        }
        self.brdf()
            .directional_albedo(self.facing_normal().dot(wo).max(0.0))
    }

    /// The normal on the side the ray arrived from (shading normal, flipped for back-face
    /// hits of double-sided materials).
    #[inline]
    pub fn facing_normal(&self) -> Vec3 {
        on_side(self.shading_normal, self.front_face)
    }

    /// The geometric normal on the side the ray arrived from.
    #[inline]
    pub fn facing_geometric_normal(&self) -> Vec3 {
        on_side(self.geometric_normal, self.front_face)
    }

    /// A ray origin just off the surface on the side `dir` leaves towards.
    #[inline]
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        offset_ray_origin(self.position, self.geometric_normal, dir)
    }

    /// The hit moved out to the smooth surface its triangle's vertex normals describe
    /// ([`smooth_point`]); `scene` must be the one the hit was made in.
    pub fn smooth_point(&self, scene: &Scene) -> Vec3 {
        smooth_point(
            scene,
            self.instance,
            self.triangle,
            self.barycentrics,
            self.position,
            self.facing_geometric_normal(),
        )
    }
}

/// What photon tracing needs of a hit, and no more: a [`SurfaceHit`] without the
/// emission, texture coordinates, material and distance, plus the object-space position
/// (photon techniques bin impacts per object). Built by [`World::photon_hit`] from
/// tables derived once per scene update ([`HitTables`]), it costs a fraction of a
/// [`SurfaceHit`] — photon tracing builds one per impact.
///
/// [`World::photon_hit`]: crate::World::photon_hit
#[derive(Clone, Copy, Debug)]
pub struct PhotonHit {
    /// World position.
    pub position: Vec3,
    /// Position in the instance's object space.
    pub position_object: Vec3,
    /// Unit geometric normal of the triangle's front face (counter-clockwise winding).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated), flipped to the geometric normal's side.
    pub shading_normal: Vec3,
    /// Diffuse albedo ρ at the hit (texture × factor); zero where `reflects` is false.
    pub albedo: Rgb,
    /// Instance hit.
    pub instance: InstanceId,
    /// Triangle within the instance's mesh.
    pub triangle: u32,
    /// Barycentrics `(b1, b2)` of the hit in its triangle (see
    /// [`Hit::barycentrics`](illume_accel::Hit)).
    pub barycentrics: Vec2,
    /// True when the ray arrived on the front face.
    pub front_face: bool,
    /// True when the surface reflects light arriving on this side (front face, or a
    /// double-sided material).
    pub reflects: bool,
    /// glTF metallic factor at the hit (texture × factor), in [0, 1].
    pub metallic: f32,
    /// glTF perceptual roughness at the hit (texture × factor), in [0, 1]. With
    /// `metallic = 0` and `roughness = 1` the surface is Lambertian
    /// ([`MetalRough::is_lambertian`](crate::metal_rough::MetalRough::is_lambertian)).
    pub roughness: f32,
}

/// What a photon reads of a surface's material at a hit: see [`photon_material`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonMaterial {
    /// Diffuse albedo ρ (texture × factor); zero where `reflects` is false.
    pub albedo: Rgb,
    /// The surface reflects light arriving on this side.
    pub reflects: bool,
    /// Metallic (texture × factor).
    pub metallic: f32,
    /// Perceptual roughness (texture × factor).
    pub roughness: f32,
}

/// A photon's albedo and sidedness at barycentrics `b` of triangle `t` of `mesh` with
/// material `mat`, arriving on the front face or not (see [`PhotonHit::new`]): the one
/// formula [`PhotonHit::new`] and [`World::photon_material`](crate::World::photon_material)
/// share, so a path re-traced with another material state gets bit-identical albedos;
/// with the metallic and roughness the photon scatters by.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn photon_material(
    scene: &Scene,
    tables: &HitTables,
    mesh: &illume_scene::Mesh,
    t: usize,
    b: Vec2,
    front_face: bool,
    mat: &illume_scene::Material,
    filtered_textures: bool,
) -> PhotonMaterial {
    let reflects = front_face || mat.double_sided;
    let uv = || {
        let (b1, b2) = (b.x, b.y);
        let b0 = 1.0 - b1 - b2;
        if mesh.uvs.is_empty() {
            Vec2::ZERO
        } else {
            let [i0, i1, i2] = mesh.indices[t].map(|i| i as usize);
            mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2
        }
    };
    let albedo = match (reflects, mat.base_color_texture) {
        (false, _) => Rgb::ZERO,
        (true, None) => mat.base_color,
        (true, Some(texture)) => {
            let uv = mat.base_color_uv(uv());
            let texel = if filtered_textures {
                tables.sample_filtered(scene, texture, uv)
            } else {
                tables.sample(scene, texture, uv)
            };
            mat.base_color * texel
        }
    };
    // Metal-roughness textures as `Scene::metal_rough` reads them (blue metallic, green
    // roughness); photons read them at full resolution (few materials have them).
    let (metallic, roughness) = match (reflects, mat.metallic_roughness_texture) {
        (true, Some(texture)) => {
            let texel = tables.sample(scene, texture, mat.metallic_roughness_uv(uv()));
            (mat.metallic * texel.z, mat.roughness * texel.y)
        }
        _ => (mat.metallic, mat.roughness),
    };
    PhotonMaterial {
        albedo,
        reflects,
        metallic,
        roughness,
    }
}

impl PhotonHit {
    /// Builds the photon's view of `hit` of `ray`, whose triangle's object-space
    /// `geometry` the tracer gave ([`Tracer::intersect_geometry`]) or
    /// [`mesh_hit_geometry`] computes. It agrees with [`SurfaceHit::new`] to rounding
    /// (positions and normals are taken in object space, then transformed once) and
    /// exactly in albedo, sidedness, instance and triangle.
    ///
    /// [`Tracer::intersect_geometry`]: illume_accel::Tracer::intersect_geometry
    ///
    /// With `filtered_textures`, base-colour textures are read through their photon
    /// copies ([`HitTables::sample_filtered`]) instead of at full resolution.
    #[inline]
    pub fn new(
        scene: &Scene,
        tables: &HitTables,
        ray: &Ray,
        hit: &Hit,
        geometry: &HitGeometry,
        filtered_textures: bool,
    ) -> Self {
        let inst = &scene.instances[hit.instance.index()];
        let frame = tables.frame(hit.instance, &inst.world_from_object);
        let mesh = &scene.meshes[inst.mesh.index()];
        let t = hit.triangle as usize;
        let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
        let b0 = 1.0 - b1 - b2;
        let position_object = geometry.position_object;
        let normal_object = geometry.normal_object;
        let position = frame.world_from_object.transform_point3(position_object);
        // (M·a)×(M·b) = cof(M)·(a×b): the world cross product without moving the corners.
        // (Mirroring transforms: the sign restores the object-space front, as above.)
        let geometric_normal = (frame.normal(normal_object) * frame.det_sign).normalize_or(Vec3::Y);
        let front_face = ray.dir.dot(geometric_normal) < 0.0;
        // Vertex indices only when attributes need them: with the tracer's geometry, a
        // mesh without normals and texture coordinates is never read here.
        let corners = || mesh.indices[t].map(|i| i as usize);
        let mut shading_normal = if mesh.normals.is_empty() {
            geometric_normal
        } else {
            let [i0, i1, i2] = corners();
            let n = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
            // Shading normals keep their outward sense under mirroring transforms.
            let n = (frame.normal(n) * frame.det_sign).normalize_or_zero();
            if n == Vec3::ZERO { geometric_normal } else { n }
        };
        if shading_normal.dot(geometric_normal) < 0.0 {
            shading_normal = -shading_normal;
        }
        let material = mesh.triangle_materials[t];
        let mat = &scene.materials[material.index()];
        let m = photon_material(
            scene,
            tables,
            mesh,
            t,
            hit.barycentrics,
            front_face,
            mat,
            filtered_textures,
        );
        Self {
            position,
            position_object,
            geometric_normal,
            shading_normal,
            albedo: m.albedo,
            instance: hit.instance,
            triangle: hit.triangle,
            barycentrics: hit.barycentrics,
            front_face,
            reflects: m.reflects,
            metallic: m.metallic,
            roughness: m.roughness,
        }
    }

    /// The normal on the side the ray arrived from (see [`SurfaceHit::facing_normal`]).
    #[inline]
    pub fn facing_normal(&self) -> Vec3 {
        on_side(self.shading_normal, self.front_face)
    }

    /// The geometric normal on the side the ray arrived from.
    #[inline]
    pub fn facing_geometric_normal(&self) -> Vec3 {
        on_side(self.geometric_normal, self.front_face)
    }

    /// A ray origin just off the surface on the side `dir` leaves towards.
    #[inline]
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        offset_ray_origin(self.position, self.geometric_normal, dir)
    }

    /// The hit moved out to the smooth surface its triangle's vertex normals describe
    /// ([`smooth_point`]); `scene` must be the one the hit was made in.
    pub fn smooth_point(&self, scene: &Scene) -> Vec3 {
        smooth_point(
            scene,
            self.instance,
            self.triangle,
            self.barycentrics,
            self.position,
            self.facing_geometric_normal(),
        )
    }
}

/// `position` (on `triangle` of `instance` at `barycentrics`, facing side `ng`) moved
/// out to the smooth surface the triangle's vertex normals describe (Hanika 2021,
/// "Hacking the shadow terminator", Ray Tracing Gems II ch. 4): the point projected
/// onto each corner's tangent plane where it lies below that plane, the projections
/// weighted by the barycentrics. On a faceted curved mesh this lifts the point above the
/// neighbouring facets, so a shadow ray towards a light the shading normal faces but the
/// facet does not can leave the object; on a flat region (corner normals equal to the
/// facet's), or a mesh without normals, it is `position` itself.
pub fn smooth_point(
    scene: &Scene,
    instance: InstanceId,
    triangle: u32,
    barycentrics: Vec2,
    position: Vec3,
    ng: Vec3,
) -> Vec3 {
    let inst = &scene.instances[instance.index()];
    let mesh = &scene.meshes[inst.mesh.index()];
    if mesh.normals.is_empty() {
        return position;
    }
    let m = &inst.world_from_object;
    let corners = mesh.indices[triangle as usize].map(|i| i as usize);
    let (b1, b2) = (barycentrics.x, barycentrics.y);
    let weights = [1.0 - b1 - b2, b1, b2];
    let mut lift = Vec3::ZERO;
    for (i, w) in corners.into_iter().zip(weights) {
        let n = transform_normal(m, mesh.normals[i]);
        // The corner's normal on the side the hit faces (a corner normal turned against
        // its facet would pull the point inwards).
        let n = if n.dot(ng) < 0.0 { -n } else { n };
        let below = (position - m.transform_point3(mesh.positions[i])).dot(n);
        lift -= n * (w * below.min(0.0));
    }
    position + lift
}

/// [`HitGeometry`] of `hit` computed from the scene's mesh (when no tracer query gave
/// it): the corners interpolated with the hit's barycentrics, and their cross product.
pub fn mesh_hit_geometry(scene: &Scene, hit: &Hit) -> HitGeometry {
    let inst = &scene.instances[hit.instance.index()];
    let mesh = &scene.meshes[inst.mesh.index()];
    let [p0, p1, p2] = mesh.triangle(hit.triangle as usize);
    let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
    HitGeometry {
        position_object: p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2,
        normal_object: (p1 - p0).cross(p2 - p0),
    }
}

/// The normal-map lookup shared by hits and the rasterized G-buffer: unit interpolated
/// shading normal `n` (not yet flipped to the geometric side, so that the tangent frame
/// keeps its handedness), world tangent `tangent` (interpolated, any length), bitangent
/// sign `sign`, texture coordinates `uv`. Returns `n` itself where the frame or the
/// mapped normal degenerates.
#[inline]
pub(crate) fn normal_mapped(
    scene: &illume_scene::Scene,
    texture: illume_scene::TextureId,
    mat: &illume_scene::Material,
    n: Vec3,
    tangent: Vec3,
    sign: f32,
    uv: Vec2,
) -> Vec3 {
    normal_mapped_with(mat, n, tangent, sign, || {
        scene.textures[texture.index()].sample(mat.normal_uv(uv))
    })
}

/// [`normal_mapped`] with the normal map's texel (in [0, 1]³) read by `texel`, which is
/// called only where the tangent frame does not degenerate.
#[inline]
pub(crate) fn normal_mapped_with(
    mat: &illume_scene::Material,
    n: Vec3,
    tangent: Vec3,
    sign: f32,
    texel: impl FnOnce() -> Rgb,
) -> Vec3 {
    let t = (tangent - n * n.dot(tangent)).normalize_or_zero();
    if t == Vec3::ZERO {
        return n;
    }
    let b = n.cross(t) * sign;
    let c = texel() * 2.0 - Vec3::ONE;
    let local = Vec3::new(c.x * mat.normal_scale, c.y * mat.normal_scale, c.z);
    let mapped = (t * local.x + b * local.y + n * local.z).normalize_or_zero();
    if mapped == Vec3::ZERO { n } else { mapped }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use illume_core::sampling::{Pcg32, SampleStream, uniform_sphere};
    use illume_core::{Affine3A, Quat, Vec3};

    #[test]
    fn photon_hits_agree_with_surface_hits_under_rotation_scale_and_mirroring() {
        let mut scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let inst = &mut scene.instances[2];
        inst.world_from_object = Affine3A::from_scale_rotation_translation(
            Vec3::new(-1.3, 0.7, 1.1),
            Quat::from_rotation_y(0.6) * Quat::from_rotation_x(0.3),
            Vec3::new(0.1, 0.2, -0.1),
        ) * inst.world_from_object;
        let world = World::new(scene);
        let b = world.scene.bounds();
        let mut rng = Pcg32::new(3, 4);
        let mut checked = 0;
        for _ in 0..20_000 {
            let u = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d());
            let ray = Ray::new(b.min + u * b.extent(), uniform_sphere(rng.next_2d()));
            let Some(h) = world.tracer.intersect(&ray, illume_scene::MASK_DEFAULT) else {
                continue;
            };
            let (s, p) = (world.surface(&ray, &h), world.photon_hit(&ray, &h));
            // The tracer's copy of the triangle gives the same record, to rounding.
            let traced = world
                .tracer
                .scoped(|t| world.trace_photon_hit(t, &ray, illume_scene::MASK_DEFAULT, false))
                .expect("same ray, same hit");
            assert_eq!((traced.instance, traced.triangle), (p.instance, p.triangle));
            assert_eq!((traced.front_face, traced.albedo), (p.front_face, p.albedo));
            assert!(
                (traced.position - p.position).abs().max_element()
                    < 1e-5 * (1.0 + p.position.abs().max_element())
            );
            assert!((traced.geometric_normal - p.geometric_normal).length() < 1e-4);
            assert!((traced.shading_normal - p.shading_normal).length() < 1e-4);
            let scale = 1e-5 * (1.0 + s.position.abs().max_element());
            assert!((s.position - p.position).abs().max_element() < scale);
            let m = &world.scene.instances[h.instance.index()].world_from_object;
            let back = m.transform_point3(p.position_object);
            assert!((back - p.position).abs().max_element() < scale);
            for (a, b) in [
                (s.geometric_normal, p.geometric_normal),
                (s.shading_normal, p.shading_normal),
            ] {
                assert!((a - b).length() < 1e-4, "{a} vs {b}");
            }
            assert_eq!(s.front_face, p.front_face);
            assert_eq!(s.reflects, p.reflects);
            assert_eq!(s.albedo, p.albedo);
            assert_eq!((s.instance, s.triangle), (p.instance, p.triangle));
            checked += 1;
        }
        assert!(checked > 10_000);
    }
}
