//! Re-tracing a photon group (§5.2, Algorithm 1): detection in the union of old and new
//! scene, then negative and positive branches from the first changed segment.
//!
//! Every group was last shot in a scene state, its *epoch* ([`Snapshot`]: instance
//! transforms and visibility, materials, lights). To bring a stale group to the current
//! state, the group's photons are traced in a *union world* ([`UnionWorld`]): the
//! current scene plus a *phantom* for every instance whose transform (or visibility)
//! differs between epoch and now — the same mesh at its old transform — with instance
//! mask bits [`OLD`] | [`NEW`] on unchanged instances, [`NEW`] on moved ones and [`OLD`]
//! on phantoms. A group has one epoch, so it never holds two phantoms of one object (the
//! M₁, M₂, M₃ example of §5.2 follows by construction).
//!
//! A photon is traced with mask OLD | NEW. While its segments end on unchanged
//! instances with unchanged materials, old and new paths coincide (a closest hit in the
//! union that belongs to both scenes is the closest hit of each), so those impacts keep
//! their deposits. At the first segment ending on a changed instance — moved, a
//! phantom, or a changed material — the path is copied with its sampler state and
//! continued twice: with negative energy in the epoch (mask OLD, the epoch's materials)
//! and positive energy now (mask NEW). A photon whose light changed is invalid from
//! emission: both branches start at the light, from the epoch's and the current light
//! set. Deposits are signed integer quanta, so the negative branch removes exactly what
//! the photon deposited when it was last traced.

use crate::elements::Elements;
use crate::groups::GroupLayout;
use crate::masking::{DELTA_P, MaskingView, TextureMasking};
use crate::qmc::{LightCells, emit, photon_stream};
use illume_core::sampling::{HaltonScramble, HaltonStream};
use illume_core::{Affine3A, Vec3};
use illume_scene::{Instance, MASK_DEFAULT, Material, Scene};
use illume_transport::World;
use illume_transport::flux::Quanta;
use illume_transport::lights::LightSet;
use illume_transport::photon::{PhotonPath, PhotonPathSettings};
use illume_transport::surface::PhotonHit;
use rayon::prelude::*;

/// Mask bit of instances present in a group's epoch (unchanged ones and phantoms).
pub const OLD: u32 = 1 << 1;
/// Mask bit of instances present now (unchanged and moved ones).
pub const NEW: u32 = 1 << 2;

/// The scene state a group was shot in.
#[derive(Debug)]
pub struct Snapshot {
    /// Increases with every lighting change.
    pub id: u64,
    /// `world_from_object` per instance.
    pub transforms: Vec<Affine3A>,
    /// True per instance when photons see it.
    pub visible: Vec<bool>,
    /// Every material.
    pub materials: Vec<Material>,
    /// The light set.
    pub lights: LightSet,
    /// Its light units and cells.
    pub cells: LightCells,
}

impl Snapshot {
    /// The state of `world`; light cells over `2^k2` cells, with emission maps `maps`
    /// ([`crate::emission`]; empty: uniform emission).
    pub fn with_maps(world: &World, id: u64, k2: u32, maps: crate::emission::EmissionMaps) -> Self {
        let mut s = Self::of(world, id, k2);
        s.cells = s.cells.with_maps(maps);
        s
    }

    /// The state of `world`; light cells over `2^k2` cells.
    pub fn of(world: &World, id: u64, k2: u32) -> Self {
        let scene = &world.scene;
        Self {
            id,
            transforms: scene
                .instances
                .iter()
                .map(|i| i.world_from_object)
                .collect(),
            visible: scene
                .instances
                .iter()
                .map(|i| i.mask & MASK_DEFAULT != 0)
                .collect(),
            materials: scene.materials.clone(),
            lights: world.lights.clone(),
            cells: LightCells::new(&world.lights, k2),
        }
    }

