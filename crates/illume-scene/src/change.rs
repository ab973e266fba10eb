//! Scene changes as data: evaluating the scene at a new time or applying an interactive
//! edit yields the list of what changed, with previous and new state, so each technique
//! can invalidate exactly what it must (DESIGN.md, "Changes and history are explicit").

use crate::animation::Trs;
use crate::model::*;
use illume_core::{Affine3A, affine_is_finite};

/// One change to the scene, with its previous and new state.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneChange {
    /// An instance's world transform changed (rigid or scaled motion).
    InstanceMoved {
        /// Which instance.
        instance: InstanceId,
        /// Transform before the change.
        from: Affine3A,
        /// Transform after the change.
        to: Affine3A,
    },
    /// A light moved or changed its emission.
    LightChanged {
        /// Which light.
        light: LightId,
        /// State before.
        from: Box<Light>,
        /// State after.
        to: Box<Light>,
    },
    /// The camera moved or changed its field of view.
    CameraMoved {
        /// Transform before.
        from: Affine3A,
        /// Transform after.
        to: Affine3A,
    },
    /// An instance was added (its id is the last one; ids of other instances stay).
    InstanceAdded {
        /// The new instance.
        instance: InstanceId,
    },
    /// An instance was removed. Its id stays allocated (ids of other instances do not
    /// shift) with mask 0, so no ray sees it and no light set counts it.
    InstanceRemoved {
        /// Which instance.
        instance: InstanceId,
        /// The instance as it was, with its mask and transform.
        from: Box<Instance>,
    },
    /// A material's parameters changed.
    MaterialChanged {
        /// Which material.
        material: MaterialId,
        /// State before.
        from: Box<Material>,
        /// State after.
        to: Box<Material>,
    },
}

/// An interactive edit a user (or a script) applies to the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Edit {
    /// Place an instance at a new world transform.
    SetInstanceTransform {
        /// Which instance.
        instance: InstanceId,
        /// New `world_from_object`.
        world_from_object: Affine3A,
    },
    /// Place a light at a new world transform.
    SetLightTransform {
        /// Which light.
        light: LightId,
        /// New `world_from_light`.
        world_from_light: Affine3A,
    },
    /// Change a light's kind or emission.
    SetLightKind {
        /// Which light.
        light: LightId,
        /// New kind and quantities.
        kind: LightKind,
    },
    /// Place the camera at a new world transform.
    SetCameraTransform {
        /// New `world_from_camera`.
        world_from_camera: Affine3A,
    },
    /// Set the camera's vertical field of view \[rad\], within (0, π).
    SetCameraFov {
        /// New vertical field of view \[rad\].
        yfov_rad: f32,
    },
    /// Replace a material's parameters.
    SetMaterial {
        /// Which material.
        material: MaterialId,
        /// New parameters.
        value: Material,
    },
    /// Place a new instance of an existing mesh (see [`Scene::add_mesh`]) under a new
    /// root node; it is dynamic and visible to [`MASK_DEFAULT`] rays.
    AddInstance {
        /// Name, for messages.
        name: String,
        /// The mesh it places.
        mesh: MeshId,
        /// Its `world_from_object`.
        world_from_object: Affine3A,
    },
    /// Remove an instance (see [`SceneChange::InstanceRemoved`]).
    RemoveInstance {
        /// Which instance.
        instance: InstanceId,
    },
}

/// Why an edit was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum EditError {
    /// The id does not name an existing item.
    #[error("{what} {index} does not exist")]
    NoSuchItem {
        /// Item kind.
        what: &'static str,
        /// The id given.
        index: u32,
    },
    /// A transform or value had NaN or infinity.
    #[error("{what}: value is not finite")]
    NotFinite {
        /// What was being set.
        what: &'static str,
    },
    /// The instance was removed before.
    #[error("instance {index} was removed")]
    Removed {
        /// The id given.
        index: u32,
    },
    /// A mesh handed to [`Scene::add_mesh`] breaks a mesh invariant.
    #[error("mesh '{name}': {reason}")]
    InvalidMesh {
        /// The mesh's name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// An item placed by an animated node's ancestor cannot be placed arbitrarily.
    #[error("{what}: parent transform is singular, cannot place a child")]
    SingularParent {
        /// What was being set.
        what: &'static str,
    },
}

