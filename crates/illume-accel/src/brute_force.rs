//! Every triangle of every instance, tested in turn: slow, obviously right, the oracle
//! for the BVH tests.

use crate::{Hit, triangle::intersect_triangle};
use illume_core::{Ray, Vec3};
use illume_scene::{InstanceId, MeshCutout, Scene};

/// World-space triangles of a scene.
pub struct BruteForce {
    /// Corners, instance, triangle, mask and the index of the mesh in `cutouts`.
    tris: Vec<([Vec3; 3], InstanceId, u32, u32, usize)>,
    /// Alpha-mask holes per scene mesh.
    cutouts: Vec<Option<MeshCutout>>,
}

impl BruteForce {
    /// Transforms every instance's triangles to world space.
    pub fn new(scene: &Scene) -> Self {
        let mut tris = Vec::new();
        let cutouts = MeshCutout::all(scene);
        for (i, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh.index()];
            for t in 0..mesh.triangle_count() {
                let w = mesh
                    .triangle(t)
                    .map(|p| inst.world_from_object.transform_point3(p));
                tris.push((
                    w,
                    InstanceId(i as u32),
                    t as u32,
                    inst.mask,
                    inst.mesh.index(),
                ));
            }
        }
        Self { tris, cutouts }
    }

    /// True when the surface of triangle `tri` of mesh `mesh` is there at `b`.
    fn keeps(&self, mesh: usize, tri: u32, b: illume_core::Vec2) -> bool {
        match &self.cutouts[mesh] {
            Some(c) => !c.is_tested(tri) || c.keeps(tri, b),
            None => true,
        }
    }

    /// Closest hit among instances visible to `mask`.
    pub fn intersect(&self, ray: &Ray, mask: u32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (w, inst, tri, m, mesh) in &self.tris {
            if m & mask == 0 {
                continue;
            }
            if let Some((t, b)) = intersect_triangle(ray, t_max, w[0], w[1], w[2])
                && self.keeps(*mesh, *tri, b)
            {
                t_max = t;
                best = Some(Hit {
                    t,
                    instance: *inst,
                    triangle: *tri,
                    barycentrics: b,
                });
            }
        }
        best
    }

    /// True when any triangle visible to `mask` is hit within `(ray.t_min, ray.t_max)`.
    pub fn occluded(&self, ray: &Ray, mask: u32) -> bool {
        self.tris.iter().any(|(w, _, tri, m, mesh)| {
            m & mask != 0
                && intersect_triangle(ray, ray.t_max, w[0], w[1], w[2])
                    .is_some_and(|(_, b)| self.keeps(*mesh, *tri, b))
        })
    }
}
