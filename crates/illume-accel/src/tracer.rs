//! The two-level tracer: mesh BVHs (shared between clones) under an instance level,
//! and its queries.

use crate::blas::Blas;
use crate::build::{BuildParams, build_binary};
use crate::kernel::{self, BoxKernel, Kernel, KernelUnavailable, TraversalKernel};
use crate::wide::{Item, PreparedRay, StackEntry, WideBvh, new_stack, traverse, with_stack};
use crate::{Hit, HitGeometry};
use illume_core::{Aabb, Affine3A, Mat3A, Ray, Vec3, Vec3A};
use illume_scene::{InstanceId, MeshCutout, MeshId, Scene};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// A [`Tracer`] with a traversal stack held for a run of queries on one thread (see
/// [`Tracer::scoped`]).
pub struct ScopedTracer<'a> {
    tracer: &'a Tracer,
    stack: &'a mut [StackEntry],
}

impl ScopedTracer<'_> {
    /// [`Tracer::intersect`].
    #[inline]
    pub fn intersect(&mut self, ray: &Ray, mask: u32) -> Option<Hit> {
        self.tracer.intersect_with(ray, mask, self.stack)
    }

    /// [`Tracer::intersect_geometry`].
    #[inline]
    pub fn intersect_geometry(&mut self, ray: &Ray, mask: u32) -> Option<(Hit, HitGeometry)> {
        self.tracer.geometry_of(ray, mask, self.stack)
    }

    /// [`Tracer::occluded`].
    #[inline]
    pub fn occluded(&mut self, ray: &Ray, mask: u32) -> bool {
        self.tracer.occluded_with(ray, mask, self.stack)
    }
}

/// Size and cost of a [`Tracer`]'s structures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TracerStats {
    /// Mesh BVHs held (one per mesh).
    pub mesh_bvhs: usize,
    /// Eight-wide nodes over all mesh BVHs.
    pub mesh_nodes: usize,
    /// Eight-wide nodes of the instance level.
    pub instance_nodes: usize,
    /// Triangles stored over all mesh BVHs (each mesh once, however often instanced).
    pub triangles: usize,
    /// Triangle slots used in the mesh BVHs' leaves: `triangles`, or more where
    /// pre-splitting ([`BvhSettings::split_budget`]) put a triangle in several leaves.
    pub stored_triangles: usize,
    /// Instances in the instance level (empty meshes and singular transforms are left out).
    pub instances: usize,
    /// Bytes of nodes, triangles and instance records.
    pub memory_bytes: usize,
    /// Milliseconds spent building mesh BVHs, in total.
    pub mesh_build_ms: f64,
    /// Milliseconds of the last instance-level build.
    pub instance_build_ms: f64,
    /// How many mesh BVHs were ever built by this tracer (each mesh once unless meshes
    /// were added; [`Tracer::update`] never rebuilds one).
    pub mesh_builds: u64,
}

/// One instance as the instance level sees it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct InstanceRecord {
    /// Maps world points to the mesh's object space.
    pub(crate) object_from_world: Affine3A,
    /// True when `object_from_world` only translates (rays keep their direction).
    pub(crate) translation_only: bool,
    /// Maps object points to world space (kept for [`Tracer::validate`]).
    pub(crate) world_from_object: Affine3A,
    /// World box of the mesh BVH's box, padded for rounding.
    pub(crate) world_bounds: Aabb,
    /// Visibility bits.
    pub(crate) mask: u32,
    /// Mesh (and mesh BVH) index.
    pub(crate) mesh: u32,
    /// Which scene instance.
    pub(crate) id: InstanceId,
}

/// Instance-level build parameters: a mesh BVH costs far more to enter than a box test,
/// so leaves hold one instance.
const INSTANCE_PARAMS: BuildParams = BuildParams {
    traversal_cost: 0.2,
    max_leaf: 1,
    block: 1,
};

