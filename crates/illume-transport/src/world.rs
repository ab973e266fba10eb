//! A scene with its tracer and light set, updated together.

use crate::hit_tables::HitTables;
use crate::lights::{LightSample, LightSet};
use crate::surface::{PhotonHit, SurfaceHit, mesh_hit_geometry};
use illume_accel::{Hit, ScopedTracer, Tracer};
use illume_core::{Ray, Vec3};
use illume_scene::change::EditError;
use illume_scene::{Edit, Scene, SceneChange};
use std::sync::{Arc, RwLock};

/// A world shared between the frame loop and long-lived simulation threads (photon
/// streaming): readers trace under a read lock; scene updates take the write lock briefly
/// (an instance-level refit, never a mesh BVH rebuild).
pub type SharedWorld = Arc<RwLock<World>>;

/// A scene, its acceleration structure and its lights, always mutually consistent.
///
/// A clone shares every mesh BVH, mesh and texture (`Arc`) and copies the instance
/// level, the light set and the scene's tables: a snapshot for a thread that must not
/// hold the shared world's lock (photon streaming).
#[derive(Clone)]
pub struct World {
    /// The scene at [`Scene::time`].
    pub scene: Scene,
    /// Ray queries against `scene`.
    pub tracer: Tracer,
    /// Every emitter of `scene`, with power-proportional selection.
    pub lights: LightSet,
    /// Instance frames and packed textures for [`World::photon_hit`].
    pub(crate) hit_tables: HitTables,
}

impl std::fmt::Debug for World {
    /// The scene's source, time and sizes (not its contents).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("source", &self.scene.source)
            .field("time", &self.scene.time)
            .field("instances", &self.scene.instances.len())
            .field("lights", &self.scene.lights.len())
            .finish_non_exhaustive()
    }
}

impl World {
    /// Builds the tracer and the light set for `scene`.
    pub fn new(scene: Scene) -> Self {
        let tracer = Tracer::new(&scene);
        let lights = LightSet::new(&scene);
        let hit_tables = HitTables::new(&scene);
        Self {
            scene,
            tracer,
            lights,
            hit_tables,
        }
    }

    /// A second world for `scene`, a scene derived from this world's (the same meshes
    /// and textures, e.g. at another time, with instances moved, added or masked): it
    /// shares every mesh BVH and packed texture with this world (`Arc`), so it costs an
    /// instance-level rebuild, the light set and the instance frames — never a mesh BVH
    /// build or a texture copy. Meshes `scene` has beyond this world's get their BVHs
    /// built. This world is not touched.
    pub fn with_scene(&self, scene: Scene) -> World {
        let mut tracer = self.tracer.clone();
        tracer.update(&scene);
        let mut hit_tables = self.hit_tables.clone();
        hit_tables.update(&scene);
        let lights = LightSet::new(&scene);
        World {
            scene,
            tracer,
            lights,
            hit_tables,
        }
    }

    /// A second world at scene time `t` \[s\] (see [`World::with_scene`]): this world's
    /// scene, edits included, evaluated at `t`.
    pub fn at_time(&self, t: f64) -> World {
        let mut scene = self.scene.clone();
        scene.set_time(t);
        self.with_scene(scene)
    }

    /// Wraps the world for sharing between threads.
    pub fn shared(self) -> SharedWorld {
        Arc::new(RwLock::new(self))
    }

    /// Moves the scene to time `t` \[s\] and brings the tracer and lights up to date.
    pub fn set_time(&mut self, t: f64) -> Vec<SceneChange> {
        let changes = self.scene.set_time(t);
        self.refresh(&changes);
        changes
    }

    /// Applies an interactive edit and brings the tracer and lights up to date.
    pub fn apply_edit(&mut self, edit: &Edit) -> Result<Vec<SceneChange>, EditError> {
        let changes = self.scene.apply_edit(edit)?;
        self.refresh(&changes);
        Ok(changes)
    }

    /// Re-derives the tracer's instance level and the light set after `changes`.
    pub fn refresh(&mut self, changes: &[SceneChange]) {
        if changes.iter().any(|c| {
            matches!(
                c,
                SceneChange::InstanceMoved { .. }
                    | SceneChange::InstanceAdded { .. }
                    | SceneChange::InstanceRemoved { .. }
            )
        }) {
            self.tracer.update(&self.scene);
        }
        if !changes.is_empty() {
            self.lights = LightSet::new(&self.scene);
            self.hit_tables.update(&self.scene);
        }
    }