    /// True when instance `i` is placed differently (or seen differently) in `other`.
    pub fn instance_differs(&self, other: &Snapshot, i: usize) -> bool {
        let a = (self.visible.get(i), self.transforms.get(i));
        let b = (other.visible.get(i), other.transforms.get(i));
        match (a, b) {
            ((Some(&va), Some(ta)), (Some(&vb), Some(tb))) => va != vb || (va && ta != tb),
            _ => true,
        }
    }
}

/// What differs between an epoch and now, per photon unit of change.
#[derive(Debug)]
pub struct Changes {
    /// Per material: differs.
    pub materials: Vec<bool>,
    /// The light cells differ in layout: every photon is invalid from emission.
    pub all_lights: bool,
    /// Per light unit (the current cells' order): its emission differs.
    pub units: Vec<bool>,
    /// Any instance moved, appeared or vanished.
    pub any_instance: bool,
}

impl Changes {
    /// Differences between `old` and `new`.
    pub fn between(old: &Snapshot, new: &Snapshot) -> Self {
        let materials = (0..new.materials.len())
            .map(|m| old.materials.get(m) != Some(&new.materials[m]))
            .collect();
        let all_lights = !old.cells.same_layout(&new.cells);
        let units = new
            .cells
            .units()
            .iter()
            .zip(old.cells.units())
            .map(|(n, o)| n.signature != o.signature)
            .collect();
        let any_instance = (0..new.transforms.len().max(old.transforms.len()))
            .any(|i| old.instance_differs(new, i));
        Self {
            materials,
            all_lights,
            units,
            any_instance,
        }
    }

    /// True when nothing photons see differs.
    pub fn none(&self) -> bool {
        !self.all_lights
            && !self.any_instance
            && !self.materials.iter().any(|&m| m)
            && !self.units.iter().any(|&u| u)
    }
}

/// The world a stale group is traced in: the current scene plus phantoms (see the
/// module doc).
pub struct UnionWorld {
    /// The union scene's world.
    pub world: World,
    /// Per union instance, the original instance it stands for.
    pub original: Vec<u32>,
    /// Per union instance: a phantom, or an instance placed differently now.
    pub changed_instance: Vec<bool>,
    /// Per union instance: a phantom.
    pub phantom: Vec<bool>,
    /// What differs.
    pub changes: Changes,
    /// Epoch and current snapshot ids it was built for.
    pub key: (u64, u64),
}

impl UnionWorld {
    /// The union of `epoch` and `current` (the live `world`'s state).
    pub fn new(world: &World, epoch: &Snapshot, current: &Snapshot) -> Self {
        let mut scene: Scene = world.scene.clone();
        let n = scene.instances.len();
        let mut original: Vec<u32> = (0..n as u32).collect();
        let mut changed_instance = vec![false; n];
        let mut phantom = vec![false; n];
        for i in 0..n {
            let now_visible = scene.instances[i].mask & MASK_DEFAULT != 0;
            let then_visible = epoch.visible.get(i).copied().unwrap_or(false);
            let differs = epoch.instance_differs(current, i);
            let inst = &mut scene.instances[i];
            inst.mask = match (then_visible, now_visible, differs) {
                (_, _, false) if now_visible => OLD | NEW,
                (_, true, true) => NEW,
                _ => 0,
            };
            changed_instance[i] = differs;
            if then_visible && differs {
                let ghost = Instance {
                    world_from_object: epoch.transforms[i],
                    mask: OLD,
                    dynamic: true,
                    ..inst.clone()
                };
                scene.instances.push(ghost);
                original.push(i as u32);
                changed_instance.push(true);
                phantom.push(true);
            }
        }
        Self {
            world: world.with_scene(scene),
            original,
            changed_instance,
            phantom,
            changes: Changes::between(epoch, current),
            key: (epoch.id, current.id),
        }
    }

    /// True when a segment ending at `hit` meets a change: a moved instance, a phantom,
    /// or a changed material.
    #[inline]
    fn meets_change(&self, hit: &PhotonHit) -> bool {
        let u = hit.instance.index();
        self.changed_instance[u] || self.changes.materials[self.material_of(hit)]
    }