/// How mesh BVHs are built. The defaults are the fastest measured (see the top of this
/// file); the knobs exist for measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhSettings {
    /// Largest number of triangles in a leaf (1..=64). Higher: shallower trees and less
    /// memory, at the cost of more triangle tests per leaf.
    pub max_leaf_triangles: usize,
    /// Cost of visiting a node relative to one triangle-packet test, in the surface area
    /// heuristic. Higher: fewer, fuller leaves.
    pub node_cost: f32,
    /// Count a leaf's cost in groups of four triangles (a packet's 4-lane halves) rather
    /// than in triangles. True favours leaves of 4 and 8 triangles.
    pub packet_aware_sah: bool,
    /// Extra triangle references the build may make by splitting badly fitting triangle
    /// boxes, as a fraction of the triangle count (pre-splitting, Karras & Aila 2013 §4;
    /// see `split.rs`). Higher: tighter leaves for long thin diagonal triangles (fewer
    /// wasted box hits), at the cost of build time and memory roughly in proportion.
    /// With a budget, each mesh BVH is built both with and without splitting and the
    /// tree the surface area heuristic prefers is kept, so splitting never makes a tree
    /// worse by that measure; the build then costs about twice the CPU time (less in
    /// wall time on several cores: each build is parallel). 0 turns splitting off. Default 0.6 (BENCHMARKS.md,
    /// "Issue 16, third pass": the fastest Sponza of 0–1.2).
    pub split_budget: f32,
}

impl Default for BvhSettings {
    fn default() -> Self {
        Self {
            max_leaf_triangles: 8,
            node_cost: 2.0,
            packet_aware_sah: true,
            split_budget: 0.6,
        }
    }
}

/// Rays per rayon task in the batch queries.
const BATCH_CHUNK: usize = 256;

/// Answers ray queries against a scene.
///
/// Cloning is cheap: mesh BVHs are shared (`Arc`) between clones, so a clone updated for
/// another state of the same scene (another time, an object moved or added) costs an
/// instance-level rebuild only; see [`Tracer::shares_mesh_bvh`].
#[derive(Clone)]
pub struct Tracer {
    /// How mesh BVHs are built.
    pub(crate) settings: BvhSettings,
    /// One BVH per scene mesh, indexed like `Scene::meshes`; shared between clones.
    pub(crate) blases: Vec<Arc<Blas>>,
    /// Instance level; leaves index `instances`.
    pub(crate) tlas: WideBvh,
    /// Instances in instance-level leaf order.
    pub(crate) instances: Vec<InstanceRecord>,
    /// Position in `instances` of each scene instance (`u32::MAX`: not in the tracer).
    pub(crate) record_of_instance: Vec<u32>,
    /// Sizes and timings.
    pub(crate) stats: TracerStats,
    /// The instruction set queries run in.
    pub(crate) kernel: Kernel,
}

/// A closest hit with where its triangle is stored: `(hit, mesh, packet, lane)`.
pub(crate) type Closest = (Hit, u32, u32, u32);

impl Tracer {
    /// Builds the acceleration structure for `scene` at its current time.
    pub fn new(scene: &Scene) -> Self {
        Self::with_settings(scene, BvhSettings::default())
    }

    /// [`Tracer::new`] with chosen mesh-BVH settings.
    pub fn with_settings(scene: &Scene, settings: BvhSettings) -> Self {
        let mut tracer = Self {
            settings,
            blases: Vec::new(),
            tlas: WideBvh {
                root: Item::NONE,
                bounds: Aabb::EMPTY,
                nodes: Vec::new(),
            },
            instances: Vec::new(),
            record_of_instance: Vec::new(),
            stats: TracerStats::default(),
            kernel: Kernel::new(TraversalKernel::default_for_this_cpu())
                .unwrap_or(Kernel::Portable(kernel::Portable)),
        };
        tracer.update(scene);
        tracer
    }

