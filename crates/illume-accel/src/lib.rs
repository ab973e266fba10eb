// MEASUREMENTS — own BVH or `obvhs`, and illume against Embree 4
// (AMD EPYC, 2 cores shared with other builds: load average 4–8 during every run, so
// wall-clock figures are noisy; CPU-time figures are not time-sliced. Medians.)
//
// Own BVH vs obvhs 0.4 (DGriffin91; its compressed 8-wide CWBVH, `medium_build` preset:
// PLOC + reinsertion), Dabrovic Sponza (66,450 triangles), 2 threads, same world-space
// triangles and rays, every hit distance equal:
//   `cargo bench -p illume-accel --bench trace -- obvhs_vs_own`
//                         obvhs CWBVH      own 4-wide BVH
//   build                 51.7 ms               40.0 ms       (5 runs: 52–103 vs 40–94)
//   incoherent rays       2.09 Mrays/s          2.84 Mrays/s  (5 runs: own 1.2–1.4× faster)
//   primary rays          10.8 Mrays/s          19.4 Mrays/s  (5 runs: own 1.4–2.0× faster)
// obvhs builds with glam 0.34 (it needs glam >=0.33, <0.35; the workspace has 0.30), so
// it can only be used beside our glam with conversions at the boundary. Decision: keep
// our own BVH — it traces faster on both ray kinds, its build is as fast, and it gives
// us control of the layout (instance masks in the nodes, triangle packets, robust slab
// test) without a second glam. obvhs stays a dev-dependency for this comparison only.
//
// Against Embree 4.4 (embreex, rtcIntersect1 per ray; `python3 benches/embree_compare.py
// --rays 1000000 --rounds 3`), closest hit, same triangles and rays, same hit distances:
//                              wall clock, 2 threads        CPU time of 1 thread
//   Mrays/s                     illume  Embree  ratio        illume  Embree  ratio
//   cornell-spot   incoherent    9.18    9.75   0.94         10.17    9.65   1.05
//   cornell-spot   primary      12.79   12.66   1.01         14.00   12.85   1.11
//   CornellBox-Sphere incoh.     8.33    9.54   0.91          9.80   10.16   0.97
//   CornellBox-Sphere primary   13.72   15.24   0.89         14.55   15.53   0.94
//   Sponza         incoherent    2.98    3.60   0.83          2.99    3.94   0.76
//   Sponza         primary      18.74   17.50   1.06         19.23   17.33   1.10
// Repeating the whole run moves each ratio by up to ±0.15 (an earlier run, load 7–8:
// 1.08 1.12 0.97 1.10 0.83 1.17 wall, 1.08 1.08 1.07 1.22 0.80 1.01 CPU).
// (Embree's two-thread figure is two processes each tracing half the rays; illume's
// cornell-spot goes through its three instances, Embree gets the flattened soup.)
// Sponza's incoherent rays are the weak spot: traversal there is bound by memory
// latency (3.5 MB of nodes and packets), and Embree selects its kernels by CPU (this one
// has AVX2 and AVX-512) where we stay on portable 4-wide SSE2 (target features need
// `unsafe` or build flags).
//
// Settings (BvhSettings::default) chosen by thread CPU time on Sponza: leaves of up to 8
// triangles with a packet-aware SAH (node cost 2) were within noise of 12 and 16 and
// 6 % faster than node cost 1 on incoherent rays; 64 SAH bins gained nothing over 32.

