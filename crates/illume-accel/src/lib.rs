//! Ray queries against a [`Scene`](illume_scene::Scene): a two-level acceleration
//! structure with one BVH per mesh (built once) and an instance level over them (rebuilt
//! from the instances' world boxes when transforms change, so a moving object never
//! rebuilds its own BVH).
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
//! * Mesh level: binned SAH (up to 32 bins, all three axes in one pass) over triangle
//!   boxes, with the cost of a leaf counted in groups of four triangles, builds a binary
//!   tree (large subtrees in parallel). Alongside it a second tree is built over pre-split triangle references
//!   ([`BvhSettings::split_budget`], `split.rs`), and the one the heuristic expects to be
//!   cheaper is kept (Sponza's is split, a Cornell box's is not). The tree is
//!   collapsed into eight-wide nodes of 256 bytes (child boxes as structure of arrays, so
//!   one ray meets eight boxes in one 8-lane test). Triangles are copied in leaf order,
//!   eight to a 320-byte packet (five cache lines; corner and two edges per lane, structure of arrays), so a
//!   leaf of up to eight triangles is one packet.
//! * Kernels ([`TraversalKernel`]): on CPUs with AVX2 and FMA, detected at run time, the
//!   whole query is compiled for them, and the box test of a node (with fused
//!   multiply-subtract) and the triangle test of a packet are one 8-lane pass each;
//!   elsewhere boxes and packets are tested in portable 4-lane halves. Triangle tests use
//!   the same operations in the same order, so both kernels return the same hits bit for
//!   bit, but for which of two triangles at equal distance wins (see [`TraversalKernel`]);
//!   [`KERNEL_ENV`] or [`Tracer::set_kernel`] forces one.
//! * Instance level: the same builder over the instances' world boxes (the mesh BVH's
//!   box under `world_from_object`), rebuilt by [`Tracer::update`] (cost linear in the
//!   instance count, independent of triangle counts); each node keeps the union of the masks below each child, so
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
//! * Tracers for several states of one scene share their mesh BVHs: [`Tracer`] clones
//!   hold them by `Arc` ([`Tracer::shares_mesh_bvh`]).
//!
//! The measurements behind these choices (and against `obvhs` and Embree) are in
//! `BENCHMARKS.md`, "Tracer (illume-accel)".

mod blas;
pub mod brute_force;
mod build;
mod kernel;
pub mod ray_sets;
mod split;
mod tracer;
pub mod triangle;
mod validate;
mod wide;

pub use kernel::{KERNEL_ENV, KernelUnavailable, TraversalKernel};
pub use tracer::{BvhSettings, ScopedTracer, Tracer, TracerStats};

use illume_core::{Vec2, Vec3};
use illume_scene::InstanceId;

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