    /// Brings the instance level up to date with the scene's current instance transforms
    /// and masks. Mesh-level structures are never rebuilt; meshes added to the scene
    /// since the last call get theirs (meshes are assumed never to change in place).
    pub fn update(&mut self, scene: &Scene) {
        if scene.meshes.len() > self.blases.len() {
            let start = Instant::now();
            let first = self.blases.len();
            let new: Vec<Arc<Blas>> = scene.meshes[first..]
                .par_iter()
                .enumerate()
                .map(|(k, m)| {
                    let cutout = MeshCutout::new(scene, MeshId((first + k) as u32));
                    Arc::new(Blas::build(m, cutout, &self.settings))
                })
                .collect();
            self.stats.mesh_builds += new.len() as u64;
            self.blases.extend(new);
            self.stats.mesh_build_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        let start = Instant::now();
        let records: Vec<InstanceRecord> = scene
            .instances
            .iter()
            .enumerate()
            .filter_map(|(i, inst)| {
                let blas = self.blases.get(inst.mesh.index())?;
                let object_from_world = inst.world_from_object.inverse();
                let usable = blas.triangle_count > 0
                    && inst.world_from_object.matrix3.determinant() != 0.0
                    && object_from_world.matrix3.is_finite()
                    && object_from_world.translation.is_finite();
                usable.then(|| InstanceRecord {
                    translation_only: inst.world_from_object.matrix3 == Mat3A::IDENTITY,
                    object_from_world,
                    world_from_object: inst.world_from_object,
                    world_bounds: pad(blas.bounds().transformed(&inst.world_from_object)),
                    mask: inst.mask,
                    mesh: inst.mesh.0,
                    id: InstanceId(i as u32),
                })
            })
            .collect();
        let boxes: Vec<Aabb> = records.iter().map(|r| r.world_bounds).collect();
        let bin = build_binary(&boxes, &[], INSTANCE_PARAMS);
        self.instances = bin.order.iter().map(|&i| records[i as usize]).collect();
        self.record_of_instance = vec![u32::MAX; scene.instances.len()];
        for (k, r) in self.instances.iter().enumerate() {
            self.record_of_instance[r.id.index()] = k as u32;
        }
        let instances = &self.instances;
        self.tlas = WideBvh::from_binary(&bin, &|first, count| {
            instances[first as usize..(first + count) as usize]
                .iter()
                .fold(0, |m, r| m | r.mask)
        });
        self.stats.instance_build_ms = start.elapsed().as_secs_f64() * 1e3;
        self.stats.mesh_bvhs = self.blases.len();
        self.stats.mesh_nodes = self.blases.iter().map(|b| b.bvh.nodes.len()).sum();
        self.stats.instance_nodes = self.tlas.nodes.len();
        self.stats.triangles = self.blases.iter().map(|b| b.triangle_count).sum();
        self.stats.stored_triangles = self.blases.iter().map(|b| b.stored_triangles()).sum();
        self.stats.instances = self.instances.len();
        self.stats.memory_bytes = self.blases.iter().map(|b| b.memory_bytes()).sum::<usize>()
            + self.tlas.memory_bytes()
            + self.instances.len() * std::mem::size_of::<InstanceRecord>();
    }

    /// Sizes and build times.
    pub fn stats(&self) -> TracerStats {
        self.stats
    }

    /// The kernel queries run in (at construction:
    /// [`TraversalKernel::default_for_this_cpu`]).
    pub fn kernel(&self) -> TraversalKernel {
        self.kernel.kind()
    }

    /// Makes queries run in `kernel` (every kernel gives the same hits bit for bit, but
    /// for ties between triangles at equal distance, see [`TraversalKernel`]);
    /// an error, leaving the kernel unchanged, when this CPU cannot run it.
    pub fn set_kernel(&mut self, kernel: TraversalKernel) -> Result<(), KernelUnavailable> {
        self.kernel = Kernel::new(kernel).ok_or(KernelUnavailable(kernel))?;
        Ok(())
    }

    /// Address of the storage of mesh `mesh`'s BVH (stable as long as that BVH is not
    /// rebuilt), for tests that check that [`Tracer::update`] keeps mesh BVHs.
    pub fn mesh_bvh_address(&self, mesh: illume_scene::MeshId) -> Option<usize> {
        self.blases
            .get(mesh.index())
            .map(|b| b.packets.as_ptr() as usize)
    }

    /// True when this tracer and `other` use the same BVH (the same memory, not a copy)
    /// for mesh `mesh`: true for clones of one tracer, whatever their instances.
    pub fn shares_mesh_bvh(&self, other: &Tracer, mesh: illume_scene::MeshId) -> bool {
        match (
            self.blases.get(mesh.index()),
            other.blases.get(mesh.index()),
        ) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }

    /// Closest hit along `ray` among instances whose mask intersects `mask`.
    pub fn intersect(&self, ray: &Ray, mask: u32) -> Option<Hit> {
        with_stack(|stack| self.intersect_with(ray, mask, stack))
    }

    /// [`Tracer::intersect`] with the hit triangle's object-space geometry.
    pub fn intersect_geometry(&self, ray: &Ray, mask: u32) -> Option<(Hit, HitGeometry)> {
        self.scoped(|tracer| tracer.intersect_geometry(ray, mask))
    }

    /// Runs `f` with this tracer and this thread's traversal stack held for all of its
    /// queries (a photon path's rays), instead of looking the stack up per query.
    /// Queries through the tracer itself inside `f` still work, each with a stack of its
    /// own (allocated: keep them out of hot loops).
    pub fn scoped<R>(&self, f: impl FnOnce(&mut ScopedTracer<'_>) -> R) -> R {
        with_stack(|stack| {
            f(&mut ScopedTracer {
                tracer: self,
                stack,
            })
        })
    }

    #[inline]
    fn geometry_of(
        &self,
        ray: &Ray,
        mask: u32,
        stack: &mut [StackEntry],
    ) -> Option<(Hit, HitGeometry)> {
        let (hit, mesh, packet, lane) = self.closest(ray, mask, stack)?;
        let (position_object, normal_object) =
            self.blases[mesh as usize].geometry(packet, lane, hit.barycentrics);
        Some((
            hit,
            HitGeometry {
                position_object,
                normal_object,
            },
        ))
    }

    /// The hit of `ray` with one triangle alone: triangle `triangle` of scene instance
    /// `instance`, whose object-space corners (`Mesh::triangle`) are `object_corners`.
    ///
    /// Contract: the ray enters the instance's object space and meets the triangle with
    /// exactly the arithmetic of [`Tracer::intersect`] (same object-space ray, the
    /// Möller–Trumbore of [`crate::triangle::intersect_triangle`]), so when the closest hit of
    /// `ray` is this triangle, the two results are equal bit for bit. `None` when the ray
    /// misses the triangle within `(ray.t_min, ray.t_max)` or the instance is not in the
    /// tracer (unknown id, empty mesh, singular transform). Masks and alpha-mask holes are not
    /// consulted (the caller has chosen the triangle).
    pub fn intersect_instance_triangle(
        &self,
        ray: &Ray,
        instance: InstanceId,
        triangle: u32,
        object_corners: [Vec3; 3],
    ) -> Option<Hit> {
        let record = *self.record_of_instance.get(instance.index())?;
        let inst = self.instances.get(record as usize)?;
        // The object-space ray of `object_ray`, without the traversal's reciprocals.
        let m = &inst.object_from_world;
        let (origin, dir) = if inst.translation_only {
            (
                Vec3A::from(ray.origin) + m.translation,
                Vec3A::from(ray.dir),
            )
        } else {
            (
                m.transform_point3a(ray.origin.into()),
                m.transform_vector3a(ray.dir.into()),
            )
        };
        let local = Ray {
            origin: origin.into(),
            dir: dir.into(),
            t_min: ray.t_min,
            t_max: ray.t_max,
        };
        let [p0, p1, p2] = object_corners;
        crate::triangle::intersect_triangle(&local, ray.t_max, p0, p1, p2).map(
            |(t, barycentrics)| Hit {
                t,
                instance,
                triangle,
                barycentrics,
            },
        )
    }

    /// True when anything visible to `mask` lies on `ray` within `(t_min, t_max)`.
    pub fn occluded(&self, ray: &Ray, mask: u32) -> bool {
        with_stack(|stack| self.occluded_with(ray, mask, stack))
    }

    /// Closest hits for a batch of rays, in parallel (rayon, in chunks of rays).
    pub fn intersect_batch(&self, rays: &[Ray], mask: u32) -> Vec<Option<Hit>> {
        self.batch(rays, |r, stack| self.intersect_with(r, mask, stack))
    }

    /// Occlusion for a batch of rays, in parallel (rayon, in chunks of rays).
    pub fn occluded_batch(&self, rays: &[Ray], mask: u32) -> Vec<bool> {
        self.batch(rays, |r, stack| self.occluded_with(r, mask, stack))
    }

    /// Runs `query` over `rays` in parallel runs of at least `BATCH_CHUNK` rays, each run
    /// with one traversal stack; results are written once, straight into the output (no
    /// pre-filled vector to overwrite).
    fn batch<T: Send>(
        &self,
        rays: &[Ray],
        query: impl Fn(&Ray, &mut [StackEntry]) -> T + Sync,
    ) -> Vec<T> {
        rays.par_iter()
            .with_min_len(BATCH_CHUNK)
            .map_init(new_stack, |stack, r| query(r, stack))
            .collect()
    }

    #[inline]
    fn intersect_with(&self, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> Option<Hit> {
        self.closest(ray, mask, stack).map(|c| c.0)
    }

    /// Closest hit with where its triangle is stored, in the tracer's kernel.
    #[inline]
    fn closest(&self, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> Option<Closest> {
        kernel::closest(self, ray, mask, stack)
    }

    /// [`Tracer::closest`] with the box tests of `k`.
    #[inline(always)]
    pub(crate) fn closest_in<K: BoxKernel>(
        &self,
        k: K,
        ray: &Ray,
        mask: u32,
        stack: &mut [StackEntry],
    ) -> Option<Closest> {
        if !usable_ray(ray) {
            return None;
        }
        let world_ray = PreparedRay::new(ray.origin.into(), ray.dir.into(), ray.t_min);
        let mut best = None;
        traverse::<K, true>(
            k,
            &self.tlas,
            &world_ray,
            ray.t_max,
            mask,
            stack,
            #[inline(always)]
            |range, t_max, free| {
                for inst in &self.instances[range] {
                    if inst.mask & mask == 0 {
                        continue;
                    }
                    let local = object_ray(inst, &world_ray);
                    if let Some((t, triangle, barycentrics, packet, lane)) =
                        self.blases[inst.mesh as usize].intersect(k, &local, *t_max, free)
                    {
                        *t_max = t;
                        best = Some((
                            Hit {
                                t,
                                instance: inst.id,
                                triangle,
                                barycentrics,
                            },
                            inst.mesh,
                            packet,
                            lane,
                        ));
                    }
                }
                false
            },
        );
        best
    }

    #[inline]
    fn occluded_with(&self, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> bool {
        kernel::occluded(self, ray, mask, stack)
    }

    /// [`Tracer::occluded`] with the box tests of `k`.
    #[inline(always)]
    pub(crate) fn occluded_in<K: BoxKernel>(
        &self,
        k: K,
        ray: &Ray,
        mask: u32,
        stack: &mut [StackEntry],
    ) -> bool {
        if !usable_ray(ray) {
            return false;
        }
        let world_ray = PreparedRay::new(ray.origin.into(), ray.dir.into(), ray.t_min);
        let mut hit = false;
        traverse::<K, true>(
            k,
            &self.tlas,
            &world_ray,
            ray.t_max,
            mask,
            stack,
            #[inline(always)]
            |range, t_max, free| {
                // A loop, not `Iterator::any`: a closure handed to a library function may
                // stay out of line, and then it is not compiled for the kernel's
                // instruction set (see `crate::kernel`).
                for inst in &self.instances[range] {
                    if inst.mask & mask != 0
                        && self.blases[inst.mesh as usize].occluded(
                            k,
                            &object_ray(inst, &world_ray),
                            *t_max,
                            free,
                        )
                    {
                        hit = true;
                        return true;
                    }
                }
                false
            },
        );
        hit
    }
}

/// The world ray in `inst`'s object space (direction not renormalised: `t` is preserved).
#[inline(always)]
fn object_ray(inst: &InstanceRecord, world_ray: &PreparedRay) -> PreparedRay {
    let m = &inst.object_from_world;
    if inst.translation_only {
        // Same direction: only the origin moves (no new reciprocals).
        return world_ray.translated(m.translation);
    }
    PreparedRay::new(
        m.transform_point3a(world_ray.origin),
        m.transform_vector3a(world_ray.dir),
        world_ray.t_min,
    )
}

/// False for a ray with a NaN or infinite origin or direction, or a NaN extent: such a
/// ray hits nothing (a degenerate camera or transform upstream must not crash traversal).
#[inline(always)]
fn usable_ray(ray: &Ray) -> bool {
    ray.origin.is_finite() && ray.dir.is_finite() && !ray.t_min.is_nan() && !ray.t_max.is_nan()
}

/// Widens a transformed box by the rounding the transform may have made.
fn pad(b: Aabb) -> Aabb {
    let e = tolerance(&b);
    Aabb::new(b.min - e, b.max + e)
}

/// Absolute slack for containment checks of boxes near `b`: a few ulps of its largest
/// coordinate.
pub(crate) fn tolerance(b: &Aabb) -> f32 {
    let scale = Vec3A::from(b.min)
        .abs()
        .max(Vec3A::from(b.max).abs())
        .max_element();
    1e-6 * scale.max(1e-3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clone_for_another_time_shares_mesh_bvhs_and_hits_like_a_fresh_build() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let tracer = Tracer::new(&scene);
        let mut later = scene.clone();
        later.set_time(1.0);
        let mut second = tracer.clone();
        second.update(&later);
        let fresh = Tracer::new(&later);
        for m in 0..scene.meshes.len() {
            let id = illume_scene::MeshId(m as u32);
            assert!(second.shares_mesh_bvh(&tracer, id));
            assert!(!fresh.shares_mesh_bvh(&tracer, id));
        }
        assert_eq!(second.stats().mesh_builds, tracer.stats().mesh_builds);
        let rays = crate::ray_sets::incoherent_rays(&later, 500, 7);
        let mask = illume_scene::MASK_DEFAULT;
        let mut differ = 0;
        for r in &rays {
            assert_eq!(second.intersect(r, mask), fresh.intersect(r, mask));
            differ += usize::from(tracer.intersect(r, mask) != second.intersect(r, mask));
        }
        assert!(differ > 0, "the sphere moved: some hits must differ");
        second.validate().unwrap();
    }

    #[test]
    fn rays_with_nan_or_infinity_hit_nothing() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let tracer = Tracer::new(&scene);
        let mask = illume_scene::MASK_DEFAULT;
        for ray in [
            Ray::new(Vec3::new(f32::NAN, 1.0, 0.0), Vec3::NEG_Y),
            Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::new(f32::NAN, -1.0, 0.0)),
            Ray::new(Vec3::new(0.0, f32::INFINITY, 0.0), Vec3::NEG_Y),
            Ray::segment(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y, f32::NAN),
        ] {
            assert_eq!(tracer.intersect(&ray, mask), None);
            assert!(!tracer.occluded(&ray, mask));
        }
    }
}