/// `sky` with its radiance multiplied by `scale` (same angular distribution).
fn scaled_sky(sky: &Sky, scale: f32) -> Sky {
    match sky {
        Sky::Uniform { radiance } => Sky::Uniform {
            radiance: *radiance * scale,
        },
        // The texels are shared, only the factor changes.
        Sky::Equirect(map) => Sky::Equirect(std::sync::Arc::new(crate::EnvMap {
            scale: map.scale * scale,
            ..(**map).clone()
        })),
    }
}

/// Sets a light's radiometric quantity (intensity or irradiance) to `value`.
fn set_light_quantity(kind: &mut LightKind, value: illume_core::Rgb) {
    match kind {
        LightKind::Point { intensity } | LightKind::Spot { intensity, .. } => *intensity = value,
        LightKind::Directional { irradiance } => *irradiance = value,
    }
}

impl Scene {
    /// Recomputes every node's world transform from the local ones and refreshes the
    /// cached transforms of instances, lights and camera. Returns the changes.
    pub fn update_world_transforms(&mut self) -> Vec<SceneChange> {
        for i in 0..self.nodes.len() {
            let local = self.nodes[i].local.to_affine();
            self.nodes[i].world_from_node = match self.nodes[i].parent {
                Some(p) => self.nodes[p.index()].world_from_node * local,
                None => local,
            };
        }
        let mut changes = Vec::new();
        for (i, inst) in self.instances.iter_mut().enumerate() {
            let to = self.nodes[inst.node.index()].world_from_node;
            if to != inst.world_from_object {
                changes.push(SceneChange::InstanceMoved {
                    instance: InstanceId(i as u32),
                    from: inst.world_from_object,
                    to,
                });
                inst.world_from_object = to;
            }
        }
        for (i, light) in self.lights.iter_mut().enumerate() {
            let to = self.nodes[light.node.index()].world_from_node;
            if to != light.world_from_light {
                let before = light.clone();
                light.world_from_light = to;
                changes.push(SceneChange::LightChanged {
                    light: LightId(i as u32),
                    from: Box::new(before),
                    to: Box::new(light.clone()),
                });
            }
        }
        if let Some(node) = self.nodes.get(self.camera.node.index()) {
            let to = node.world_from_node;
            if to != self.camera.world_from_camera {
                changes.push(SceneChange::CameraMoved {
                    from: self.camera.world_from_camera,
                    to,
                });
                self.camera.world_from_camera = to;
            }
        }
        changes
    }

    /// Evaluates the active animation at time `t` \[s\] and returns what changed since the
    /// scene's previous state. Nodes not driven by the animation keep their transforms.
    pub fn set_time(&mut self, t: f64) -> Vec<SceneChange> {
        let mut changes = self.set_animation_time(t);
        self.apply_sun(&mut changes);
        changes
    }

    /// Binds a `[sun]` table to the directional light named `settings.light` (created,
    /// with its own root node, if the scene has no light of that name) and poses it at the
    /// scene's current time. Returns the light.
    pub fn attach_sun(
        &mut self,
        settings: crate::sun::SunSettings,
    ) -> Result<LightId, crate::sun::SunError> {
        settings.validate()?;
        let existing = self.lights.iter().position(|l| l.name == settings.light);
        let light = match existing {
            Some(i) => {
                if !matches!(self.lights[i].kind, LightKind::Directional { .. }) {
                    return Err(crate::sun::SunError::NotDirectional(settings.light.clone()));
                }
                // The sun sets the node's rotation in world space: give it a root node.
                let node = NodeId(self.nodes.len() as u32);
                let old = self.lights[i].node;
                let translation = self
                    .nodes
                    .get(old.index())
                    .map(|n| n.world_from_node.translation.into())
                    .unwrap_or(glam::Vec3::ZERO);
                self.nodes.push(Node {
                    name: format!("{} (sun path)", settings.light),
                    parent: None,
                    local: Trs {
                        translation,
                        ..Trs::IDENTITY
                    },
                    world_from_node: glam::Affine3A::from_translation(translation),
                });
                self.lights[i].node = node;
                LightId(i as u32)
            }
            None => {
                let node = NodeId(self.nodes.len() as u32);
                self.nodes.push(Node {
                    name: settings.light.clone(),
                    parent: None,
                    local: Trs::IDENTITY,
                    world_from_node: glam::Affine3A::IDENTITY,
                });
                self.lights.push(Light {
                    name: settings.light.clone(),
                    kind: LightKind::Directional {
                        irradiance: illume_core::Rgb::ZERO,
                    },
                    node,
                    world_from_light: glam::Affine3A::IDENTITY,
                });
                LightId(self.lights.len() as u32 - 1)
            }
        };
        self.sun = Some(SunPath {
            settings,
            light,
            sky_base: self.sky.clone(),
        });
        let mut ignored = Vec::new();
        self.apply_sun(&mut ignored);
        Ok(light)
    }

