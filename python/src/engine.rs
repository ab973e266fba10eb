//! `illume.Engine` (one technique stepped frame by frame) and `illume.render` (one
//! still), configured as the CLI configures them.

use crate::edit::Edit;
use crate::images::to_array;
use crate::scene::{LoadArgs, Scene, load};
use crate::{Interrupted, detached, value_error};
use illume_core::Progress;
use illume_engine::{Config, ConfigLayers, TechniqueKind, read_world};
use illume_transport::Budget;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};
use std::sync::Mutex;

/// A Python settings value as TOML, or a ValueError naming `key`.
fn toml_value(key: &str, value: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        let v: i64 = value
            .extract()
            .map_err(|_| value_error(format!("{key}={value}: integer out of range")))?;
        return Ok(toml::Value::Integer(v));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract()?));
    }
    if let Ok(list) = value.cast::<PyList>() {
        let items: PyResult<Vec<_>> = list.iter().map(|v| toml_value(key, &v)).collect();
        return Ok(toml::Value::Array(items?));
    }
    if let Ok(tuple) = value.cast::<pyo3::types::PyTuple>() {
        let items: PyResult<Vec<_>> = tuple.iter().map(|v| toml_value(key, &v)).collect();
        return Ok(toml::Value::Array(items?));
    }
    let type_name = value.get_type().name()?;
    Err(value_error(format!(
        "{key}: a {type_name} is no setting value (expected bool, int, float, str or a list)"
    )))
}

/// A settings key: `KEY` is the technique's (`spp` → `reference.spp`), `TABLE.KEY` any
/// table's (`render.shadows`, `photon_stream.vsl_count`).
fn key_path(technique: TechniqueKind, key: &str) -> Vec<String> {
    if key.contains('.') {
        key.split('.').map(str::to_owned).collect()
    } else {
        vec![technique.name().to_owned(), key.to_owned()]
    }
}

/// What a configuration is made of, as Python gives it.
pub(crate) struct ConfigArgs<'a, 'py> {
    pub technique: &'a str,
    pub preset: Option<&'a str>,
    /// Used when no preset is given and the technique has one of this name (`render`
    /// asks for `still`, as `illume render` does).
    pub default_preset: Option<&'a str>,
    pub settings: Option<&'a Bound<'py, PyDict>>,
    pub width: u32,
    pub height: u32,
    pub seed: Option<u64>,
    pub spp: Option<u32>,
}

/// The configuration `args` give, layered as the CLI layers `--technique`, `--preset`,
/// `--set TABLE.KEY=VALUE` (one per setting, in order), `--width`/`--height`, `--spp`
/// and `--seed`; errors are the CLI's messages.
pub(crate) fn config(args: &ConfigArgs<'_, '_>) -> PyResult<Config> {
    let technique: TechniqueKind = args.technique.parse().map_err(value_error)?;
    let preset = args.preset.or_else(|| {
        args.default_preset
            .filter(|p| technique.preset_table(p).is_some())
    });
    let mut config = Config::layered(&ConfigLayers {
        technique: Some(technique),
        preset,
        ..Default::default()
    })
    .map_err(value_error)?;
    if let Some(settings) = args.settings {
        for (key, value) in settings.iter() {
            let key: String = key
                .extract()
                .map_err(|_| value_error(format!("settings key {key}: not a string")))?;
            let value = toml_value(&key, &value)?;
            let path = key_path(technique, &key);
            if path.iter().any(String::is_empty) {
                return Err(value_error(format!(
                    "settings key '{key}': empty part (expected KEY or TABLE.KEY)"
                )));
            }
            let argument = format!("{}={value}", path.join("."));
            config = config
                .with_value(&argument, &path, value)
                .map_err(value_error)?;
        }
    }
    config.render.width = args.width;
    config.render.height = args.height;
    illume_render::check_image_size(args.width, args.height)
        .map_err(|m| value_error(format!("width/height: {m}")))?;
    if let Some(spp) = args.spp {
        if spp == 0 {
            return Err(value_error("spp=0: at least 1 sample per pixel"));
        }
        if !config.technique_settings_mut().set_samples_per_pixel(spp) {
            return Err(value_error(format!(
                "spp={spp}: {technique} has no samples-per-pixel setting"
            )));
        }
    }
    if let Some(seed) = args.seed {
        config.set_seed(seed);
    }
    Ok(config)
}