    /// Closest hit of `ray` among instances visible to `mask`, as a surface description.
    pub fn trace(&self, ray: &Ray, mask: u32) -> Option<SurfaceHit> {
        self.tracer
            .intersect(ray, mask)
            .map(|h| self.surface(ray, &h))
    }

    /// Surface description of a hit.
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> SurfaceHit {
        SurfaceHit::new(&self.scene, ray, hit)
    }

    /// Diffuse albedo of `material` at texture coordinates `uv`: equal bit for bit to
    /// [`Scene::albedo`], through the packed copies of the textures (fewer cache misses).
    #[inline]
    pub fn albedo(
        &self,
        material: illume_scene::MaterialId,
        uv: illume_core::Vec2,
    ) -> illume_core::Rgb {
        let m = &self.scene.materials[material.index()];
        match m.base_color_texture {
            Some(t) => m.base_color * self.hit_tables.sample(&self.scene, t, m.base_color_uv(uv)),
            None => m.base_color,
        }
    }

    /// [`World::albedo`] filtered over a pixel's `footprint` (trilinear mip-mapping,
    /// [`crate::mip`]): equal to [`World::albedo`] where the footprint is at most one
    /// texel, the texture's mean over the footprint where it is larger.
    #[inline]
    pub fn albedo_footprint(
        &self,
        material: illume_scene::MaterialId,
        uv: illume_core::Vec2,
        footprint: &crate::mip::UvFootprint,
    ) -> illume_core::Rgb {
        let m = &self.scene.materials[material.index()];
        match m.base_color_texture {
            Some(t) => {
                let f = footprint.through(uv, |uv| m.base_color_uv(uv));
                m.base_color
                    * self
                        .hit_tables
                        .sample_footprint(&self.scene, t, m.base_color_uv(uv), &f)
            }
            None => m.base_color,
        }
    }

    /// The photon's view of a hit (see [`PhotonHit`]): what [`World::surface`] gives,
    /// less what photons never read, at a fraction of the cost.
    pub fn photon_hit(&self, ray: &Ray, hit: &Hit) -> PhotonHit {
        let geometry = mesh_hit_geometry(&self.scene, hit);
        PhotonHit::new(&self.scene, &self.hit_tables, ray, hit, &geometry, false)
    }

    /// The albedo, sidedness, metallic and roughness `hit` would have with material
    /// `material` instead of the scene's (the same formula as [`PhotonHit::new`], bit for
    /// bit): selective photon tracing re-traces old paths with the materials of their
    /// time. `filtered_textures` as for [`World::trace_photon_hit`].
    pub fn photon_material(
        &self,
        hit: &PhotonHit,
        material: &illume_scene::Material,
        filtered_textures: bool,
    ) -> crate::surface::PhotonMaterial {
        let inst = &self.scene.instances[hit.instance.index()];
        let mesh = &self.scene.meshes[inst.mesh.index()];
        crate::surface::photon_material(
            &self.scene,
            &self.hit_tables,
            mesh,
            hit.triangle as usize,
            hit.barycentrics,
            hit.front_face,
            material,
            filtered_textures,
        )
    }

    /// Closest hit of `ray` among instances visible to `mask`, as a [`PhotonHit`], traced
    /// with `tracer` (this world's tracer, [`Tracer::scoped`]). The hit point and normal
    /// come from the tracer's copy of the triangle, still in cache, so the next photon
    /// ray does not wait on the mesh's arrays. `filtered_textures`: see
    /// [`PhotonPathSettings::filtered_textures`](crate::photon::PhotonPathSettings).
    #[inline]
    pub fn trace_photon_hit(
        &self,
        tracer: &mut ScopedTracer<'_>,
        ray: &Ray,
        mask: u32,
        filtered_textures: bool,
    ) -> Option<PhotonHit> {
        let (hit, geometry) = tracer.intersect_geometry(ray, mask)?;
        Some(PhotonHit::new(
            &self.scene,
            &self.hit_tables,
            ray,
            &hit,
            &geometry,
            filtered_textures,
        ))
    }