//! Ray queries against a [`Scene`]: a two-level acceleration structure with one BVH per
//! mesh (built once) and an instance level over them (rebuilt from the instances' world
//! boxes when transforms change, so a moving object never rebuilds its own BVH).
//!
//! Queries take an instance mask: a ray sees instance `i` when `ray_mask & i.mask != 0`
//! (see [`illume_scene::MASK_DEFAULT`]), so a technique can include or ignore chosen
//! instances (selective photon tracing's phantoms).
//!
//! ```
//! use illume_accel::Tracer;
//! use illume_core::{Ray, Vec3};
//! let scene = illume_scene::builtin::load("cornell-spot").unwrap();
//! let tracer = Tracer::new(&scene);
//! let hit = tracer.intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y), illume_scene::MASK_DEFAULT);
//! assert!((hit.unwrap().t - 1.0).abs() < 1e-5); // the floor
//! tracer.validate().unwrap();
//! ```
//!
//! # Design
//!
//! * Mesh level: binned SAH (32 bins, all three axes) over triangle boxes, with the cost
//!   of a leaf counted in packets of four triangles, builds a binary tree that is
//!   collapsed into four-wide nodes of 128 bytes (child boxes as structure of arrays, so
//!   one ray meets four boxes in 4-lane arithmetic). Triangles are copied in leaf order,
//!   four to a 160-byte packet (corner and two edges per lane), and tested four at once.
//! * Instance level: the same builder over the instances' world boxes (the mesh BVH's
//!   box under `world_from_object`), rebuilt by [`Tracer::update`] (about a millisecond
//!   for 1000 instances); each node keeps the union of the masks below each child, so
//!   masked-out instances are culled at the instance level. Rays enter a mesh BVH through
//!   the precomputed `object_from_world` (for translation-only instances, by moving the
//!   origin alone); the object-space direction is not renormalised, so `t` stays in the
//!   units of the caller's ray.
//! * Traversal is ordered (nearest child first, far children culled on pop against the
//!   closest hit), with a conservative slab test (exit distance widened by 2γ₃) and a
//!   reciprocal direction that stays finite for zero direction components. The stack is
//!   per thread and reused.
//! * [`brute_force`] intersects every triangle; it is the oracle the BVH is tested
//!   against, and [`ray_sets`] makes the benchmark rays.
//!
//! The measurements behind these choices (and against `obvhs` and Embree) are in a
//! comment at the top of this file.

mod blas;
pub mod brute_force;
mod build;
pub mod ray_sets;
pub mod triangle;
mod wide;

use crate::blas::Blas;
use crate::build::{BuildParams, build_binary};
use crate::wide::{Bvh4, Item, PreparedRay, StackEntry, traverse, with_stack};
use illume_core::{Aabb, Affine3A, Mat3A, Ray, Vec2, Vec3, Vec3A};
use illume_scene::{InstanceId, Scene};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// A ray–triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray (in units of `ray.dir`'s length).
    pub t: f32,
    /// The instance hit.
    pub instance: InstanceId,
    /// Triangle index within the instance's mesh.
    pub triangle: u32,
    /// Barycentrics `(b1, b2)` of the hit: `p = (1 − b1 − b2)·v0 + b1·v1 + b2·v2`.
    pub barycentrics: Vec2,
}

/// Object-space geometry of a hit triangle, read from the tracer's own copy of the
/// triangle (in cache right after the query, unlike the mesh's arrays).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitGeometry {
    /// The hit point in the instance's object space, `v0 + b1·(v1 − v0) + b2·(v2 − v0)`
    /// (equal to the mesh's corners interpolated with [`Hit::barycentrics`], to
    /// rounding).
    pub position_object: Vec3,
    /// `(v1 − v0) × (v2 − v0)` in object space: the front face's normal, unnormalised.
    pub normal_object: Vec3,
}

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
}

/// Size and cost of a [`Tracer`]'s structures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TracerStats {
    /// Mesh BVHs held (one per mesh).
    pub mesh_bvhs: usize,
    /// Four-wide nodes over all mesh BVHs.
    pub mesh_nodes: usize,
    /// Four-wide nodes of the instance level.
    pub instance_nodes: usize,
    /// Triangles stored over all mesh BVHs (each mesh once, however often instanced).
    pub triangles: usize,
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
struct InstanceRecord {
    /// Maps world points to the mesh's object space.
    object_from_world: Affine3A,
    /// True when `object_from_world` only translates (rays keep their direction).
    translation_only: bool,
    /// Maps object points to world space (kept for [`Tracer::validate`]).
    world_from_object: Affine3A,
    /// World box of the mesh BVH's box, padded for rounding.
    world_bounds: Aabb,
    /// Visibility bits.
    mask: u32,
    /// Mesh (and mesh BVH) index.
    mesh: u32,
    /// Which scene instance.
    id: InstanceId,
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
    /// Count a leaf's cost in packets of four triangles (as they are tested) rather than
    /// in triangles. True favours leaves of 4 and 8 triangles.
    pub packet_aware_sah: bool,
}