    /// Replaces the sky (`--sky`, `--envmap`). With a sun path it is the sky at scale 1,
    /// which the sun scales with the time of day — what a `.illumepc` file's scene
    /// fingerprint holds — so a sky given on the command line is seen, and a precompute
    /// and a render given the same one agree (issue 38). Without a sun it is the sky.
    pub fn replace_sky(&mut self, sky: Sky) {
        match &mut self.sun {
            Some(sun) => {
                sun.sky_base = Some(sky);
                let mut ignored = Vec::new();
                self.apply_sun(&mut ignored);
            }
            None => self.sky = Some(sky),
        }
    }

    /// Poses the sun's light for the current time (if the scene has a sun), merging its
    /// change into `changes` as one `LightChanged` from the state before.
    fn apply_sun(&mut self, changes: &mut Vec<SceneChange>) {
        let Some(sun) = &self.sun else {
            return;
        };
        // A table that passed `attach_sun` always evaluates.
        let Ok(state) = crate::sun::evaluate(&sun.settings, self.time) else {
            return;
        };
        let id = sun.light;
        self.sky = sun
            .sky_base
            .as_ref()
            .map(|sky| scaled_sky(sky, state.sky_scale));
        let Some(light) = self.lights.get(id.index()) else {
            return;
        };
        let before = light.clone();
        let node = light.node.index();
        self.nodes[node].local.rotation = state.rotation;
        self.nodes[node].world_from_node = self.nodes[node].local.to_affine();
        let light = &mut self.lights[id.index()];
        light.world_from_light = self.nodes[node].world_from_node;
        set_light_quantity(&mut light.kind, state.irradiance);
        if *light == before {
            return;
        }
        let now = light.clone();
        let existing = changes.iter_mut().find_map(|c| match c {
            SceneChange::LightChanged { light: l, to, .. } if *l == id => Some(to),
            _ => None,
        });
        match existing {
            Some(to) => **to = now,
            None => changes.push(SceneChange::LightChanged {
                light: id,
                from: Box::new(before),
                to: Box::new(now),
            }),
        }
    }

    /// [`Scene::set_time`] without the sun: the active animation only.
    fn set_animation_time(&mut self, t: f64) -> Vec<SceneChange> {
        self.time = t;
        let Some(a) = self.active_animation else {
            return self.update_world_transforms();
        };
        let mut locals: Vec<Trs> = self.nodes.iter().map(|n| n.local).collect();
        self.animations[a].apply(t, &mut locals);
        for (n, l) in self.nodes.iter_mut().zip(locals) {
            n.local = l;
        }
        if self.animations[a].properties.is_empty() {
            return self.update_world_transforms();
        }
        let lights_before = self.lights.clone();
        let materials_before = self.materials.clone();
        let mut changes = self.update_world_transforms();
        self.apply_properties(a, t as f32);
        // One LightChanged per light, from its state before this call.
        for (i, before) in lights_before.into_iter().enumerate() {
            let now = &self.lights[i];
            if now.kind == before.kind {
                continue;
            }
            let light = LightId(i as u32);
            let existing = changes.iter_mut().find_map(|c| match c {
                SceneChange::LightChanged { light: l, from, to } if *l == light => Some((from, to)),
                _ => None,
            });
            match existing {
                Some((from, to)) => {
                    **from = before;
                    **to = now.clone();
                }
                None => changes.push(SceneChange::LightChanged {
                    light,
                    from: Box::new(before),
                    to: Box::new(now.clone()),
                }),
            }
        }
        for (i, before) in materials_before.into_iter().enumerate() {
            if self.materials[i] != before {
                changes.push(SceneChange::MaterialChanged {
                    material: MaterialId(i as u32),
                    from: Box::new(before),
                    to: Box::new(self.materials[i].clone()),
                });
            }
        }
        changes
    }

