//! The mesh level: one BVH per mesh, built once in object space, with the mesh's
//! triangles copied in leaf order (corner plus two edges) so a leaf is one contiguous run.

use crate::build::{BuildParams, build_binary};
use crate::wide::{Bvh4, MAX_LEAF, PreparedRay, StackEntry, traverse};
use illume_core::{Aabb, Vec2, Vec3, Vec3A};
use illume_scene::Mesh;

/// Mesh-level build parameters: a box test costs about as much as a triangle test, and
/// leaves hold up to 8 triangles (chosen by measurement, see lib.rs).
const PARAMS: BuildParams = BuildParams {
    traversal_cost: 1.0,
    max_leaf: 8,
};
const _: () = assert!(PARAMS.max_leaf <= MAX_LEAF);

/// A triangle ready for Möller–Trumbore: corner `v0`, edges `e1 = v1 − v0`,
/// `e2 = v2 − v0`, and its index in the mesh.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PreparedTriangle {
    /// First corner.
    pub v0: Vec3,
    /// `v1 − v0`.
    pub e1: Vec3,
    /// `v2 − v0`.
    pub e2: Vec3,
    /// Index of the triangle in its mesh.
    pub index: u32,
}

impl PreparedTriangle {
    /// Hit distance and barycentrics `(b1, b2)` for `t` in `(ray.t_min, t_max)`; the same
    /// test (and the same acceptance on edges) as [`crate::triangle::intersect_triangle`].
    #[inline(always)]
    pub fn intersect(&self, ray: &PreparedRay, t_max: f32) -> Option<(f32, Vec2)> {
        let e1 = Vec3A::from(self.e1);
        let e2 = Vec3A::from(self.e2);
        let pvec = ray.dir.cross(e2);
        let det = e1.dot(pvec);
        if det.abs() < f32::MIN_POSITIVE {
            return None;
        }
        let inv_det = 1.0 / det;
        let tvec = ray.origin - Vec3A::from(self.v0);
        let b1 = tvec.dot(pvec) * inv_det;
        if !(0.0..=1.0).contains(&b1) {
            return None;
        }
        let qvec = tvec.cross(e1);
        let b2 = ray.dir.dot(qvec) * inv_det;
        if b2 < 0.0 || b1 + b2 > 1.0 {
            return None;
        }
        let t = e2.dot(qvec) * inv_det;
        (t > ray.t_min && t < t_max).then_some((t, Vec2::new(b1, b2)))
    }

    /// The three corners (rebuilt from the edges, so within rounding of the mesh's).
    pub fn corners(&self) -> [Vec3; 3] {
        [self.v0, self.v0 + self.e1, self.v0 + self.e2]
    }
}

/// One mesh's BVH, in the mesh's object space.
#[derive(Clone, Debug)]
pub(crate) struct Blas {
    /// The tree; leaves index `triangles`.
    pub bvh: Bvh4,
    /// Triangles in leaf order.
    pub triangles: Vec<PreparedTriangle>,
}

impl Blas {
    /// Builds the BVH of `mesh` (binned SAH, then collapsed to four-wide nodes).
    pub fn build(mesh: &Mesh) -> Blas {
        let boxes: Vec<Aabb> = (0..mesh.triangle_count())
            .map(|t| Aabb::from_points(mesh.triangle(t)))
            .collect();
        let bin = build_binary(&boxes, PARAMS);
        let triangles = bin
            .order
            .iter()
            .map(|&t| {
                let [v0, v1, v2] = mesh.triangle(t as usize);
                PreparedTriangle {
                    v0,
                    e1: v1 - v0,
                    e2: v2 - v0,
                    index: t,
                }
            })
            .collect();
        let bvh = Bvh4::from_binary(&bin, &|_, _| u32::MAX);
        Blas { bvh, triangles }
    }

    /// Object-space bounds.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds
    }

    /// Bytes used by nodes and triangles.
    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes() + self.triangles.len() * std::mem::size_of::<PreparedTriangle>()
    }

    /// Closest hit `(t, triangle index, barycentrics)` with `t < t_max`.
    #[inline]
    pub fn intersect(
        &self,
        ray: &PreparedRay,
        t_max: f32,
        stack: &mut [StackEntry],
    ) -> Option<(f32, u32, Vec2)> {
        let mut best = None;
        traverse(&self.bvh, ray, t_max, u32::MAX, stack, |range, t_max, _| {
            for tri in &self.triangles[range] {
                if let Some((t, b)) = tri.intersect(ray, *t_max) {
                    *t_max = t;
                    best = Some((t, tri.index, b));
                }
            }
            false
        });
        best
    }

    /// True when any triangle is hit with `t < t_max`.
    #[inline]
    pub fn occluded(&self, ray: &PreparedRay, t_max: f32, stack: &mut [StackEntry]) -> bool {
        let mut hit = false;
        traverse(&self.bvh, ray, t_max, u32::MAX, stack, |range, t_max, _| {
            hit = self.triangles[range]
                .iter()
                .any(|tri| tri.intersect(ray, *t_max).is_some());
            hit
        });
        hit
    }
}
