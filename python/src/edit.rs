//! `illume.Edit`: a change to a scene by name, resolved into the engine's
//! `illume_scene::Edit` against the scene it is applied to.

use crate::value_error;
use glam::Vec3;
use illume_bench::EditSpec;
use illume_scene::{LightId, LightKind, SceneChange};
use pyo3::prelude::*;

/// What an [`Edit`] does, before it meets a scene.
#[derive(Clone, Debug)]
enum Spec {
    /// Place an instance or light, or recolour a material: a bench scenario's `[[edit]]`
    /// entry, resolved and checked by the bench's own code.
    Scripted(EditSpec),
    /// Set a light's intensity (W/sr; W/m² for a directional light).
    LightIntensity { light: String, value: [f32; 3] },
    /// Place the camera at `eye` looking at `target`.
    LookFrom { eye: [f32; 3], target: [f32; 3] },
    /// Set the camera's vertical field of view \[degrees\].
    Fov { degrees: f32 },
}

/// A scene edit by name: build one with `Edit.move_instance`, `Edit.move_light`,
/// `Edit.set_material`, `Edit.set_light_intensity`, `Edit.look_from` or
/// `Edit.set_fov`, then `scene.apply(edit)` or `engine.apply(edit)`. An engine hands it
/// to its technique as the engine's own `Edit`, like the window's edits and a bench
/// scenario's.
#[pyclass(module = "illume._illume", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct Edit {
    spec: Spec,
}

/// `v` as a finite RGB triple, or a ValueError naming `what`.
fn finite3(what: &str, v: [f32; 3]) -> PyResult<[f32; 3]> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(value_error(format!("{what}={v:?}: not finite")))
    }
}

/// A bench `[[edit]]` entry as an [`Edit`], checked by the bench's rules.
fn scripted(spec: EditSpec) -> PyResult<Edit> {
    spec.validate()
        .map_err(|m| value_error(format!("edit of {}: {m}", spec.target())))?;
    Ok(Edit {
        spec: Spec::Scripted(spec),
    })
}

/// An intensity given as one number (grey) or three.
#[derive(FromPyObject)]
pub(crate) enum Colour {
    /// Grey.
    Grey(f32),
    /// Red, green, blue.
    Rgb([f32; 3]),
}

impl Colour {
    fn rgb(&self) -> [f32; 3] {
        match *self {
            Colour::Grey(v) => [v; 3],
            Colour::Rgb(v) => v,
        }
    }
}

#[pymethods]
impl Edit {
    /// Places the instance named `name`: a new world `translation` (x, y, z) [m] and/or
    /// `rotation_deg` (about X, Y, Z, R = Rx·Ry·Rz); what is not given keeps its value.
    #[staticmethod]
    #[pyo3(signature = (name, translation=None, rotation_deg=None))]
    fn move_instance(
        name: String,
        translation: Option<[f32; 3]>,
        rotation_deg: Option<[f32; 3]>,
    ) -> PyResult<Self> {
        scripted(EditSpec {
            instance: Some(name),
            translation,
            rotation_deg,
            ..Default::default()
        })
    }

    /// Places the light named `name` (see `move_instance`).
    #[staticmethod]
    #[pyo3(signature = (name, translation=None, rotation_deg=None))]
    fn move_light(
        name: String,
        translation: Option<[f32; 3]>,
        rotation_deg: Option<[f32; 3]>,
    ) -> PyResult<Self> {
        scripted(EditSpec {
            light: Some(name),
            translation,
            rotation_deg,
            ..Default::default()
        })
    }

    /// Sets the material named `name`'s diffuse `base_color` (linear RGB in [0, 1])
    /// and/or its `emission` [W/(m²·sr)].
    #[staticmethod]
    #[pyo3(signature = (name, base_color=None, emission=None))]
    fn set_material(
        name: String,
        base_color: Option<[f32; 3]>,
        emission: Option<[f32; 3]>,
    ) -> PyResult<Self> {
        scripted(EditSpec {
            material: Some(name),
            base_color,
            emission,
            ..Default::default()
        })
    }

