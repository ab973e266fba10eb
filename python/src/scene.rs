//! `illume.Scene`: a loaded scene, listed and edited.

use crate::edit::Edit;
use crate::{caught, detached, value_error};
use glam::{Affine3A, Mat4, Vec3};
use numpy::{IntoPyArray, PyArray2, ndarray::Array2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// A scene: a file (`.gltf`, `.glb`, `.obj`, `.ply`) or `builtin:NAME`, loaded with the
/// options of `illume render` (`--units`, `--strict`, `--spot-from-above`, `--animation`,
/// `--time`, `--look-from`/`--look-at`, `--sky`, `--envmap`).
#[pyclass(module = "illume._illume")]
#[derive(Clone)]
pub struct Scene {
    pub(crate) inner: illume_scene::Scene,
}

/// The options of [`load`], as `illume render` takes them.
pub(crate) struct LoadArgs {
    pub units: String,
    pub strict: bool,
    pub spot_from_above: bool,
    pub animation: Option<String>,
    pub time: f64,
    pub look_from: Option<[f32; 3]>,
    pub look_at: Option<[f32; 3]>,
    pub sky: Option<[f32; 3]>,
    pub envmap: Option<PathBuf>,
    pub envmap_scale: f32,
    pub envmap_rotation: f32,
}

impl Default for LoadArgs {
    fn default() -> Self {
        Self {
            units: "radiometric".into(),
            strict: false,
            spot_from_above: false,
            animation: None,
            time: 0.0,
            look_from: None,
            look_at: None,
            sky: None,
            envmap: None,
            envmap_scale: 1.0,
            envmap_rotation: 0.0,
        }
    }
}

/// Loads `path` as `illume render PATH` with `args` would; errors are the CLI's,
/// prefixed with the option they concern.
pub(crate) fn load(path: &str, args: &LoadArgs) -> PyResult<illume_scene::Scene> {
    let units = match args.units.as_str() {
        "radiometric" => illume_scene::Units::Radiometric,
        "photometric" => illume_scene::Units::Photometric,
        other => {
            return Err(value_error(format!(
                "units='{other}': expected 'radiometric' or 'photometric'"
            )));
        }
    };
    if !args.time.is_finite() {
        return Err(value_error(format!(
            "time={}: not a finite number",
            args.time
        )));
    }
    let options = illume_scene::LoadOptions {
        strict: args.strict,
        units,
        ..Default::default()
    };
    let mut scene =
        illume_scene::load_scene_with(std::path::Path::new(path), &options).map_err(value_error)?;
    if args.spot_from_above {
        scene = illume_scene::builtin::spot_from_above(scene);
    }
    if let Some(name) = &args.animation {
        scene
            .select_animation(name)
            .map_err(|m| value_error(format!("animation='{name}': {m}")))?;
    }
    scene.set_time(args.time);
    match (args.look_from, args.look_at) {
        (Some(eye), Some(target)) => {
            illume_scene::builtin::look_from(&mut scene, Vec3::from(eye), Vec3::from(target))
                .map_err(|m| value_error(format!("look_from/look_at: {m}")))?
        }
        (None, None) => {}
        _ => return Err(value_error("look_from and look_at go together")),
    }
    if let Some(radiance) = args.sky {
        let radiance = Vec3::from(radiance);
        if !radiance.is_finite() || radiance.min_element() < 0.0 {
            return Err(value_error(format!(
                "sky={radiance}: each channel must be finite and ≥ 0"
            )));
        }
        scene.sky = Some(illume_scene::Sky::Uniform { radiance });
    }
    if let Some(file) = &args.envmap {
        if args.sky.is_some() {
            return Err(value_error("sky and envmap exclude each other"));
        }
        scene.sky = Some(
            illume_scene::load_envmap(file, args.envmap_scale, args.envmap_rotation)
                .map_err(value_error)?,
        );
    }
    Ok(scene)
}

/// `m` as a 4×4 row-major NumPy matrix (column vectors: `p' = M @ [p, 1]`).
pub(crate) fn matrix<'py>(py: Python<'py>, m: &Affine3A) -> Bound<'py, PyArray2<f32>> {
    let cols = Mat4::from(*m).to_cols_array_2d();
    Array2::from_shape_fn((4, 4), |(r, c)| cols[c][r]).into_pyarray(py)
}

/// `c` as a tuple of three floats.
fn rgb(c: Vec3) -> (f32, f32, f32) {
    (c.x, c.y, c.z)
}

/// The instances of `scene` as dicts.
pub(crate) fn instances<'py>(
    py: Python<'py>,
    scene: &illume_scene::Scene,
) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for (i, x) in scene.instances.iter().enumerate() {
        let d = PyDict::new(py);
        d.set_item("index", i)?;
        d.set_item("name", &x.name)?;
        d.set_item("mesh", &scene.meshes[x.mesh.index()].name)?;
        d.set_item("dynamic", x.dynamic)?;
        d.set_item("translation", rgb(x.world_from_object.translation.into()))?;
        d.set_item("transform", matrix(py, &x.world_from_object))?;
        list.append(d)?;
    }
    Ok(list)
}