/// A scene argument: a [`Scene`] (copied) or a path / `builtin:NAME` loaded with the
/// default options.
pub(crate) fn scene_arg(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<illume_scene::Scene> {
    if let Ok(s) = scene.cast::<Scene>() {
        return Ok(s.borrow().inner.clone());
    }
    let path: std::path::PathBuf = scene.extract().map_err(|_| {
        value_error("scene: expected an illume.Scene, a file path or 'builtin:NAME'")
    })?;
    let path = path.to_string_lossy().into_owned();
    detached(py, || load(&path, &LoadArgs::default()))
}

/// Progress reported to a Python callable `callback(what, done, total)`; each report
/// also checks for Ctrl-C. An exception (the callback's, or `KeyboardInterrupt`) unwinds
/// out of the engine's work as [`Interrupted`].
pub(crate) struct PyProgress {
    callback: Option<Py<PyAny>>,
    what: String,
    total: u64,
}

impl PyProgress {
    pub(crate) fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            what: String::new(),
            total: 0,
        }
    }

    fn report(&self, done: u64) {
        let result = Python::attach(|py| -> PyResult<()> {
            py.check_signals()?;
            if let Some(f) = &self.callback {
                f.call1(py, (self.what.as_str(), done, self.total))?;
            }
            Ok(())
        });
        if let Err(e) = result {
            std::panic::resume_unwind(Box::new(Interrupted(e)));
        }
    }
}

impl Progress for PyProgress {
    fn begin(&mut self, what: &str, total: u64) {
        self.what = what.to_owned();
        self.total = total;
        self.report(0);
    }
    fn set(&mut self, done: u64) {
        self.report(done);
    }
    fn end(&mut self) {
        self.report(self.total);
    }
    fn message(&mut self, _text: &str) {}
}

/// One still of `scene` with `technique`, as `illume render` makes it (the technique's
/// `still` preset unless `preset` is given; the reference path-traces the whole image
/// with `spp` samples per pixel). `scene` is an `illume.Scene`, a file or
/// `builtin:NAME`; `settings` maps `KEY` (the technique's) or `TABLE.KEY` to values.
/// Returns the radiance as float32 (height, width, 3); with `split=True` a dict of
/// `full`, `direct` and `indirect`. Ctrl-C (or an exception in `progress(what, done,
/// total)`) stops the render.
#[pyfunction]
#[pyo3(signature = (scene, technique="reference", spp=None, width=32, height=24, *,
    seed=None, preset=None, settings=None, split=false, progress=None))]
#[expect(clippy::too_many_arguments, reason = "Python keyword arguments")]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    technique: &str,
    spp: Option<u32>,
    width: u32,
    height: u32,
    seed: Option<u64>,
    preset: Option<&str>,
    settings: Option<&Bound<'py, PyDict>>,
    split: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let config = config(&ConfigArgs {
        technique,
        preset,
        default_preset: Some("still"),
        settings,
        width,
        height,
        seed,
        spp,
    })?;
    let scene = scene_arg(py, scene)?;
    let still = detached(py, move || {
        let mut progress = PyProgress::new(progress);
        illume_engine::render_still(scene, &config, &mut progress).map_err(value_error)
    })?;
    if split {
        let d = PyDict::new(py);
        d.set_item("full", to_array(py, &still.full))?;
        d.set_item("direct", to_array(py, &still.direct))?;
        d.set_item("indirect", to_array(py, &still.indirect))?;
        Ok(d.into_any())
    } else {
        Ok(to_array(py, &still.full).into_any())
    }
}

/// Every technique: a dict from its name to its summary, work unit and presets.
#[pyfunction]
pub fn techniques(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for &kind in TechniqueKind::ALL {
        let t = PyDict::new(py);
        t.set_item("summary", kind.summary())?;
        t.set_item("work_unit", kind.work_unit())?;
        let presets: Vec<&str> = kind.presets().iter().map(|(n, _)| *n).collect();
        t.set_item("presets", presets)?;
        d.set_item(kind.name(), t)?;
    }
    Ok(d)
}

/// A scene, a technique and a renderer, stepped frame by frame (`illume_engine::Engine`).
///
/// `Engine(scene, technique="photon_stream", *, settings=None, preset=None, width=64,
/// height=48, seed=None, work=None, time_ms=None)`: `scene` is an `illume.Scene`, a
/// file or `builtin:NAME`; `settings` maps `KEY` (the technique's table) or `TABLE.KEY`
/// to values, checked as `--set` checks them (ValueError naming the key); `work` and
/// `time_ms` replace the per-frame budget the settings give (work units of the
/// technique, wall-clock milliseconds).
#[pyclass(module = "illume._illume")]
pub struct Engine {
    engine: Mutex<illume_engine::Engine>,
    technique: &'static str,
    width: u32,
    height: u32,
}

impl Engine {
    /// Runs `f` on the engine with the GIL released; a panic inside is a RuntimeError,
    /// and one that left the engine half-updated makes later calls RuntimeErrors too.
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut illume_engine::Engine) -> PyResult<T> + Send,
    ) -> PyResult<T> {
        detached(py, || {
            let mut engine = self.engine.lock().map_err(|_| {
                PyRuntimeError::new_err(
                    "the engine stopped in an internal error or an interrupted precompute; build a new one",
                )
            })?;
            f(&mut engine)
        })
    }
}