    /// Sets the light named `name`'s intensity: one number (grey) or (r, g, b), in W/sr
    /// (W/m² for a directional light), each finite and ≥ 0.
    #[staticmethod]
    fn set_light_intensity(name: String, intensity: Colour) -> PyResult<Self> {
        let value = finite3("intensity", intensity.rgb())?;
        if value.iter().any(|&x| x < 0.0) {
            return Err(value_error(format!("intensity={value:?}: must be ≥ 0")));
        }
        Ok(Self {
            spec: Spec::LightIntensity { light: name, value },
        })
    }

    /// Places the camera at `eye` (x, y, z) [m] looking at `target`, +Y up (as
    /// `--look-from`/`--look-at`).
    #[staticmethod]
    fn look_from(eye: [f32; 3], target: [f32; 3]) -> PyResult<Self> {
        Ok(Self {
            spec: Spec::LookFrom {
                eye: finite3("eye", eye)?,
                target: finite3("target", target)?,
            },
        })
    }

    /// Sets the camera's vertical field of view [degrees], within (0, 180).
    #[staticmethod]
    fn set_fov(degrees: f32) -> PyResult<Self> {
        if !(degrees > 0.0 && degrees < 180.0) {
            return Err(value_error(format!(
                "degrees={degrees}: the field of view must lie within (0, 180)"
            )));
        }
        Ok(Self {
            spec: Spec::Fov { degrees },
        })
    }

    fn __repr__(&self) -> String {
        format!("Edit({:?})", self.spec)
    }
}

impl Edit {
    /// The engine's edit this makes on `scene` in its current state. Raises ValueError
    /// naming an item that does not exist (with the names there are).
    pub(crate) fn resolve(&self, scene: &illume_scene::Scene) -> PyResult<illume_scene::Edit> {
        match &self.spec {
            Spec::Scripted(spec) => spec.resolve(scene).map_err(value_error),
            Spec::LightIntensity { light, value } => {
                let Some(i) = scene.lights.iter().position(|l| &l.name == light) else {
                    let have: Vec<&str> = scene.lights.iter().map(|l| l.name.as_str()).collect();
                    return Err(value_error(format!(
                        "no light named \"{light}\" (have: {})",
                        have.join(", ")
                    )));
                };
                let mut kind = scene.lights[i].kind;
                let v = Vec3::from(*value);
                match &mut kind {
                    LightKind::Point { intensity } | LightKind::Spot { intensity, .. } => {
                        *intensity = v
                    }
                    LightKind::Directional { irradiance } => *irradiance = v,
                }
                Ok(illume_scene::Edit::SetLightKind {
                    light: LightId(i as u32),
                    kind,
                })
            }
            Spec::LookFrom { eye, target } => {
                // `look_from` places the camera of a scene; a copy of this one shows
                // where, and the edit moves the camera there.
                let mut placed = scene.clone();
                illume_scene::builtin::look_from(
                    &mut placed,
                    Vec3::from(*eye),
                    Vec3::from(*target),
                )
                .map_err(|m| value_error(format!("look_from: {m}")))?;
                Ok(illume_scene::Edit::SetCameraTransform {
                    world_from_camera: placed.camera.world_from_camera,
                })
            }
            Spec::Fov { degrees } => Ok(illume_scene::Edit::SetCameraFov {
                yfov_rad: degrees.to_radians(),
            }),
        }
    }
}

/// A scene change as one line: what changed and its id.
pub(crate) fn describe(change: &SceneChange) -> String {
    match change {
        SceneChange::InstanceMoved { instance, .. } => format!("instance {} moved", instance.0),
        SceneChange::LightChanged { light, .. } => format!("light {} changed", light.0),
        SceneChange::CameraMoved { .. } => "camera moved".into(),
        SceneChange::InstanceAdded { instance } => format!("instance {} added", instance.0),
        SceneChange::InstanceRemoved { instance, .. } => {
            format!("instance {} removed", instance.0)
        }
        SceneChange::MaterialChanged { material, .. } => {
            format!("material {} changed", material.0)
        }
    }
}