    #[inline]
    fn material_of(&self, hit: &PhotonHit) -> usize {
        let scene = &self.world.scene;
        let inst = &scene.instances[hit.instance.index()];
        scene.meshes[inst.mesh.index()].triangle_materials[hit.triangle as usize].index()
    }
}

/// What a pilot's first changed segment met (§5.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Met {
    /// An instance where it is now (moved since the group's epoch).
    Moved,
    /// A phantom: an instance where it was in the group's epoch.
    Phantom,
    /// A surface whose material changed.
    Material,
    /// The photon's light changed.
    Light,
}

/// Where a photon's shared path first meets a change: the path there, what it met
/// (the instance by its original index) and the increment of P a pilot gives.
struct Fork {
    at: PhotonPath,
    met: Met,
    instance: u32,
    delta_p: f32,
}

/// A pilot that met a change (§5.3): the group it raises (Eq. 6) and by how much.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotHit {
    /// The pilot's index (it raises group `pilot mod N_g`).
    pub pilot: u64,
    /// What its first changed segment met.
    pub met: Met,
    /// The original instance met, or `u32::MAX` for a light change.
    pub instance: u32,
    /// Its increment of P: Δp/T_e for the texture where the segment ended
    /// ([`TextureMasking::increment`]), Δp for a light change.
    pub delta_p: f32,
}

/// One deposit: accumulator index, side (0 front, 1 back), sign (+1 an impact added, −1
/// an impact taken back), signed quanta.
pub type Deposit = (u32, u8, i8, Quanta);

/// What tracing some photons of a group produced.
#[derive(Clone, Debug, Default)]
pub struct TraceOutput {
    /// Signed deposits, to be applied together.
    pub deposits: Vec<Deposit>,
    /// Pilots that met a change.
    pub pilot_hits: Vec<PilotHit>,
    /// Pilots traced with an impact in the view frustum: (pilot index, visible).
    pub pilots: Vec<(u64, bool)>,
    /// Photons traced.
    pub photons: u64,
    /// Photons found invalid (re-traced in two branches).
    pub invalid: u64,
    /// Rays traced (shared prefix once, branches each).
    pub rays: u64,
}

impl TraceOutput {
    fn merge(mut self, o: TraceOutput) -> TraceOutput {
        self.deposits.extend(o.deposits);
        self.pilot_hits.extend(o.pilot_hits);
        self.pilots.extend(o.pilots);
        self.photons += o.photons;
        self.invalid += o.invalid;
        self.rays += o.rays;
        self
    }
}

/// Everything a trace needs besides the world.
pub struct TraceContext<'a> {
    /// Mesh elements.
    pub elements: &'a Elements,
    /// Pool layout.
    pub layout: GroupLayout,
    /// Halton scrambling.
    pub scramble: &'a HaltonScramble,
    /// Photon path settings.
    pub path: PhotonPathSettings,
    /// Quanta per watt.
    pub inv_quantum: f64,
    /// Tells whether a world point is in the view frustum.
    pub frustum: &'a Frustum,
    /// Texture masking of pilot increments (§5.3).
    pub masking: &'a TextureMasking,
    /// The camera, for the MIP level texture masking reads.
    pub view: MaskingView,
}

/// The camera's view frustum, for §5.3's visibility factor.
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    /// `camera_from_world`.
    pub camera_from_world: Affine3A,
    /// tan(yfov/2).
    pub tan_y: f32,
    /// tan(yfov/2)·aspect.
    pub tan_x: f32,
}

impl Frustum {
    /// The frustum of `scene`'s camera for an image of aspect `aspect` (width/height).
    pub fn of(scene: &Scene, aspect: f32) -> Self {
        let tan_y = (scene.camera.yfov_rad * 0.5).tan();
        Self {
            camera_from_world: scene.camera.world_from_camera.inverse(),
            tan_y,
            tan_x: tan_y * aspect,
        }
    }

    /// True when `p` lies inside (the camera looks down −Z).
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        let c = self.camera_from_world.transform_point3(p);
        let d = -c.z;
        d > 0.0 && c.x.abs() <= self.tan_x * d && c.y.abs() <= self.tan_y * d
    }
}

