//! What a ray hit, in world space.

use illume_accel::Hit;
use illume_core::{Ray, Rgb, Vec2, Vec3, offset_ray_origin, transform_normal};
use illume_scene::{InstanceId, MaterialId, Scene};

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
    /// Triangle within the instance's mesh.
    pub triangle: u32,
    /// Material of the triangle.
    pub material: MaterialId,
    /// Diffuse albedo ρ at the hit (texture × factor).
    pub albedo: Rgb,
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
        let geometric_normal = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y);
        let front_face = ray.dir.dot(geometric_normal) < 0.0;
        let mut shading_normal = if mesh.normals.is_empty() {
            geometric_normal
        } else {
            let n = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
            let n = transform_normal(m, n);
            if n == Vec3::ZERO { geometric_normal } else { n }
        };
        if shading_normal.dot(geometric_normal) < 0.0 {
            shading_normal = -shading_normal;
        }
        let uv = if mesh.uvs.is_empty() {
            Vec2::ZERO
        } else {
            mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2
        };
        let material = mesh.triangle_materials[t];
        let mat = &scene.materials[material.index()];
        let reflects = front_face || mat.double_sided;
        let albedo = if reflects {
            scene.albedo(material, uv)
        } else {
            Rgb::ZERO
        };
        let emission = if reflects { mat.emission } else { Rgb::ZERO };
        Self {
            position,
            geometric_normal,
            shading_normal,
            uv,
            instance: hit.instance,
            triangle: hit.triangle,
            material,
            albedo,
            emission,
            front_face,
            reflects,
            t: hit.t,
        }
    }

    /// The normal on the side the ray arrived from (shading normal, flipped for back-face
    /// hits of double-sided materials).
    #[inline]
    pub fn facing_normal(&self) -> Vec3 {
        if self.front_face {
            self.shading_normal
        } else {
            -self.shading_normal
        }
    }

    /// The geometric normal on the side the ray arrived from.
    #[inline]
    pub fn facing_geometric_normal(&self) -> Vec3 {
        if self.front_face {
            self.geometric_normal
        } else {
            -self.geometric_normal
        }
    }

    /// A ray origin just off the surface on the side `dir` leaves towards.
    #[inline]
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        offset_ray_origin(self.position, self.geometric_normal, dir)
    }
}