    /// Writes animation `a`'s light and material values at time `t`.
    fn apply_properties(&mut self, a: usize, t: f32) {
        use crate::animation::PropertyTarget as P;
        for c in &self.animations[a].properties {
            let v = c.sample(t);
            let rgb = illume_core::Rgb::new(v.x, v.y, v.z).max(illume_core::Rgb::ZERO);
            match c.target {
                P::LightIntensity { light, colour } => {
                    set_light_quantity(&mut self.lights[light.index()].kind, colour * v.x.max(0.0))
                }
                P::LightColour { light, intensity } => {
                    set_light_quantity(&mut self.lights[light.index()].kind, rgb * intensity)
                }
                P::SpotInnerCone { light } => {
                    if let LightKind::Spot { inner_cone_rad, .. } =
                        &mut self.lights[light.index()].kind
                    {
                        *inner_cone_rad = v.x.clamp(0.0, std::f32::consts::FRAC_PI_2);
                    }
                }
                P::SpotOuterCone { light } => {
                    if let LightKind::Spot { outer_cone_rad, .. } =
                        &mut self.lights[light.index()].kind
                    {
                        *outer_cone_rad = v.x.clamp(0.0, std::f32::consts::FRAC_PI_2);
                    }
                }
                P::BaseColour { material } => {
                    self.materials[material.index()].base_color = rgb.min(illume_core::Rgb::ONE)
                }
                P::Emissive { material, strength } => {
                    self.materials[material.index()].emission = rgb * strength
                }
                P::Metallic { material } => {
                    self.materials[material.index()].metallic = v.x.clamp(0.0, 1.0)
                }
                P::Roughness { material } => {
                    self.materials[material.index()].roughness = v.x.clamp(0.0, 1.0)
                }
            }
        }
    }