impl Default for BvhSettings {
    fn default() -> Self {
        Self {
            max_leaf_triangles: 8,
            node_cost: 2.0,
            packet_aware_sah: true,
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
    settings: BvhSettings,
    /// One BVH per scene mesh, indexed like `Scene::meshes`; shared between clones.
    blases: Vec<Arc<Blas>>,
    /// Instance level; leaves index `instances`.
    tlas: Bvh4,
    /// Instances in instance-level leaf order.
    instances: Vec<InstanceRecord>,
    /// Position in `instances` of each scene instance (`u32::MAX`: not in the tracer).
    record_of_instance: Vec<u32>,
    /// Sizes and timings.
    stats: TracerStats,
}

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
            tlas: Bvh4 {
                root: Item::NONE,
                bounds: Aabb::EMPTY,
                nodes: Vec::new(),
            },
            instances: Vec::new(),
            record_of_instance: Vec::new(),
            stats: TracerStats::default(),
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
            let new: Vec<Arc<Blas>> = scene.meshes[self.blases.len()..]
                .par_iter()
                .map(|m| Arc::new(Blas::build(m, &self.settings)))
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
        let bin = build_binary(&boxes, INSTANCE_PARAMS);
        self.instances = bin.order.iter().map(|&i| records[i as usize]).collect();
        self.record_of_instance = vec![u32::MAX; scene.instances.len()];
        for (k, r) in self.instances.iter().enumerate() {
            self.record_of_instance[r.id.index()] = k as u32;
        }
        let instances = &self.instances;
        self.tlas = Bvh4::from_binary(&bin, &|first, count| {
            instances[first as usize..(first + count) as usize]
                .iter()
                .fold(0, |m, r| m | r.mask)
        });
        self.stats.instance_build_ms = start.elapsed().as_secs_f64() * 1e3;
        self.stats.mesh_bvhs = self.blases.len();
        self.stats.mesh_nodes = self.blases.iter().map(|b| b.bvh.nodes.len()).sum();
        self.stats.instance_nodes = self.tlas.nodes.len();
        self.stats.triangles = self.blases.iter().map(|b| b.triangle_count).sum();
        self.stats.instances = self.instances.len();
        self.stats.memory_bytes = self.blases.iter().map(|b| b.memory_bytes()).sum::<usize>()
            + self.tlas.memory_bytes()
            + self.instances.len() * std::mem::size_of::<InstanceRecord>();
    }