/// The analytic lights of `scene` as dicts.
pub(crate) fn lights<'py>(
    py: Python<'py>,
    scene: &illume_scene::Scene,
) -> PyResult<Bound<'py, PyList>> {
    use illume_scene::LightKind;
    let list = PyList::empty(py);
    for (i, l) in scene.lights.iter().enumerate() {
        let d = PyDict::new(py);
        d.set_item("index", i)?;
        d.set_item("name", &l.name)?;
        let (kind, value) = match l.kind {
            LightKind::Point { intensity } => ("point", intensity),
            LightKind::Spot { intensity, .. } => ("spot", intensity),
            LightKind::Directional { irradiance } => ("directional", irradiance),
        };
        d.set_item("kind", kind)?;
        d.set_item("intensity", rgb(value))?;
        d.set_item("position", rgb(l.position()))?;
        d.set_item("direction", rgb(l.direction()))?;
        d.set_item("transform", matrix(py, &l.world_from_light))?;
        list.append(d)?;
    }
    Ok(list)
}

/// The materials of `scene` as dicts.
pub(crate) fn materials<'py>(
    py: Python<'py>,
    scene: &illume_scene::Scene,
) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for (i, m) in scene.materials.iter().enumerate() {
        let d = PyDict::new(py);
        d.set_item("index", i)?;
        d.set_item("name", &m.name)?;
        d.set_item("base_color", rgb(m.base_color))?;
        d.set_item("emission", rgb(m.emission))?;
        d.set_item("metallic", m.metallic)?;
        d.set_item("roughness", m.roughness)?;
        d.set_item("textured", m.base_color_texture.is_some())?;
        list.append(d)?;
    }
    Ok(list)
}

/// The camera of `scene` as a dict.
pub(crate) fn camera<'py>(
    py: Python<'py>,
    scene: &illume_scene::Scene,
) -> PyResult<Bound<'py, PyDict>> {
    let c = &scene.camera;
    let d = PyDict::new(py);
    d.set_item("name", &c.name)?;
    d.set_item("yfov_deg", c.yfov_rad.to_degrees())?;
    d.set_item("position", rgb(c.world_from_camera.translation.into()))?;
    d.set_item("transform", matrix(py, &c.world_from_camera))?;
    Ok(d)
}

#[pymethods]
impl Scene {
    /// Loads a scene file or `builtin:NAME` (`builtin:furnace`, `builtin:cornell-spot`,
    /// …). The keyword options are `illume render`'s: `units` ("radiometric" or
    /// "photometric"), `strict`, `spot_from_above`, `animation`, `time` [s],
    /// `look_from`/`look_at` (x, y, z) [m], `sky` (r, g, b) [W/(m²·sr)], `envmap` (a
    /// file) with `envmap_scale` and `envmap_rotation` [degrees]. Raises ValueError
    /// naming the file and what is wrong.
    #[new]
    #[pyo3(signature = (path, *, units="radiometric", strict=false, spot_from_above=false,
        animation=None, time=0.0, look_from=None, look_at=None, sky=None, envmap=None,
        envmap_scale=1.0, envmap_rotation=0.0))]
    #[expect(clippy::too_many_arguments, reason = "Python keyword arguments")]
    fn new(
        py: Python<'_>,
        path: PathBuf,
        units: &str,
        strict: bool,
        spot_from_above: bool,
        animation: Option<String>,
        time: f64,
        look_from: Option<[f32; 3]>,
        look_at: Option<[f32; 3]>,
        sky: Option<[f32; 3]>,
        envmap: Option<PathBuf>,
        envmap_scale: f32,
        envmap_rotation: f32,
    ) -> PyResult<Self> {
        let args = LoadArgs {
            units: units.to_owned(),
            strict,
            spot_from_above,
            animation,
            time,
            look_from,
            look_at,
            sky,
            envmap,
            envmap_scale,
            envmap_rotation,
        };
        let path = path.to_string_lossy().into_owned();
        let inner = detached(py, || load(&path, &args))?;
        Ok(Self { inner })
    }

    /// Where the scene came from (`builtin:furnace`, a file path).
    #[getter]
    fn source(&self) -> String {
        self.inner.source.clone()
    }

    /// The scene time [s].
    #[getter]
    fn time(&self) -> f64 {
        self.inner.time
    }

    /// The loader's warnings (missing textures, …).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }

    /// The instances: dicts with `index`, `name`, `mesh`, `dynamic`, `translation` and
    /// `transform` (4×4 world-from-object).
    fn instances<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        instances(py, &self.inner)
    }

    /// The analytic lights: dicts with `index`, `name`, `kind`, `intensity` (W/sr, or
    /// W/m² for a directional light), `position`, `direction` and `transform`.
    fn lights<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        lights(py, &self.inner)
    }

    /// The materials: dicts with `index`, `name`, `base_color`, `emission`, `metallic`,
    /// `roughness` and `textured`.
    fn materials<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        materials(py, &self.inner)
    }

    /// The camera: a dict with `name`, `yfov_deg`, `position` and `transform`.
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera(py, &self.inner)
    }

    /// Applies `edit` to this scene (an engine built from it afterwards starts from the
    /// edited state). Returns the changes, as strings. Raises ValueError when the edit
    /// names an item that does not exist or has a bad value.
    fn apply(&mut self, edit: &Edit) -> PyResult<Vec<String>> {
        caught(|| {
            let resolved = edit.resolve(&self.inner)?;
            let changes = self.inner.apply_edit(&resolved).map_err(value_error)?;
            Ok(changes.iter().map(crate::edit::describe).collect())
        })
    }

    /// An independent copy.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene('{}', {} instances, {} lights, {} materials, time {} s)",
            self.inner.source,
            self.inner.instances.len(),
            self.inner.lights.len(),
            self.inner.materials.len(),
            self.inner.time
        )
    }
}