    /// Selects the animation named `name` as the active one.
    pub fn select_animation(&mut self, name: &str) -> Result<(), String> {
        match self.animations.iter().position(|a| a.name == name) {
            Some(i) => {
                self.active_animation = Some(i);
                Ok(())
            }
            None => Err(format!(
                "{}: no animation named '{name}' (have: {})",
                self.source,
                self.animations
                    .iter()
                    .map(|a| a.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
        }
    }

    /// Applies an interactive edit and returns what changed. A placed item's node gets
    /// the local transform that puts it at the requested world transform.
    pub fn apply_edit(&mut self, edit: &Edit) -> Result<Vec<SceneChange>, EditError> {
        match edit {
            Edit::SetInstanceTransform {
                instance,
                world_from_object,
            } => {
                let node = self
                    .instances
                    .get(instance.index())
                    .ok_or(EditError::NoSuchItem {
                        what: "instance",
                        index: instance.0,
                    })?
                    .node;
                self.place_node(node, world_from_object, "instance transform")?;
                Ok(self.update_world_transforms())
            }
            Edit::SetLightTransform {
                light,
                world_from_light,
            } => {
                let node = self
                    .lights
                    .get(light.index())
                    .ok_or(EditError::NoSuchItem {
                        what: "light",
                        index: light.0,
                    })?
                    .node;
                self.place_node(node, world_from_light, "light transform")?;
                Ok(self.update_world_transforms())
            }
            Edit::SetCameraTransform { world_from_camera } => {
                let node = self.camera.node;
                self.place_node(node, world_from_camera, "camera transform")?;
                Ok(self.update_world_transforms())
            }
            Edit::SetCameraFov { yfov_rad } => {
                if !(yfov_rad.is_finite() && *yfov_rad > 0.0 && *yfov_rad < std::f32::consts::PI) {
                    return Err(EditError::NotFinite {
                        what: "camera field of view (must be within (0, π))",
                    });
                }
                if *yfov_rad == self.camera.yfov_rad {
                    return Ok(Vec::new());
                }
                self.camera.yfov_rad = *yfov_rad;
                let at = self.camera.world_from_camera;
                Ok(vec![SceneChange::CameraMoved { from: at, to: at }])
            }
            Edit::SetLightKind { light, kind } => {
                let l = self
                    .lights
                    .get_mut(light.index())
                    .ok_or(EditError::NoSuchItem {
                        what: "light",
                        index: light.0,
                    })?;
                let finite = match kind {
                    LightKind::Point { intensity } => intensity.is_finite(),
                    LightKind::Spot {
                        intensity,
                        inner_cone_rad,
                        outer_cone_rad,
                    } => {
                        intensity.is_finite()
                            && inner_cone_rad.is_finite()
                            && outer_cone_rad.is_finite()
                    }
                    LightKind::Directional { irradiance } => irradiance.is_finite(),
                };
                if !finite {
                    return Err(EditError::NotFinite { what: "light kind" });
                }
                let before = l.clone();
                l.kind = *kind;
                Ok(vec![SceneChange::LightChanged {
                    light: *light,
                    from: Box::new(before),
                    to: Box::new(l.clone()),
                }])
            }
            Edit::AddInstance {
                name,
                mesh,
                world_from_object,
            } => {
                if mesh.index() >= self.meshes.len() {
                    return Err(EditError::NoSuchItem {
                        what: "mesh",
                        index: mesh.0,
                    });
                }
                if !affine_is_finite(world_from_object) {
                    return Err(EditError::NotFinite {
                        what: "instance transform",
                    });
                }
                let node = NodeId(self.nodes.len() as u32);
                self.nodes.push(Node {
                    name: name.clone(),
                    parent: None,
                    local: Trs::from_affine(world_from_object),
                    world_from_node: *world_from_object,
                });
                let instance = InstanceId(self.instances.len() as u32);
                self.instances.push(Instance {
                    name: name.clone(),
                    mesh: *mesh,
                    node,
                    world_from_object: *world_from_object,
                    dynamic: true,
                    mask: MASK_DEFAULT,
                });
                let mut changes = vec![SceneChange::InstanceAdded { instance }];
                // The TRS round trip may move the node by rounding: report it as motion.
                changes.extend(self.update_world_transforms());
                Ok(changes)
            }
            Edit::RemoveInstance { instance } => {
                let inst =
                    self.instances
                        .get_mut(instance.index())
                        .ok_or(EditError::NoSuchItem {
                            what: "instance",
                            index: instance.0,
                        })?;
                if inst.mask == 0 {
                    return Err(EditError::Removed { index: instance.0 });
                }
                let from = Box::new(inst.clone());
                inst.mask = 0;
                Ok(vec![SceneChange::InstanceRemoved {
                    instance: *instance,
                    from,
                }])
            }
            Edit::SetMaterial { material, value } => {
                let m = self
                    .materials
                    .get_mut(material.index())
                    .ok_or(EditError::NoSuchItem {
                        what: "material",
                        index: material.0,
                    })?;
                if !value.base_color.is_finite() || !value.emission.is_finite() {
                    return Err(EditError::NotFinite { what: "material" });
                }
                let before = std::mem::replace(m, value.clone());
                Ok(vec![SceneChange::MaterialChanged {
                    material: *material,
                    from: Box::new(before),
                    to: Box::new(value.clone()),
                }])
            }
        }
    }

    /// Adds a mesh (object space) for [`Edit::AddInstance`] to place; the mesh is
    /// checked first ([`Mesh::validate`]). Adding a mesh changes nothing visible, so
    /// there is no scene change for it.
    pub fn add_mesh(&mut self, mesh: Mesh) -> Result<MeshId, EditError> {
        mesh.validate(self.materials.len())
            .map_err(|reason| EditError::InvalidMesh {
                name: mesh.name.clone(),
                reason,
            })?;
        self.meshes.push(std::sync::Arc::new(mesh));
        Ok(MeshId(self.meshes.len() as u32 - 1))
    }

    fn place_node(
        &mut self,
        node: NodeId,
        world: &Affine3A,
        what: &'static str,
    ) -> Result<(), EditError> {
        if !affine_is_finite(world) {
            return Err(EditError::NotFinite { what });
        }
        let local = match self.nodes[node.index()].parent {
            Some(p) => {
                let parent = self.nodes[p.index()].world_from_node;
                if parent.matrix3.determinant().abs() < 1e-12 {
                    return Err(EditError::SingularParent { what });
                }
                parent.inverse() * *world
            }
            None => *world,
        };
        self.nodes[node.index()].local = Trs::from_affine(&local);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::Vec3;

    #[test]
    fn time_change_reports_moved_instance_with_previous_transform() {
        let mut s = crate::builtin::load("cornell-spot").unwrap();
        s.set_time(0.0);
        let before: Vec<_> = s.instances.iter().map(|i| i.world_from_object).collect();
        let changes = s.set_time(1.0);
        let moved: Vec<_> = changes
            .iter()
            .filter_map(|c| match c {
                SceneChange::InstanceMoved { instance, from, to } => Some((*instance, *from, *to)),
                _ => None,
            })
            .collect();
        assert!(!moved.is_empty(), "the sphere must move");
        for (id, from, to) in moved {
            assert_eq!(from, before[id.index()]);
            assert_eq!(to, s.instances[id.index()].world_from_object);
            assert_ne!(from, to);
        }
        assert!(
            changes
                .iter()
                .any(|c| matches!(c, SceneChange::LightChanged { .. })),
            "the spot light must move"
        );
        // Same time again: nothing changes.
        assert!(s.set_time(1.0).is_empty());
    }

    #[test]
    fn fov_edit_is_a_camera_change_and_refuses_nonsense() {
        let mut s = crate::builtin::load("cornell-spot").unwrap();
        let ch = s.apply_edit(&Edit::SetCameraFov { yfov_rad: 0.5 }).unwrap();
        assert!(matches!(ch[..], [SceneChange::CameraMoved { .. }]));
        assert_eq!(s.camera.yfov_rad, 0.5);
        for bad in [f32::NAN, 0.0, 4.0] {
            assert!(s.apply_edit(&Edit::SetCameraFov { yfov_rad: bad }).is_err());
        }
        assert_eq!(s.camera.yfov_rad, 0.5);
    }

    #[test]
    fn edit_moves_instance_and_rejects_nan() {
        let mut s = crate::builtin::load("cornell-spot").unwrap();
        let target = Affine3A::from_translation(Vec3::new(0.1, 0.2, 0.3));
        let ch = s
            .apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(0),
                world_from_object: target,
            })
            .unwrap();
        assert_eq!(ch.len(), 1);
        assert!(
            (s.instances[0].world_from_object.translation - target.translation).length() < 1e-6
        );
        let bad = Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
        assert_eq!(
            s.apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(0),
                world_from_object: bad
            }),
            Err(EditError::NotFinite {
                what: "instance transform"
            })
        );
        assert!(
            s.apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(999),
                world_from_object: target
            })
            .is_err()
        );
    }

    #[test]
    fn material_edit_reports_previous_value() {
        let mut s = crate::builtin::load("furnace").unwrap();
        let mut m = s.materials[0].clone();
        let old = m.clone();
        m.base_color = Vec3::new(0.1, 0.2, 0.3);
        let ch = s
            .apply_edit(&Edit::SetMaterial {
                material: MaterialId(0),
                value: m.clone(),
            })
            .unwrap();
        assert_eq!(
            ch,
            vec![SceneChange::MaterialChanged {
                material: MaterialId(0),
                from: Box::new(old),
                to: Box::new(m)
            }]
        );
    }

    #[test]
    fn instances_are_added_and_removed_with_stable_ids() {
        let mut s = crate::builtin::load("cornell-spot").unwrap();
        let n = s.instances.len();
        let mesh = s
            .add_mesh(Mesh {
                name: "tri".into(),
                positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
                indices: vec![[0, 1, 2]],
                triangle_materials: vec![MaterialId(0)],
                ..Default::default()
            })
            .unwrap();
        let at = Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0));
        let ch = s
            .apply_edit(&Edit::AddInstance {
                name: "new".into(),
                mesh,
                world_from_object: at,
            })
            .unwrap();
        let id = InstanceId(n as u32);
        assert_eq!(ch[0], SceneChange::InstanceAdded { instance: id });
        assert_eq!(s.instances[n].world_from_object, at);
        assert_eq!(s.instances[n].mask, MASK_DEFAULT);
        // It stays where it was put when time moves on.
        s.set_time(0.5);
        assert_eq!(s.instances[n].world_from_object, at);
        let ch = s
            .apply_edit(&Edit::RemoveInstance { instance: id })
            .unwrap();
        assert!(
            matches!(&ch[..], [SceneChange::InstanceRemoved { instance, from }]
            if *instance == id && from.mask == MASK_DEFAULT)
        );
        assert_eq!(s.instances.len(), n + 1, "ids do not shift");
        assert_eq!(s.instances[n].mask, 0);
        assert_eq!(
            s.apply_edit(&Edit::RemoveInstance { instance: id }),
            Err(EditError::Removed { index: id.0 })
        );
        // Bad input is refused and changes nothing.
        let bad = Affine3A::from_translation(Vec3::new(f32::INFINITY, 0.0, 0.0));
        let count = s.instances.len();
        assert!(
            s.apply_edit(&Edit::AddInstance {
                name: "x".into(),
                mesh,
                world_from_object: bad,
            })
            .is_err()
        );
        assert!(
            s.apply_edit(&Edit::AddInstance {
                name: "x".into(),
                mesh: MeshId(999),
                world_from_object: at,
            })
            .is_err()
        );
        assert_eq!(s.instances.len(), count);
        let broken = Mesh {
            name: "broken".into(),
            positions: vec![Vec3::ZERO],
            indices: vec![[0, 1, 2]],
            triangle_materials: vec![MaterialId(0)],
            ..Default::default()
        };
        assert!(matches!(
            s.add_mesh(broken),
            Err(EditError::InvalidMesh { ref name, .. }) if name == "broken"
        ));
    }
}