    /// Sizes and build times.
    pub fn stats(&self) -> TracerStats {
        self.stats
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
    /// Möller–Trumbore of [`triangle::intersect_triangle`]), so when the closest hit of
    /// `ray` is this triangle, the two results are equal bit for bit. `None` when the ray
    /// misses the triangle within `(ray.t_min, ray.t_max)` or the instance is not in the
    /// tracer (unknown id, empty mesh, singular transform). Masks are not consulted.
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
        triangle::intersect_triangle(&local, ray.t_max, p0, p1, p2).map(|(t, barycentrics)| Hit {
            t,
            instance,
            triangle,
            barycentrics,
        })
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

    /// Runs `query` over `rays` in parallel chunks, each chunk with one traversal stack.
    fn batch<T: Send + Clone + Default>(
        &self,
        rays: &[Ray],
        query: impl Fn(&Ray, &mut [StackEntry]) -> T + Sync,
    ) -> Vec<T> {
        let mut out = vec![T::default(); rays.len()];
        out.par_chunks_mut(BATCH_CHUNK)
            .zip(rays.par_chunks(BATCH_CHUNK))
            .for_each(|(out, rays)| {
                with_stack(|stack| {
                    for (o, r) in out.iter_mut().zip(rays) {
                        *o = query(r, stack);
                    }
                })
            });
        out
    }

    #[inline]
    fn intersect_with(&self, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> Option<Hit> {
        self.closest(ray, mask, stack).map(|c| c.0)
    }

    /// Closest hit with where its triangle is stored: `(hit, mesh, packet, lane)`.
    #[inline(always)]
    fn closest(
        &self,
        ray: &Ray,
        mask: u32,
        stack: &mut [StackEntry],
    ) -> Option<(Hit, u32, u32, u32)> {
        let world_ray = PreparedRay::new(ray.origin.into(), ray.dir.into(), ray.t_min);
        let mut best = None;
        traverse::<true>(
            &self.tlas,
            &world_ray,
            ray.t_max,
            mask,
            stack,
            |range, t_max, free| {
                for inst in &self.instances[range] {
                    if inst.mask & mask == 0 {
                        continue;
                    }
                    let local = object_ray(inst, &world_ray);
                    if let Some((t, triangle, barycentrics, packet, lane)) =
                        self.blases[inst.mesh as usize].intersect(&local, *t_max, free)
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
        let world_ray = PreparedRay::new(ray.origin.into(), ray.dir.into(), ray.t_min);
        let mut hit = false;
        traverse::<true>(
            &self.tlas,
            &world_ray,
            ray.t_max,
            mask,
            stack,
            |range, t_max, free| {
                hit = self.instances[range].iter().any(|inst| {
                    inst.mask & mask != 0
                        && self.blases[inst.mesh as usize].occluded(
                            &object_ray(inst, &world_ray),
                            *t_max,
                            free,
                        )
                });
                hit
            },
        );
        hit
    }

    /// Checks the structure's invariants (bounds contain children and triangles, every
    /// triangle referenced once); the message says what is broken.
    pub fn validate(&self) -> Result<(), String> {
        for (m, blas) in self.blases.iter().enumerate() {
            validate_blas(blas).map_err(|e| format!("mesh {m} BVH: {e}"))?;
        }
        let mut seen = vec![0u32; self.instances.len()];
        validate_tree(&self.tlas, &mut |range, bounds, mask, place| {
            for (k, inst) in self.instances[range.clone()].iter().enumerate() {
                seen[range.start + k] += 1;
                if !bounds.contains_box(&inst.world_bounds, tolerance(bounds)) {
                    return Err(format!("{place}: box {bounds:?} does not contain instance {} box {:?}", inst.id.0, inst.world_bounds));
                }
                let blas_world = self.blases[inst.mesh as usize].bounds().transformed(&inst.world_from_object);
                if !inst.world_bounds.contains_box(&blas_world, tolerance(&blas_world)) {
                    return Err(format!("{place}: instance {} box {:?} does not contain its mesh BVH's world box {blas_world:?}", inst.id.0, inst.world_bounds));
                }
                if inst.mask & !mask != 0 {
                    return Err(format!("{place}: mask {mask:#x} lacks bits of instance {} mask {:#x}", inst.id.0, inst.mask));
                }
            }
            Ok(())
        })
        .map_err(|e| format!("instance level: {e}"))?;
        if let Some(i) = seen.iter().position(|&c| c != 1) {
            return Err(format!(
                "instance level: instance record {i} (instance {}) referenced {} times",
                self.instances[i].id.0, seen[i]
            ));
        }
        Ok(())
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

/// Widens a transformed box by the rounding the transform may have made.
fn pad(b: Aabb) -> Aabb {
    let e = tolerance(&b);
    Aabb::new(b.min - e, b.max + e)
}

/// Absolute slack for containment checks of boxes near `b`: a few ulps of its largest
/// coordinate.
fn tolerance(b: &Aabb) -> f32 {
    let scale = Vec3A::from(b.min)
        .abs()
        .max(Vec3A::from(b.max).abs())
        .max_element();
    1e-6 * scale.max(1e-3)
}

fn validate_blas(blas: &Blas) -> Result<(), String> {
    let n = blas.triangle_count;
    let mut packet_refs = vec![0u32; blas.packets.len()];
    let mut index_refs = vec![0u32; n];
    validate_tree(&blas.bvh, &mut |range, bounds, _, place| {
        for (k, packet) in blas.packets[range.clone()].iter().enumerate() {
            packet_refs[range.start + k] += 1;
            for (index, corners) in packet.triangles() {
                let Some(c) = index_refs.get_mut(index as usize) else {
                    return Err(format!(
                        "{place}: triangle index {index} out of range 0..{n}"
                    ));
                };
                *c += 1;
                let tb = Aabb::from_points(corners);
                if !bounds.contains_box(&tb, tolerance(&tb)) {
                    return Err(format!(
                        "{place}: box {bounds:?} does not contain triangle {index} {corners:?}"
                    ));
                }
            }
        }
        Ok(())
    })?;
    if let Some(i) = packet_refs.iter().position(|&c| c != 1) {
        return Err(format!(
            "triangle packet {i} is in {} leaves",
            packet_refs[i]
        ));
    }
    if let Some(i) = index_refs.iter().position(|&c| c != 1) {
        return Err(format!(
            "mesh triangle {i} is stored {} times",
            index_refs[i]
        ));
    }
    Ok(())
}

/// Checks one leaf: `(primitive range, box and mask its parent holds, where)`.
type LeafCheck<'a> = dyn FnMut(std::ops::Range<usize>, &Aabb, u32, &str) -> Result<(), String> + 'a;

/// Walks every node of `bvh` checking that each node's child boxes lie inside the box
/// its parent holds for it and that unused slots are empty; calls
/// `leaf(range, box, mask, place)` for every leaf with the box and mask its parent holds.
fn validate_tree(bvh: &Bvh4, leaf: &mut LeafCheck<'_>) -> Result<(), String> {
    if bvh.root == Item::NONE {
        return if bvh.nodes.is_empty() {
            Ok(())
        } else {
            Err(format!("empty tree has {} nodes", bvh.nodes.len()))
        };
    }
    let mut visits = vec![0u32; bvh.nodes.len()];
    // (reference, box the parent holds for it, mask the parent holds for it, parent description)
    let mut work = vec![(bvh.root, bvh.bounds, u32::MAX, "root".to_string())];
    while let Some((item, bounds, mask, place)) = work.pop() {
        if item.is_leaf() {
            leaf(
                item.leaf_range(),
                &bounds,
                mask,
                &format!("leaf {:?} under {place}", item.leaf_range()),
            )?;
            continue;
        }
        let index = item.node();
        let node = bvh.nodes.get(index).ok_or_else(|| {
            format!(
                "{place}: child node {index} out of range 0..{}",
                bvh.nodes.len()
            )
        })?;
        visits[index] += 1;
        if visits[index] > 1 {
            return Err(format!("node {index} is referenced more than once"));
        }
        let count = node.child_count();
        if count < 2 {
            return Err(format!("node {index} has {count} children"));
        }
        for slot in 0..wide::WIDTH {
            let b = node.child_bounds(slot);
            if slot >= count {
                if !b.is_empty() || node.masks[slot] != 0 {
                    return Err(format!(
                        "node {index} slot {slot}: unused slot is not empty"
                    ));
                }
                continue;
            }
            if !bounds.contains_box(&b, tolerance(&b)) {
                return Err(format!(
                    "node {index} slot {slot}: child box {b:?} is outside the node's box {bounds:?}"
                ));
            }
            if node.masks[slot] & !mask != 0 {
                return Err(format!(
                    "node {index} slot {slot}: mask {:#x} has bits the parent's {mask:#x} lacks",
                    node.masks[slot]
                ));
            }
            work.push((
                Item(node.children[slot]),
                b,
                node.masks[slot],
                format!("node {index} slot {slot}"),
            ));
        }
    }
    if let Some(i) = visits.iter().position(|&v| v == 0) {
        return Err(format!("node {i} is unreachable"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_names_the_broken_node() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let mut tracer = Tracer::new(&scene);
        assert_eq!(tracer.validate(), Ok(()));
        // Shrink one child box of the sphere's root node: its triangles stick out.
        let sphere = scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .unwrap();
        let mesh = scene.instances[sphere].mesh.index();
        let blas = Arc::get_mut(&mut tracer.blases[mesh]).expect("not shared");
        blas.bvh.nodes[0].bounds[3][1] -= 0.05;
        let err = tracer.validate().unwrap_err();
        assert!(err.starts_with(&format!("mesh {mesh} BVH:")), "{err}");
        assert!(
            err.contains("outside the node's box") || err.contains("does not contain triangle"),
            "{err}"
        );
        // Losing a triangle reference is caught too.
        let mut tracer = Tracer::new(&scene);
        let first = tracer.blases[mesh].packets[0].index[0];
        Arc::get_mut(&mut tracer.blases[mesh])
            .expect("not shared")
            .packets[1]
            .index[0] = first;
        let err = tracer.validate().unwrap_err();
        assert!(err.contains(" times"), "{err}");
        // An instance box that no longer covers its mesh.
        let mut tracer = Tracer::new(&scene);
        tracer.instances[0].world_bounds.max.y -= 0.5;
        let err = tracer.validate().unwrap_err();
        assert!(err.starts_with("instance level:"), "{err}");
    }

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
}