impl TraceContext<'_> {
    #[inline]
    fn deposit(
        &self,
        world: &World,
        original: u32,
        hit: &PhotonHit,
        flux: illume_core::Rgb,
        sign: i64,
        out: &mut Vec<Deposit>,
    ) {
        let inst = original as usize;
        if inst >= self.elements.instances() {
            return;
        }
        let mesh = world.scene.instances[inst].mesh.index();
        let e = self
            .elements
            .element(inst, mesh, hit.triangle as usize, hit.barycentrics);
        let q = Quanta::from_flux(flux, self.inv_quantum);
        let (q, sign) = if sign < 0 { (-q, -1) } else { (q, 1) };
        out.push((e, (!hit.front_face) as u8, sign, q));
    }

    /// Traces photons `indices` from scratch in `world` (mask [`MASK_DEFAULT`]) with
    /// `lights`, depositing every impact after the first with positive energy: the
    /// initial fill (index order) and the from-scratch oracle of the tests.
    pub fn trace_fresh(&self, world: &World, cells: &LightCells, indices: &[u64]) -> TraceOutput {
        indices
            .par_iter()
            .fold(TraceOutput::default, |mut out, &i| {
                let mut s = photon_stream(i, self.scramble);
                out.photons += 1;
                if let Some((path, _)) = emit(&world.lights, cells, &mut s) {
                    let mask = MASK_DEFAULT;
                    let visible = self.branch(world, None, path, &mut s, mask, 1, &mut out);
                    if self.layout.is_pilot(i) {
                        out.pilots.push((i, visible));
                    }
                }
                out
            })
            .reduce(TraceOutput::default, TraceOutput::merge)
    }

    /// Continues `path` to its end in `world` with `mask`, depositing impacts with
    /// `bounce ≥ 1` with `sign`. `union`: map phantoms to their originals and, for the
    /// old branch (`sign < 0`), apply `old_materials`. Returns whether an impact fell in
    /// the view frustum.
    #[allow(clippy::too_many_arguments)]
    fn branch(
        &self,
        world: &World,
        union: Option<(&UnionWorld, &[Material])>,
        mut path: PhotonPath,
        s: &mut HaltonStream<'_>,
        mask: u32,
        sign: i64,
        out: &mut TraceOutput,
    ) -> bool {
        let mut visible = false;
        world.tracer.scoped(|tracer| {
            while path.alive(&self.path) {
                out.rays += 1;
                let Some(mut hit) = path.trace(world, tracer, mask, &self.path) else {
                    break;
                };
                let original = match union {
                    Some((u, old)) => {
                        if sign < 0 {
                            let m = u.material_of(&hit);
                            if u.changes.materials[m] {
                                let was = world.photon_material(
                                    &hit,
                                    &old[m],
                                    self.path.filtered_textures,
                                );
                                hit.albedo = was.albedo;
                                hit.reflects = was.reflects;
                                hit.metallic = was.metallic;
                                hit.roughness = was.roughness;
                            }
                        }
                        u.original[hit.instance.index()]
                    }
                    None => hit.instance.0,
                };
                if !hit.reflects {
                    break;
                }
                visible |= self.frustum.contains(hit.position);
                let (impact, continues) = path.scatter(hit, s, &self.path);
                if impact.bounce >= 1 {
                    self.deposit(
                        world,
                        original,
                        &impact.hit,
                        impact.flux,
                        sign,
                        &mut out.deposits,
                    );
                }
                if !continues {
                    break;
                }
            }
        });
        visible
    }

    /// Brings photons `indices` (of one stale group) from `epoch` to `current` in
    /// `union` (see the module doc).
    pub fn retrace(
        &self,
        union: &UnionWorld,
        epoch: &Snapshot,
        current: &Snapshot,
        indices: &[u64],
    ) -> TraceOutput {
        indices
            .par_iter()
            .fold(TraceOutput::default, |mut out, &i| {
                self.retrace_photon(union, epoch, current, i, &mut out);
                out
            })
            .reduce(TraceOutput::default, TraceOutput::merge)
    }

    /// Photon `i` from `epoch` to `current`: wholly re-traced with negative and positive
    /// energy when its light changed, else traced once in the union up to the first
    /// change it meets and forked there.
    fn retrace_photon(
        &self,
        union: &UnionWorld,
        epoch: &Snapshot,
        current: &Snapshot,
        i: u64,
        out: &mut TraceOutput,
    ) {
        let world = &union.world;
        out.photons += 1;
        let is_pilot = self.layout.is_pilot(i);
        let fresh = photon_stream(i, self.scramble);
        let mut s = fresh.clone();
        let now = emit(&current.lights, &current.cells, &mut s);
        let light_changed = union.changes.all_lights
            || now
                .as_ref()
                .is_some_and(|(_, unit)| union.changes.units.get(*unit as usize) != Some(&false));
        if light_changed {
            out.invalid += 1;
            if is_pilot {
                out.pilot_hits.push(PilotHit {
                    pilot: i,
                    met: Met::Light,
                    instance: u32::MAX,
                    delta_p: DELTA_P,
                });
            }
            let mut old_s = fresh.clone();
            if let Some((old_path, _)) = emit(&epoch.lights, &epoch.cells, &mut old_s) {
                self.branch(
                    world,
                    Some((union, &epoch.materials)),
                    old_path,
                    &mut old_s,
                    OLD,
                    -1,
                    out,
                );
            }
            let mut visible = false;
            if let Some((path, _)) = now {
                visible = self.branch(
                    world,
                    Some((union, &epoch.materials)),
                    path,
                    &mut s,
                    NEW,
                    1,
                    out,
                );
            }
            if is_pilot {
                out.pilots.push((i, visible));
            }
            return;
        }
        let Some((path, _)) = now else {
            return;
        };
        let (mut visible, fork) = self.shared_prefix(union, path, &mut s, is_pilot, out);
        if let Some(Fork {
            at,
            met,
            instance,
            delta_p,
        }) = fork
        {
            out.invalid += 1;
            if is_pilot {
                out.pilot_hits.push(PilotHit {
                    pilot: i,
                    met,
                    instance,
                    delta_p,
                });
            }
            let mut old_s = s.clone();
            self.branch(
                world,
                Some((union, &epoch.materials)),
                at,
                &mut old_s,
                OLD,
                -1,
                out,
            );
            visible |= self.branch(
                world,
                Some((union, &epoch.materials)),
                at,
                &mut s,
                NEW,
                1,
                out,
            );
        }
        if is_pilot {
            out.pilots.push((i, visible));
        }
    }

    /// The photon's path shared by the old and the new world, traced once in the union
    /// (counting rays into `out`): whether it fell in the view frustum, and where it
    /// first meets a change, if it does.
    fn shared_prefix(
        &self,
        union: &UnionWorld,
        mut path: PhotonPath,
        s: &mut HaltonStream<'_>,
        is_pilot: bool,
        out: &mut TraceOutput,
    ) -> (bool, Option<Fork>) {
        let world = &union.world;
        let mut visible = false;
        let mut fork = None;
        world.tracer.scoped(|tracer| {
            while path.alive(&self.path) {
                out.rays += 1;
                let Some(hit) = path.trace(world, tracer, OLD | NEW, &self.path) else {
                    break;
                };
                if union.meets_change(&hit) {
                    let u = hit.instance.index();
                    let met = if union.phantom[u] {
                        Met::Phantom
                    } else if union.changed_instance[u] {
                        Met::Moved
                    } else {
                        Met::Material
                    };
                    let delta_p = if is_pilot {
                        self.masking.increment(&world.scene, &hit, &self.view)
                    } else {
                        DELTA_P
                    };
                    fork = Some(Fork {
                        at: path,
                        met,
                        instance: union.original[u],
                        delta_p,
                    });
                    break;
                }
                if !hit.reflects {
                    break;
                }
                visible |= self.frustum.contains(hit.position);
                let (_, continues) = path.scatter(hit, s, &self.path);
                if !continues {
                    break;
                }
            }
        });
        (visible, fork)
    }
}