#[pymethods]
impl Engine {
    #[new]
    #[pyo3(signature = (scene, technique="photon_stream", *, settings=None, preset=None,
        width=64, height=48, seed=None, work=None, time_ms=None))]
    #[expect(clippy::too_many_arguments, reason = "Python keyword arguments")]
    fn new(
        py: Python<'_>,
        scene: &Bound<'_, PyAny>,
        technique: &str,
        settings: Option<&Bound<'_, PyDict>>,
        preset: Option<&str>,
        width: u32,
        height: u32,
        seed: Option<u64>,
        work: Option<u64>,
        time_ms: Option<f64>,
    ) -> PyResult<Self> {
        let config = config(&ConfigArgs {
            technique,
            preset,
            default_preset: None,
            settings,
            width,
            height,
            seed,
            spp: None,
        })?;
        if let Some(ms) = time_ms
            && !(ms.is_finite() && ms > 0.0)
        {
            return Err(value_error(format!(
                "time_ms={ms}: must be a finite number > 0"
            )));
        }
        let scene = scene_arg(py, scene)?;
        let engine = detached(py, move || {
            let mut engine = illume_engine::Engine::new(scene, &config).map_err(value_error)?;
            if work.is_some() || time_ms.is_some() {
                engine.set_budget(Budget { work, time_ms });
            }
            Ok(engine)
        })?;
        Ok(Self {
            technique: engine.kind().name(),
            engine: Mutex::new(engine),
            width,
            height,
        })
    }

    /// The technique's name.
    #[getter]
    fn technique(&self) -> &'static str {
        self.technique
    }

    /// The image size (width, height) [pixels].
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Runs the technique's precompute now (else the first `step` does), reporting to
    /// `progress(what, done, total)`; returns its wall-clock time [ms] (0 when it already
    /// ran). Ctrl-C or an exception in `progress` stops it; the engine is then unusable.
    #[pyo3(signature = (progress=None))]
    fn precompute(&self, py: Python<'_>, progress: Option<Py<PyAny>>) -> PyResult<f64> {
        self.with(py, move |engine| {
            let mut progress = PyProgress::new(progress);
            engine.precompute(&mut progress).map_err(value_error)
        })
    }

    /// One frame: with `time` [s] the scene moves to that time first (animations
    /// play); without, it stays as it is, edits included. Returns `(image, counters)`:
    /// the radiance as float32 (height, width, 3) and the frame's counters (the
    /// technique's, `render.*`, and `engine.update_ms`, `engine.advance_ms`,
    /// `engine.precompute_ms`). With `split=True` the image is a dict of `full`,
    /// `direct` and `indirect`.
    #[pyo3(signature = (time=None, *, split=false))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        time: Option<f64>,
        split: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
        if let Some(t) = time
            && !t.is_finite()
        {
            return Err(value_error(format!("time={t}: not a finite number")));
        }
        let out = self.with(py, move |engine| {
            engine.set_split(split);
            match time {
                Some(t) => engine.step(t),
                None => engine.step_held(),
            }
            .map_err(value_error)
        })?;
        let counters = PyDict::new(py);
        for (name, value) in out.stats.iter() {
            counters.set_item(name, value)?;
        }
        counters.set_item("engine.update_ms", out.update_ms)?;
        counters.set_item("engine.advance_ms", out.advance_ms)?;
        counters.set_item("engine.precompute_ms", out.precompute_ms)?;
        if let Some(reason) = out.rebuilt {
            counters.set_item("engine.rebuilt", reason)?;
        }
        let image = if split {
            let d = PyDict::new(py);
            d.set_item("full", to_array(py, &out.frame.full))?;
            d.set_item("direct", to_array(py, &out.frame.direct))?;
            d.set_item("indirect", to_array(py, &out.frame.indirect))?;
            d.into_any()
        } else {
            to_array(py, &out.frame.full).into_any()
        };
        Ok((image, counters))
    }

    /// Applies `edit` now; the technique sees it as a change (and rebuilds if it must).
    /// Returns the changes, as strings. Raises ValueError when the edit names an item
    /// that does not exist or has a bad value (the scene is then unchanged).
    fn apply(&self, py: Python<'_>, edit: Edit) -> PyResult<Vec<String>> {
        self.with(py, move |engine| {
            let resolved = edit.resolve(&read_world(engine.world()).scene)?;
            let changes = engine.apply_edit(&resolved).map_err(value_error)?;
            Ok(changes.iter().map(crate::edit::describe).collect())
        })
    }

    /// The scene as the engine has it now (a copy).
    #[getter]
    fn scene(&self, py: Python<'_>) -> PyResult<Scene> {
        self.with(py, |engine| {
            Ok(Scene {
                inner: read_world(engine.world()).scene.clone(),
            })
        })
    }

    /// Sets the index the next frame renders as (it seeds the direct light's samples).
    fn set_frame_index(&self, py: Python<'_>, index: u64) -> PyResult<()> {
        self.with(py, move |engine| {
            engine.set_frame_index(index);
            Ok(())
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Engine(technique='{}', {}×{})",
            self.technique, self.width, self.height
        )
    }
}