    /// The first surface `ray` meets (instances visible to `mask`) as cheaply as a hit can
    /// be recorded: the tracer's hit (distance, instance, triangle), the object-space
    /// point, and whether the ray arrived on the front face — the same side
    /// [`PhotonHit::front_face`] gives, so lookups keyed like photon deposits (surface
    /// point and side) agree with them. No material, normal or texture is read.
    #[inline]
    pub fn trace_side(
        &self,
        tracer: &mut ScopedTracer<'_>,
        ray: &Ray,
        mask: u32,
    ) -> Option<(Hit, illume_core::Vec3, bool)> {
        let (hit, geometry) = tracer.intersect_geometry(ray, mask)?;
        let inst = &self.scene.instances[hit.instance.index()];
        let frame = self.hit_tables.frame(hit.instance, &inst.world_from_object);
        let front_face = ray
            .dir
            .dot(frame.normal(geometry.normal_object) * frame.det_sign)
            < 0.0;
        Some((hit, geometry.position_object, front_face))
    }

    /// True when nothing visible to the default mask lies between `hit` and the light
    /// point of `sample` along [`World::shadow_ray`] (false when there is no such ray).
    #[inline]
    pub fn unoccluded(&self, hit: &SurfaceHit, sample: &LightSample) -> bool {
        self.shadow_ray(hit, sample)
            .is_some_and(|ray| !self.tracer.occluded(&ray, illume_scene::MASK_DEFAULT))
    }

    /// The shadow ray of `sample` at `hit`, which every technique's next-event
    /// estimation and the reference share: from just off the surface to just short of
    /// the light (directional samples reach to infinity).
    ///
    /// Light arriving from below the hit's facet (behind its geometric normal, where the
    /// caller's shading normal still faces it) is the shadow terminator of a faceted
    /// curved mesh: the ray then leaves from [`SurfaceHit::smooth_point`], lifted off the
    /// facet, and meets the object itself only where the smooth surface would shadow the
    /// point too. `None` when that point is not lifted (a flat region, or normals that
    /// only a normal map tilts): the facet itself hides the light, as a ray from just
    /// above it would find. Without this the lit side ended in steps, one facet at a time.
    #[inline]
    pub fn shadow_ray(&self, hit: &SurfaceHit, sample: &LightSample) -> Option<Ray> {
        let ng = hit.facing_geometric_normal();
        if ng.dot(sample.wi) > 0.0 {
            return Some(sample.shadow_ray(hit.spawn_origin(sample.wi)));
        }
        self.terminator_ray(hit, sample)
    }

    /// [`World::shadow_ray`] from below the facet: out of line, as it is rare.
    #[cold]
    #[inline(never)]
    fn terminator_ray(&self, hit: &SurfaceHit, sample: &LightSample) -> Option<Ray> {
        if !self.hit_tables.is_curved(hit.mesh, hit.triangle) {
            return None;
        }
        let ng = hit.facing_geometric_normal();
        terminator_ray(hit.position, ng, hit.smooth_point(&self.scene), sample)
    }

    /// [`World::shadow_ray`] at a photon or gather hit.
    pub fn photon_shadow_ray(&self, hit: &PhotonHit, sample: &LightSample) -> Option<Ray> {
        let ng = hit.facing_geometric_normal();
        if ng.dot(sample.wi) > 0.0 {
            return Some(sample.shadow_ray(hit.spawn_origin(sample.wi)));
        }
        let mesh = self.scene.instances[hit.instance.index()].mesh;
        if !self.hit_tables.is_curved(mesh, hit.triangle) {
            return None;
        }
        terminator_ray(hit.position, ng, hit.smooth_point(&self.scene), sample)
    }
}

/// The shadow ray of `sample` (from below the facet at `position`, facing side `ng`)
/// leaving from `smooth`, the point lifted to the smooth surface; `None` when it is not
/// lifted ([`World::shadow_ray`]).
fn terminator_ray(position: Vec3, ng: Vec3, smooth: Vec3, sample: &LightSample) -> Option<Ray> {
    // A tenth of a spawned ray's offset: below it the lift is rounding.
    let rounding = 1e-5 * (1.0 + position.abs().max_element());
    if (smooth - position).dot(ng) <= rounding {
        return None;
    }
    let origin = illume_core::offset_ray_origin(smooth, ng, ng);
    let mut ray = sample.shadow_ray(origin);
    if ray.t_max.is_finite() {
        // The light point stays where the sample put it.
        ray.t_max = (ray.t_max - (origin - position).dot(sample.wi)).max(0.0);
    }
    Some(ray)
}
