//! The scenario file: one TOML file names a scene, an animation or scripted edits, the
//! techniques with their settings and budgets, the frames, the converged reference and
//! the metrics. Unknown keys are errors that name the file and the key.
//!
//! ```toml
//! name = "cornell_spot_moving_sphere"
//! scene = "builtin:cornell-spot"
//! animation = "move_sphere"
//! width = 320
//! height = 240
//! duration_s = 2.5
//! fps = 8
//!
//! [reference]
//! spp = 256
//! equal_time = true
//!
//! [[technique]]
//! name = "reference"
//! samples = 1
//!
//! [[edit]]
//! at_s = 1.0
//! instance = "tall_box"
//! translation = [0.4, 0.6, -0.5]
//! ```

use crate::error::BenchError;
use illume_core::{Affine3A, Quat, Rgb, Vec3};
use illume_engine::{Config, TechniqueKind};
use illume_metrics::Metric;
use illume_scene::{Edit, InstanceId, LightId, MaterialId, Scene};
use illume_transport::Budget;
use std::path::{Path, PathBuf};

/// Most frames one run may have (a scenario with more is refused before anything is
/// rendered).
pub const MAX_FRAMES: usize = 1_000_000;

/// Largest `budget_ms` of a technique \[ms\]: an hour per frame.
pub const MAX_BUDGET_MS: f64 = 3_600_000.0;

/// Longest image side of a [`Scenario::miniature`] \[pixels\].
pub const MINIATURE_SIDE: u32 = 32;

/// Most samples per pixel of a [`Scenario::miniature`]'s converged references.
pub const MINIATURE_SPP: u32 = 4;

/// A benchmark scenario (one `.toml` file). Every field but `scene` and `[[technique]]`
/// has a default.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// The report's title and the default output folder `out/bench/<name>/`. Default: the
    /// scenario file's stem.
    pub name: String,
    /// One line printed under the report's title. Default empty.
    pub description: String,
    /// The scene: `builtin:NAME` or a scene file (`.gltf`, `.glb`, `.obj`, `.ply`).
    /// A relative path is resolved against the scenario file's folder; `${VAR}` is
    /// replaced by the environment variable `VAR` (e.g. `${ILLUME_SCENES}/cornell_box/…`
    /// with `ILLUME_SCENES=/work/shared/scenes`). Required.
    pub scene: String,
    /// The scene animation to play (e.g. `move_sphere`). Default: none — the scene stays
    /// as loaded, even if the file has animations.
    pub animation: Option<String>,
    /// Image width \[pixels\]. Default 320.
    pub width: u32,
    /// Image height \[pixels\]. Default 240.
    pub height: u32,
    /// Time of the first frame \[s\] with `duration_s` + `fps`. Default 0.
    pub start_s: f64,
    /// Length of the sequence \[s\]: frames at `start_s + i / fps` for
    /// `i = 0 .. round(duration_s × fps)`. Use with `fps`, or give `times_s` instead.
    /// Default: none.
    pub duration_s: Option<f64>,
    /// Frame rate of the sequence [frames/s]. Default: none.
    pub fps: Option<f64>,
    /// Explicit frame times \[s\], finite, ≥ 0 and strictly increasing. Alternative to
    /// `duration_s` + `fps`. Default: none.
    pub times_s: Option<Vec<f64>>,
    /// Image metrics measured on every frame against the converged reference
    /// (`rmse`, `relmse`, `psnr`, `ssim`, `flip`, `hdr-flip`). Default
    /// `["rmse", "relmse", "flip"]`.
    pub metrics: Vec<Metric>,
    /// The metric plotted against time and used for latency; added to `metrics` if
    /// missing. Must be one where lower is better. Default `flip`.
    pub error_metric: Metric,
    /// Latency threshold in units of `error_metric`, against the converged reference:
    /// after an event, the latency is the time until the error stays below this value up
    /// to the next event (or the last frame). Default 0.1.
    pub latency_threshold: f64,
    /// Latency threshold in units of `error_metric` against the technique's own
    /// converged images (`own_converged_frames`): the latency "to own steady state" is
    /// the time until that error stays below this value. A technique's bias keeps its
    /// error against the path tracer above some floor, so a threshold that is meaningful
    /// against its own steady state (e.g. FLIP 0.05) is usually lower than
    /// `latency_threshold`. Finite and > 0; only with `own_converged_frames` > 0.
    /// Default: `latency_threshold` (see [`Scenario::own_latency_threshold`]).
    pub own_latency_threshold: Option<f64>,
    /// Frame indices (0-based, into the frame times) measured against the converged
    /// reference, e.g. `[0, 10, 20]`: only these get a reference image and metrics, so
    /// long sequences stay affordable; other frames are rendered and timed but carry no
    /// error (empty cells, not zeros). Latency is judged on the measured frames. Default:
    /// every frame.
    pub reference_frames: Option<Vec<usize>>,
    /// A uniform sky of this radiance \[W/(m²·sr)\] (linear RGB), replacing the scene's
    /// (as `--sky` of `render`). Default: the scene's own.
    pub sky: Option<[f32; 3]>,
    /// A `[sun]` table (`illume_scene::sun::SunSettings`): a directional light posed by the
    /// solar position at each frame's time, its irradiance from the sun's elevation, and
    /// the sky scaled by it (for `precomputed` and any technique on a day of sun).
    /// Default: none (a scene's own `[sun]`, e.g. `builtin:sun-room`'s, stays).
    pub sun: Option<illume_scene::sun::SunSettings>,
    /// Relight the scene as the photon-streaming paper's measurements do
    /// ([`illume_scene::builtin::spot_from_above`], as `--spot-from-above` of `render`):
    /// its emitters switched off and one spot light near the top of its bounds shining
    /// straight down, e.g. for a model file without lights (Sibenik). Applied before
    /// `[sun]` and `[[sphere]]`. Default false.
    pub spot_from_above: bool,
    /// World position \[m\] of `spot_from_above`'s spot light (still shining straight
    /// down), e.g. under a vault that the default place near the top of the bounds lies
    /// above (Sibenik: the roof is above the vault, so the default spot lights only the
    /// outside). Only with `spot_from_above`. Default: near the top of the bounds.
    pub spot_at: Option<[f32; 3]>,
    /// Camera position \[m\] (with `look_at`), replacing the scene's camera placement
    /// (as `--look-from` of `render`). Default: the scene's camera.
    pub look_from: Option<[f32; 3]>,
    /// Point the camera looks at \[m\] (with `look_from`).
    pub look_at: Option<[f32; 3]>,
    /// Also measure each technique against its own converged image of each measured
    /// frame's state, to separate a technique's latency (how long until it reaches its
    /// own steady state after a change) from its bias (how far that steady state is from
    /// the path tracer's). The converged image is the same technique with the same
    /// settings, built fresh at that state (edits applied) and run for this many frames
    /// at fixed work per frame (its default budget), all at the frame's time. Cost: this
    /// many frames per measured frame per technique. The latency "to own steady state"
    /// is judged with `own_latency_threshold`. 0 = off. Default 0.
    pub own_converged_frames: u32,
    /// Renderer settings shared by every technique: the `[render]` table of a
    /// configuration file (e.g. `area_light_samples`, `seed`), without `width`/`height`
    /// (set above). Default: the renderer's defaults.
    pub render: Option<toml::Table>,
    /// The converged reference and the equal-time comparison (`[reference]`).
    pub reference: ReferenceSpec,
    /// The techniques to run (`[[technique]]`, at least one), each on the same frames.
    #[serde(rename = "technique")]
    pub techniques: Vec<TechniqueSpec>,
    /// Scripted edits (`[[edit]]`), applied when the frame time reaches them.
    #[serde(rename = "edit")]
    pub edits: Vec<EditSpec>,
    /// Spheres added to the scene as loaded (`[[sphere]]`), e.g. an object for an
    /// `[[edit]]` to move in a scene file that has none. Default: none.
    #[serde(rename = "sphere")]
    pub spheres: Vec<SphereSpec>,
    /// The file this scenario was read from (empty for text parsed without a file).
    #[serde(skip)]
    pub file: PathBuf,
    /// The scenario's TOML text, echoed in the report.
    #[serde(skip)]
    pub text: String,
    /// A smoke run ([`Scenario::miniature`]): every technique's settings also get
    /// [`TechniqueSettings::miniature`](illume_transport::TechniqueSettings::miniature).
    #[serde(skip)]
    pub miniature: bool,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            name: String::new(),
            description: String::new(),
            scene: String::new(),
            animation: None,
            width: 320,
            height: 240,
            start_s: 0.0,
            duration_s: None,
            fps: None,
            times_s: None,
            metrics: vec![Metric::Rmse, Metric::RelMse, Metric::Flip],
            error_metric: Metric::Flip,
            latency_threshold: 0.1,
            own_latency_threshold: None,
            reference_frames: None,
            sky: None,
            sun: None,
            spot_from_above: false,
            spot_at: None,
            look_from: None,
            look_at: None,
            own_converged_frames: 0,
            render: None,
            reference: ReferenceSpec::default(),
            techniques: Vec::new(),
            edits: Vec::new(),
            spheres: Vec::new(),
            file: PathBuf::new(),
            text: String::new(),
            miniature: false,
        }
    }
}

/// The converged reference every frame is measured against, and the equal-time
/// comparison (`[reference]`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReferenceSpec {
    /// Samples per pixel of the converged reference of each distinct frame state. Noise
    /// falls as 1/√spp; time grows linearly (cached, so paid once). Default 256.
    pub spp: u32,
    /// Seed of the converged reference. Default 0.
    pub seed: u64,
    /// Bounces before Russian roulette may end a path. Default 3.
    pub rr_start_depth: u32,
    /// Equal-time comparison: for each technique, also run the progressive reference path
    /// tracer with the technique's measured wall-clock time per frame (accumulating while
    /// the scene is unchanged) and measure it against the converged reference — the
    /// technique against brute force at equal cost. Default true.
    pub equal_time: bool,
}

impl Default for ReferenceSpec {
    fn default() -> Self {
        Self {
            spp: 256,
            seed: 0,
            rr_start_depth: 3,
            equal_time: true,
        }
    }
}

/// One technique to run (`[[technique]]`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TechniqueSpec {
    /// The technique's name (`reference`, `photon_stream`, …). Required.
    pub name: String,
    /// The series name in tables, CSV and plots; must be unique in the scenario.
    /// Default: `name`.
    pub label: Option<String>,
    /// A named preset of the technique (`illume render --help` lists them) that
    /// `settings` then override key by key. Default: none (the technique's defaults).
    pub preset: Option<String>,
    /// The technique's settings: the same keys as its table in a configuration file
    /// (e.g. `[technique.settings]` → the `[photon_stream]` table). Default: the
    /// technique's defaults (or `preset`'s).
    pub settings: Option<toml::Table>,
    /// Wall-clock budget of the technique's `advance` per frame \[ms\], finite and in
    /// (0, [`MAX_BUDGET_MS`]]. Default: none (the technique's default budget).
    pub budget_ms: Option<f64>,
    /// Work per frame in the technique's own unit (`photon_stream`: photons;
    /// `reference`: samples per pixel; `illume render --help` lists them). Also accepted
    /// as `photons` or `samples`; at least 1. Default: the technique's setting (`photon_stream`:
    /// `photons_per_frame` in deterministic mode; `reference`: `spp_per_frame`).
    #[serde(alias = "photons", alias = "samples")]
    pub work: Option<u64>,
    /// Frames rendered at K × K times the scenario's pixels and averaged over K × K
    /// blocks, as the reference's pixels are box-filtered: the technique measured
    /// without the aliasing of one sample at each pixel's centre (edges, thin sunlit
    /// detail, minified texture), at K² times the pixels a frame, so frame times and
    /// frame rates are those of the larger image. An integer in 1..=[`MAX_SUPERSAMPLE`].
    /// Default 1: one sample at each pixel's centre.
    pub supersample: Option<u32>,
}

/// Largest `supersample` of a technique entry (64 times the pixels a frame).
pub const MAX_SUPERSAMPLE: u32 = 8;

impl TechniqueSpec {
    /// The series name: `label`, or `name`.
    pub fn label(&self) -> &str {
        self.label.as_deref().unwrap_or(&self.name)
    }

    /// K of [`TechniqueSpec::supersample`] (1 when not given).
    pub fn supersample(&self) -> u32 {
        self.supersample.unwrap_or(1)
    }
}

/// A sphere added to the scene (`[[sphere]]`): a dynamic instance of a 48×24 UV sphere
/// with a diffuse material of its own, both named `name`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SphereSpec {
    /// Name of the instance and its material (for `[[edit]] instance = …`); not one the
    /// scene has. Required.
    pub name: String,
    /// Centre \[m\]. Required, finite.
    pub center: [f32; 3],
    /// Radius \[m\]: finite and > 0. Required.
    pub radius: f32,
    /// Diffuse albedo (linear RGB, each in [0, 1]). Default 0.8 grey.
    pub base_color: Option<[f32; 3]>,
}

impl SphereSpec {
    /// The problem with its values, if any, as `(field, message)`.
    fn check(&self) -> Result<(), (&'static str, String)> {
        if self.name.is_empty() {
            return Err(("name", "required".into()));
        }
        if !self.center.iter().all(|c| c.is_finite()) {
            return Err(("center", format!("{:?} must be finite", self.center)));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(("radius", format!("{} must be finite and > 0", self.radius)));
        }
        if let Some(c) = self.base_color
            && !c.iter().all(|v| (0.0..=1.0).contains(v))
        {
            return Err(("base_color", format!("{c:?}: each value must be in [0, 1]")));
        }
        Ok(())
    }

    /// Adds the sphere to `scene`; errors name what is wrong.
    fn add_to(&self, scene: &mut Scene) -> Result<(), String> {
        if scene.instances.iter().any(|i| i.name == self.name) {
            return Err(format!(
                "the scene already has an instance \"{}\"",
                self.name
            ));
        }
        let material = MaterialId(scene.materials.len() as u32);
        scene.materials.push(illume_scene::Material {
            name: self.name.clone(),
            base_color: Rgb::from(self.base_color.unwrap_or([0.8; 3])),
            ..Default::default()
        });
        let mut mesh = illume_scene::builtin::uv_sphere(1.0, 48, 24, material, false);
        mesh.name = self.name.clone();
        let mesh = scene.add_mesh(mesh).map_err(|e| e.to_string())?;
        scene
            .apply_edit(&Edit::AddInstance {
                name: self.name.clone(),
                mesh,
                world_from_object: Affine3A::from_scale_rotation_translation(
                    Vec3::splat(self.radius),
                    Quat::IDENTITY,
                    Vec3::from(self.center),
                ),
            })
            .map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// A scripted edit (`[[edit]]`): exactly one target (`instance`, `light` or `material`,
/// by name) and the values to set. Items not given keep their current value.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EditSpec {
    /// Scene time \[s\] of the edit: it is applied just before the first frame whose time
    /// is ≥ `at_s`. Required, finite.
    pub at_s: f64,
    /// Name of the event in the latency table. Default `edit N (TARGET)`.
    pub label: Option<String>,
    /// The instance to place (by name).
    pub instance: Option<String>,
    /// The light to place (by name).
    pub light: Option<String>,
    /// The material to change (by name).
    pub material: Option<String>,
    /// New world translation of the instance or light \[m\]. Default: keep.
    pub translation: Option<[f32; 3]>,
    /// New world rotation of the instance or light \[degrees\], as angles about X, Y and Z
    /// with `R = Rx · Ry · Rz`. Default: keep.
    pub rotation_deg: Option<[f32; 3]>,
    /// New diffuse albedo of the material (linear RGB, each in [0, 1]). Default: keep.
    pub base_color: Option<[f32; 3]>,
    /// New emitted radiance of the material [W/(m²·sr)]. Default: keep.
    pub emission: Option<[f32; 3]>,
}

impl EditSpec {
    /// The target as `kind "name"`, e.g. `instance "sphere"`.
    pub fn target(&self) -> String {
        match (&self.instance, &self.light, &self.material) {
            (Some(n), _, _) => format!("instance \"{n}\""),
            (_, Some(n), _) => format!("light \"{n}\""),
            (_, _, Some(n)) => format!("material \"{n}\""),
            _ => "nothing".into(),
        }
    }

    /// The scene edit this entry makes on `scene` in its current state; unspecified
    /// components keep the current value. Errors name the missing item.
    pub fn resolve(&self, scene: &Scene) -> Result<Edit, String> {
        let place = |current: &Affine3A| {
            let (scale, rotation, translation) = current.to_scale_rotation_translation();
            let translation = self.translation.map_or(translation, Vec3::from);
            let rotation = self.rotation_deg.map_or(rotation, |[x, y, z]| {
                Quat::from_rotation_x(x.to_radians())
                    * Quat::from_rotation_y(y.to_radians())
                    * Quat::from_rotation_z(z.to_radians())
            });
            Affine3A::from_scale_rotation_translation(scale, rotation, translation)
        };
        let missing = |kind: &str, name: &str, have: Vec<&str>| {
            format!("no {kind} named \"{name}\" (have: {})", have.join(", "))
        };
        if let Some(name) = &self.instance {
            let i = scene
                .instances
                .iter()
                .position(|x| &x.name == name)
                .ok_or_else(|| {
                    missing(
                        "instance",
                        name,
                        scene.instances.iter().map(|x| x.name.as_str()).collect(),
                    )
                })?;
            return Ok(Edit::SetInstanceTransform {
                instance: InstanceId(i as u32),
                world_from_object: place(&scene.instances[i].world_from_object),
            });
        }
        if let Some(name) = &self.light {
            let i = scene
                .lights
                .iter()
                .position(|x| &x.name == name)
                .ok_or_else(|| {
                    missing(
                        "light",
                        name,
                        scene.lights.iter().map(|x| x.name.as_str()).collect(),
                    )
                })?;
            return Ok(Edit::SetLightTransform {
                light: LightId(i as u32),
                world_from_light: place(&scene.lights[i].world_from_light),
            });
        }
        if let Some(name) = &self.material {
            let i = scene
                .materials
                .iter()
                .position(|x| &x.name == name)
                .ok_or_else(|| {
                    missing(
                        "material",
                        name,
                        scene.materials.iter().map(|x| x.name.as_str()).collect(),
                    )
                })?;
            let mut value = scene.materials[i].clone();
            if let Some(c) = self.base_color {
                value.base_color = Rgb::from(c);
            }
            if let Some(e) = self.emission {
                value.emission = Rgb::from(e);
            }
            return Ok(Edit::SetMaterial {
                material: MaterialId(i as u32),
                value,
            });
        }
        Err("no target".into())
    }

    /// Checks the entry on its own (one target, values fit the target).
    pub fn validate(&self) -> Result<(), String> {
        if !self.at_s.is_finite() || self.at_s < 0.0 {
            return Err(format!("at_s = {} must be finite and ≥ 0", self.at_s));
        }
        let targets = [&self.instance, &self.light, &self.material]
            .iter()
            .filter(|t| t.is_some())
            .count();
        if targets != 1 {
            return Err(format!(
                "needs exactly one of `instance`, `light`, `material` (has {targets})"
            ));
        }
        let placing = self.translation.is_some() || self.rotation_deg.is_some();
        let colouring = self.base_color.is_some() || self.emission.is_some();
        let finite = |v: &Option<[f32; 3]>| v.is_none_or(|v| v.iter().all(|x| x.is_finite()));
        if ![
            self.translation,
            self.rotation_deg,
            self.base_color,
            self.emission,
        ]
        .iter()
        .all(finite)
        {
            return Err("a value is not finite".into());
        }
        if self.material.is_some() {
            if placing {
                return Err("a material takes `base_color`/`emission`, not a placement".into());
            }
            if !colouring {
                return Err("sets nothing (give `base_color` or `emission`)".into());
            }
        } else {
            if colouring {
                return Err(
                    "`base_color`/`emission` apply to a material, not an instance or light".into(),
                );
            }
            if !placing {
                return Err("sets nothing (give `translation` or `rotation_deg`)".into());
            }
        }
        Ok(())
    }
}

impl Scenario {
    /// Reads and checks a scenario file.
    pub fn load(path: &Path) -> Result<Self, BenchError> {
        let text =
            illume_core::files::read_regular_text(path, illume_core::files::MAX_SETTINGS_BYTES)
                .map_err(|e| BenchError::io(path, e))?;
        Self::parse(&text, path)
    }

    /// Parses and checks scenario text; `path` names it in errors and anchors relative
    /// scene paths.
    pub fn parse(text: &str, path: &Path) -> Result<Self, BenchError> {
        let mut s: Scenario = toml::from_str(text).map_err(|e| BenchError::Parse {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        s.file = path.to_owned();
        s.text = text.to_owned();
        if s.name.is_empty() {
            s.name = path
                .file_stem()
                .map_or_else(|| "scenario".into(), |n| n.to_string_lossy().into_owned());
        }
        if !s.metrics.contains(&s.error_metric) {
            s.metrics.push(s.error_metric);
        }
        s.validate()?;
        Ok(s)
    }

    fn invalid(&self, field: impl Into<String>, message: impl Into<String>) -> BenchError {
        BenchError::Invalid {
            path: self.file.clone(),
            field: field.into(),
            message: message.into(),
        }
    }

    /// Checks every field's range and every technique's settings.
    fn validate(&self) -> Result<(), BenchError> {
        if self.scene.is_empty() {
            return Err(self.invalid("scene", "required (builtin:NAME or a scene file)"));
        }
        if let Err(m) = illume_render::check_image_size(self.width, self.height) {
            return Err(self.invalid("width/height", m));
        }
        if self.reference.spp == 0 {
            return Err(self.invalid("reference.spp", "must be ≥ 1"));
        }
        if self.error_metric.higher_is_better() {
            return Err(self.invalid(
                "error_metric",
                format!(
                    "{} is higher-is-better; use an error metric",
                    self.error_metric
                ),
            ));
        }
        if !(self.latency_threshold.is_finite() && self.latency_threshold > 0.0) {
            return Err(self.invalid("latency_threshold", "must be finite and > 0"));
        }
        if let Some(t) = self.own_latency_threshold {
            if !(t.is_finite() && t > 0.0) {
                return Err(self.invalid("own_latency_threshold", "must be finite and > 0"));
            }
            if self.own_converged_frames == 0 {
                return Err(self.invalid(
                    "own_latency_threshold",
                    "has no effect without `own_converged_frames` > 0 (it is the latency \
                     threshold against the technique's own converged images)",
                ));
            }
        }
        let render = self.render.as_ref();
        if let Some(k) = ["width", "height"]
            .iter()
            .find(|k| render.is_some_and(|r| r.contains_key(**k)))
        {
            return Err(self.invalid(
                format!("render.{k}"),
                "set `width`/`height` at the top level of the scenario",
            ));
        }
        self.check_times()?;
        if let Some(frames) = &self.reference_frames {
            let n = self.frame_times().len();
            if frames.is_empty() {
                return Err(self.invalid(
                    "reference_frames",
                    "lists no frame (leave it out to measure every frame)",
                ));
            }
            if let Some(f) = frames.iter().find(|&&f| f >= n) {
                return Err(self.invalid(
                    "reference_frames",
                    format!("frame {f} is past the last frame ({})", n.saturating_sub(1)),
                ));
            }
            if frames.windows(2).any(|w| w[0] >= w[1]) {
                return Err(self.invalid(
                    "reference_frames",
                    "frame indices must be strictly increasing",
                ));
            }
        }
        if self.own_converged_frames > 10_000 {
            return Err(self.invalid("own_converged_frames", "must be at most 10000"));
        }
        if self.techniques.is_empty() {
            return Err(self.invalid("technique", "at least one [[technique]] entry is needed"));
        }
        let mut labels: Vec<&str> = Vec::new();
        for (i, t) in self.techniques.iter().enumerate() {
            if labels.contains(&t.label()) {
                return Err(self.invalid(
                    format!("technique[{i}].label"),
                    format!("`{}` is used twice; give each entry a `label`", t.label()),
                ));
            }
            // `--save-frames` writes each series under `frames/` by its file-safe label.
            let folder = crate::run::file_safe(t.label());
            if let Some(other) = labels.iter().find(|l| crate::run::file_safe(l) == folder) {
                return Err(self.invalid(
                    format!("technique[{i}].label"),
                    format!(
                        "`{}` and `{other}` would share the frames folder `frames/{folder}`; \
                         give one of them another `label`",
                        t.label()
                    ),
                ));
            }
            labels.push(t.label());
            if let Some(b) = t.budget_ms
                && !(b.is_finite() && b > 0.0 && b <= MAX_BUDGET_MS)
            {
                return Err(self.invalid(
                    format!("technique[{i}].budget_ms"),
                    format!("{b:e} must be finite and in (0, {MAX_BUDGET_MS}] ms"),
                ));
            }
            if t.work == Some(0) {
                return Err(self.invalid(
                    format!("technique[{i}].work"),
                    "must be at least 1 (leave it out for the technique's default)",
                ));
            }
            if let Some(k) = t.supersample
                && !(1..=MAX_SUPERSAMPLE).contains(&k)
            {
                return Err(self.invalid(
                    format!("technique[{i}].supersample"),
                    format!(
                        "{k} must be in 1..={MAX_SUPERSAMPLE} (samples along each side of a pixel)"
                    ),
                ));
            }
            self.technique_config(i)?;
        }
        for (i, e) in self.edits.iter().enumerate() {
            e.validate().map_err(|message| BenchError::Edit {
                path: self.file.clone(),
                index: i,
                message,
            })?;
        }
        for (i, sphere) in self.spheres.iter().enumerate() {
            sphere
                .check()
                .map_err(|(field, m)| self.invalid(format!("sphere[{i}].{field}"), m))?;
        }
        Ok(())
    }

    fn check_times(&self) -> Result<(), BenchError> {
        match (&self.times_s, self.duration_s, self.fps) {
            (Some(times), None, None) => {
                if times.is_empty() {
                    return Err(self.invalid("times_s", "is empty"));
                }
                if times.len() > MAX_FRAMES {
                    return Err(self.invalid(
                        "times_s",
                        format!(
                            "has {} frames, more than the {MAX_FRAMES} a run may have",
                            times.len()
                        ),
                    ));
                }
                if let Some(i) = times.iter().position(|t| !t.is_finite() || *t < 0.0) {
                    return Err(self.invalid(
                        "times_s",
                        format!("entry {i} ({}) must be finite and ≥ 0", times[i]),
                    ));
                }
                if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
                    return Err(self.invalid(
                        "times_s",
                        format!(
                            "must be strictly increasing (entry {} = {} follows {})",
                            i + 1,
                            times[i + 1],
                            times[i]
                        ),
                    ));
                }
                Ok(())
            }
            (None, Some(duration), Some(fps)) => {
                if !(fps.is_finite() && fps > 0.0) {
                    return Err(self.invalid("fps", "must be finite and > 0"));
                }
                if !(duration.is_finite() && duration > 0.0) {
                    return Err(self.invalid("duration_s", "must be finite and > 0"));
                }
                if !(self.start_s.is_finite() && self.start_s >= 0.0) {
                    return Err(self.invalid("start_s", "must be finite and ≥ 0"));
                }
                if (duration * fps).round() < 1.0 {
                    return Err(self.invalid("duration_s", "gives no frame at this fps"));
                }
                if (duration * fps).round() > MAX_FRAMES as f64 {
                    return Err(self.invalid(
                        "duration_s/fps",
                        format!(
                            "give {} frames, more than the {MAX_FRAMES} a run may have",
                            (duration * fps).round()
                        ),
                    ));
                }
                Ok(())
            }
            _ => Err(self.invalid(
                "times_s/duration_s/fps",
                "give either `times_s`, or both `duration_s` and `fps`",
            )),
        }
    }

    /// The latency threshold against the technique's own converged images:
    /// `own_latency_threshold`, or `latency_threshold` when not given.
    pub fn own_latency_threshold(&self) -> f64 {
        self.own_latency_threshold.unwrap_or(self.latency_threshold)
    }

    /// For each of `frame_count` frames, true when it is measured against the converged
    /// reference (`reference_frames`, default all).
    pub fn measured_frames(&self, frame_count: usize) -> Vec<bool> {
        match &self.reference_frames {
            None => vec![true; frame_count],
            Some(list) => {
                let mut m = vec![false; frame_count];
                for &f in list {
                    if let Some(x) = m.get_mut(f) {
                        *x = true;
                    }
                }
                m
            }
        }
    }

    /// The frame times \[s\], in order.
    pub fn frame_times(&self) -> Vec<f64> {
        match (&self.times_s, self.duration_s, self.fps) {
            (Some(times), _, _) => times.clone(),
            (None, Some(duration), Some(fps)) => {
                let n = (duration * fps).round() as usize;
                (0..n).map(|i| self.start_s + i as f64 / fps).collect()
            }
            _ => Vec::new(),
        }
    }

    /// The engine configuration of technique entry `index`: its settings table parsed as
    /// the technique's table of a [`Config`], the scenario's `[render]` table and size.
    /// An unknown name is an error naming the file, the entry and the valid names.
    pub fn technique_config(&self, index: usize) -> Result<Config, BenchError> {
        let spec = &self.techniques[index];
        let error = |message: String| BenchError::Technique {
            path: self.file.clone(),
            index,
            name: spec.name.clone(),
            message,
        };
        let kind: TechniqueKind = spec.name.parse().map_err(error)?;
        let mut table = toml::Table::new();
        table.insert("technique".into(), toml::Value::String(spec.name.clone()));
        let mut render = self.render.clone().unwrap_or_default();
        // A supersampled entry renders K × K pixels for each of the scenario's
        // (`TechniqueSpec::supersample`; its frames are averaged back before measuring).
        let k = spec.supersample().clamp(1, MAX_SUPERSAMPLE);
        render.insert(
            "width".into(),
            toml::Value::Integer((self.width * k).into()),
        );
        render.insert(
            "height".into(),
            toml::Value::Integer((self.height * k).into()),
        );
        table.insert("render".into(), toml::Value::Table(render));
        let mut settings = match &spec.preset {
            Some(name) => Some(kind.preset_table(name).ok_or_else(|| {
                let available: Vec<&str> = kind.presets().iter().map(|(n, _)| *n).collect();
                error(format!(
                    "unknown preset `{name}`; {kind}'s presets are {}",
                    available.join(", ")
                ))
            })?),
            None => None,
        };
        if let Some(keys) = &spec.settings {
            illume_engine::config::merge(
                settings.get_or_insert_with(toml::Table::new),
                keys.clone(),
            );
        }
        if let Some(settings) = settings {
            table.insert(spec.name.clone(), toml::Value::Table(settings));
        }
        // A value of the wrong type is named by its key in the scenario: the entry's
        // `settings` (or preset) table, or the scenario's `[render]` table.
        let mut config: Config =
            toml::Value::Table(table.clone())
                .try_into()
                .map_err(|e: toml::de::Error| {
                    let key =
                        illume_engine::config::refused_key::<Config>(&table).map(|(key, value)| {
                            match key.strip_prefix(&format!("{}.", spec.name)) {
                                Some(setting) => format!("{setting} = {value}: "),
                                None => format!("{key} = {value}: "),
                            }
                        });
                    error(format!(
                        "settings: {}{}",
                        key.unwrap_or_default(),
                        e.message()
                    ))
                })?;
        if self.miniature {
            config.technique_settings_mut().miniature();
        }
        config
            .check()
            .map_err(|m| error(format!("settings: {m}")))?;
        debug_assert_eq!(config.technique, kind);
        Ok(config)
    }

    /// The per-frame budget of technique entry `index`: the entry's budget fields over
    /// the technique's default budget.
    pub fn technique_budget(&self, index: usize, config: &Config) -> Budget {
        let spec = &self.techniques[index];
        let default = config.budget();
        Budget {
            work: spec.work.or(default.work),
            time_ms: spec.budget_ms.or(default.time_ms),
        }
    }

    /// The scene path with `${VAR}` expanded and a relative file path resolved against
    /// the scenario's folder; `builtin:NAME` unchanged.
    pub fn scene_path(&self) -> Result<PathBuf, BenchError> {
        let expanded = expand_env(&self.scene).map_err(|m| self.invalid("scene", m))?;
        if expanded.starts_with("builtin:") {
            return Ok(PathBuf::from(expanded));
        }
        let p = PathBuf::from(expanded);
        Ok(if p.is_relative() {
            self.file.parent().unwrap_or(Path::new("")).join(p)
        } else {
            p
        })
    }

    /// Loads the scene, applies `look_from`/`look_at`, `sky` and `[sun]`, selects the animation (none:
    /// animations are switched off) and sets the scene to the first frame's time.
    pub fn load_scene(&self) -> Result<Scene, BenchError> {
        let path = self.scene_path()?;
        let scene_error = |message: String| BenchError::Scene {
            path: self.file.clone(),
            message,
        };
        let mut scene = illume_scene::load_scene(&path).map_err(|e| scene_error(e.to_string()))?;
        if self.spot_from_above {
            scene = illume_scene::builtin::spot_from_above(scene);
        }
        match (self.spot_at, self.spot_from_above) {
            (Some(p), true) if p.iter().all(|c| c.is_finite()) => {
                illume_scene::builtin::move_spot_from_above(&mut scene, p.into());
            }
            (Some(p), true) => {
                return Err(scene_error(format!("spot_at = {p:?}: must be finite")));
            }
            (Some(_), false) => {
                return Err(scene_error(
                    "spot_at places spot_from_above's light: set spot_from_above = true".into(),
                ));
            }
            (None, _) => {}
        }
        match (self.look_from, self.look_at) {
            (Some(eye), Some(target)) => {
                illume_scene::builtin::look_from(&mut scene, eye.into(), target.into())
                    .map_err(|m| scene_error(format!("look_from/look_at: {m}")))?
            }
            (None, None) => {}
            _ => {
                return Err(scene_error(
                    "look_from and look_at go together: give both or neither".into(),
                ));
            }
        }
        if let Some(rgb) = self.sky {
            if !rgb.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(scene_error(format!(
                    "sky = {rgb:?}: each value must be ≥ 0"
                )));
            }
            let radiance = illume_core::Rgb::from(rgb);
            match scene.sun.as_mut() {
                // A sun scales its sky: replace the sky it scales.
                Some(path) => path.sky_base = Some(illume_scene::Sky::Uniform { radiance }),
                None => scene.sky = Some(illume_scene::Sky::Uniform { radiance }),
            }
        }
        if let Some(sun) = &self.sun {
            if let Some(path) = scene.sun.take() {
                scene.sky = path.sky_base;
            }
            scene
                .attach_sun(sun.clone())
                .map_err(|e| scene_error(format!("[sun]: {e}")))?;
        }
        for (i, sphere) in self.spheres.iter().enumerate() {
            sphere
                .add_to(&mut scene)
                .map_err(|m| scene_error(format!("sphere[{i}]: {m}")))?;
        }
        match &self.animation {
            Some(name) => scene.select_animation(name).map_err(scene_error)?,
            None => scene.active_animation = None,
        }
        scene.set_time(self.frame_times().first().copied().unwrap_or(0.0));
        self.check_edits(&scene)?;
        Ok(scene)
    }

    /// Replays every `[[edit]]` on a copy of `scene` and checks the result after each
    /// with the loader's own checks ([`Scene::validate`]): an edit's albedo of 2 or −1,
    /// or an emission of 3e38 (a total power beyond any scene's), is refused before any
    /// frame is rendered, as the same value in the scene file would be (issue 38).
    fn check_edits(&self, scene: &Scene) -> Result<(), BenchError> {
        use crate::replay::EditTarget as _;
        let mut replayed = scene.clone();
        for index in self.edit_order() {
            let edit_error = |message: String| BenchError::Edit {
                path: self.file.clone(),
                index,
                message,
            };
            replayed
                .apply_spec(&self.edits[index])
                .map_err(edit_error)?;
            replayed.validate().map_err(|m| {
                edit_error(format!(
                    "{} makes the scene invalid: {m}",
                    self.edits[index].target()
                ))
            })?;
        }
        Ok(())
    }

    /// What identifies the scene's content for the reference cache: `builtin:NAME` (with
    /// the illume version, which the cache key holds anyway), or the file's absolute path,
    /// size and modification time.
    pub fn scene_identity(&self) -> Result<String, BenchError> {
        let path = self.scene_path()?;
        let text = path.to_string_lossy();
        if text.starts_with("builtin:") {
            return Ok(text.into_owned());
        }
        let meta = std::fs::metadata(&path).map_err(|e| BenchError::io(&path, e))?;
        let modified = meta
            .modified()
            .ok()
            .and_then(|m| m.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        let absolute = std::fs::canonicalize(&path).unwrap_or(path);
        Ok(format!(
            "{} size {} modified {modified}",
            absolute.display(),
            meta.len()
        ))
    }

    /// Indices of the edits in the order they apply (by `at_s`, then file order).
    pub fn edit_order(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.edits.len()).collect();
        order.sort_by(|&a, &b| self.edits[a].at_s.total_cmp(&self.edits[b].at_s));
        order
    }

    /// The same scenario at toy sizes (`illume bench --miniature`; CI runs every shipped
    /// scenario this way so that the commands behind `docs/reproductions.md` cannot rot):
    /// the image at most [`MINIATURE_SIDE`] pixels on its longer side, the converged
    /// references at most [`MINIATURE_SPP`] samples per pixel, own converged images of at
    /// most 2 frames, and only a few of the frames — the first and the last, the first
    /// and the last measured one, and the first frame at or after each edit (where the
    /// edit shows) — at their own times, so every edit and event still happens — and each
    /// technique's settings cut by its own
    /// [`TechniqueSettings::miniature`](illume_transport::TechniqueSettings::miniature)
    /// (work that does not scale with the pixels). The scene stays. Its numbers mean
    /// nothing; it shows that the scenario runs end to end.
    pub fn miniature(&self) -> Scenario {
        let times = self.frame_times();
        let measured = self.measured_frames(times.len());
        let last = times.len().saturating_sub(1);
        let mut keep = vec![0, last];
        keep.extend(measured.iter().position(|&m| m));
        keep.extend(measured.iter().rposition(|&m| m));
        for e in &self.edits {
            keep.extend(times.iter().position(|&t| t >= e.at_s));
        }
        keep.sort_unstable();
        keep.dedup();
        let mut mini = self.clone();
        let scale = (MINIATURE_SIDE as f64 / self.width.max(self.height) as f64).min(1.0);
        mini.width = ((self.width as f64 * scale).round() as u32).max(1);
        mini.height = ((self.height as f64 * scale).round() as u32).max(1);
        mini.times_s = Some(keep.iter().map(|&i| times[i]).collect());
        mini.duration_s = None;
        mini.fps = None;
        mini.reference_frames = self.reference_frames.as_ref().map(|_| {
            (0..keep.len())
                .filter(|&j| measured[keep[j]])
                .collect::<Vec<usize>>()
        });
        mini.reference.spp = self.reference.spp.min(MINIATURE_SPP);
        mini.own_converged_frames = self.own_converged_frames.min(2);
        mini.name = format!("{} (miniature)", self.name);
        mini.miniature = true;
        mini
    }

    /// The event name of edit `index`: its `label`, or `edit N (TARGET)`.
    pub fn edit_label(&self, index: usize) -> String {
        let e = &self.edits[index];
        e.label
            .clone()
            .unwrap_or_else(|| format!("edit {index} ({})", e.target()))
    }
}

/// Replaces each `${VAR}` by the environment variable `VAR`; an unset variable is an
/// error naming it, except `ILLUME_SCENES`, which then means the shared scenes folder
/// beside the checkout ([`illume_scene::checkout_scenes_dir`]) when that exists, so the
/// shipped scenarios run from a clone beside `shared/` with nothing set.
fn expand_env(text: &str) -> Result<String, String> {
    expand_with(text, |var| {
        if let Ok(value) = std::env::var(var) {
            return Ok(value);
        }
        let fallback = (var == "ILLUME_SCENES").then(illume_scene::checkout_scenes_dir);
        match fallback {
            Some(dir) if dir.is_dir() => Ok(dir.display().to_string()),
            Some(dir) => Err(format!(
                "is not set, and the shared scenes folder beside the checkout ({}) does not exist",
                dir.display()
            )),
            None => Err("is not set".into()),
        }
    })
}

/// [`expand_env`] with `lookup` giving each variable's value, or why it has none.
fn expand_with(
    text: &str,
    lookup: impl Fn(&str) -> Result<String, String>,
) -> Result<String, String> {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("${") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        let end = after
            .find('}')
            .ok_or_else(|| format!("unclosed `${{` in `{text}`"))?;
        let var = &after[..end];
        let value = lookup(var)
            .map_err(|why| format!("environment variable {var} (used in `{text}`) {why}"))?;
        out.push_str(&value);
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expand_env_replaces_and_names_missing_variables() {
        // PATH is set in any test environment.
        let path = std::env::var("PATH").unwrap();
        assert_eq!(expand_env("${PATH}/x").unwrap(), format!("{path}/x"));
        assert_eq!(expand_env("plain").unwrap(), "plain");
        let e = expand_env("${ILLUME_SURELY_UNSET_VARIABLE}/a").unwrap_err();
        assert!(e.contains("ILLUME_SURELY_UNSET_VARIABLE"), "{e}");
        assert!(expand_env("${OPEN").is_err());
    }

    #[test]
    fn unset_illume_scenes_means_the_folder_beside_the_checkout() {
        // The lookup is injected: the process environment is shared by parallel tests.
        let unset = |_: &str| -> Result<String, String> { Err("is not set".into()) };
        let e = expand_with("${ILLUME_SCENES}/a.obj", unset).unwrap_err();
        assert!(
            e.contains("ILLUME_SCENES") && e.contains("is not set"),
            "{e}"
        );
        let set = |v: &str| -> Result<String, String> { Ok(format!("<{v}>")) };
        assert_eq!(
            expand_with("${ILLUME_SCENES}/a.obj", set).unwrap(),
            "<ILLUME_SCENES>/a.obj"
        );
        // With the variable unset in this process (CI sets nothing), the real expansion
        // names the checkout's folder, which exists beside this repository.
        if std::env::var_os("ILLUME_SCENES").is_none() {
            let dir = illume_scene::checkout_scenes_dir();
            assert_eq!(
                expand_env("${ILLUME_SCENES}/x").unwrap(),
                format!("{}/x", dir.display())
            );
        }
    }

    #[test]
    fn frame_times_from_duration_and_fps() {
        let s = Scenario {
            start_s: 0.5,
            duration_s: Some(1.0),
            fps: Some(4.0),
            ..Scenario::default()
        };
        assert_eq!(s.frame_times(), vec![0.5, 0.75, 1.0, 1.25]);
    }

    #[test]
    fn spot_from_above_relights_the_scene_and_spot_at_places_it() {
        let s = Scenario {
            scene: "builtin:cornell-spot".into(),
            spot_from_above: true,
            spot_at: Some([0.1, 0.5, -0.2]),
            times_s: Some(vec![0.0]),
            ..Scenario::default()
        };
        let scene = s.load_scene().unwrap();
        assert_eq!(scene.lights.len(), 1);
        let light = &scene.lights[0];
        assert_eq!(light.name, "spot_from_above");
        let at = illume_core::Vec3::from(light.world_from_light.translation);
        assert!(
            (at - illume_core::Vec3::new(0.1, 0.5, -0.2)).length() < 1e-6,
            "{at:?}"
        );
        // spot_at without spot_from_above, or not finite: errors naming the key.
        for bad in [
            Scenario {
                spot_from_above: false,
                ..s.clone()
            },
            Scenario {
                spot_at: Some([f32::NAN, 0.0, 0.0]),
                ..s.clone()
            },
        ] {
            let e = bad.load_scene().unwrap_err().to_string();
            assert!(e.contains("spot_at"), "{e}");
        }
    }

    #[test]
    fn a_sun_and_a_sky_are_attached_to_the_scene() {
        let s = Scenario {
            scene: "builtin:cornell-spot".into(),
            sky: Some([0.1, 0.2, 0.3]),
            sun: Some(illume_scene::sun::SunSettings::default()),
            times_s: Some(vec![12.0 * 3600.0]),
            ..Scenario::default()
        };
        let scene = s.load_scene().unwrap();
        let path = scene.sun.as_ref().expect("a sun path");
        assert_eq!(
            path.sky_base,
            Some(illume_scene::Sky::Uniform {
                radiance: illume_core::Rgb::new(0.1, 0.2, 0.3)
            })
        );
        match scene.lights[path.light.index()].kind {
            illume_scene::LightKind::Directional { irradiance } => {
                assert!(irradiance.max_element() > 0.0, "noon: {irradiance:?}")
            }
            ref other => panic!("{other:?}"),
        }
        let bad = Scenario {
            sky: Some([-1.0, 0.0, 0.0]),
            ..s.clone()
        };
        assert!(bad.load_scene().unwrap_err().to_string().contains("sky"));
        // A camera placed by look_from/look_at; one without the other is an error.
        let placed = Scenario {
            look_from: Some([0.0, 1.0, 3.0]),
            look_at: Some([0.0, 1.0, 0.0]),
            ..s.clone()
        };
        let scene = placed.load_scene().unwrap();
        let eye = scene.camera.world_from_camera.translation;
        assert!(
            (eye - illume_core::Vec3A::new(0.0, 1.0, 3.0)).length() < 1e-5,
            "{eye:?}"
        );
        let half = Scenario {
            look_from: Some([0.0, 1.0, 3.0]),
            ..s
        };
        assert!(
            half.load_scene()
                .unwrap_err()
                .to_string()
                .contains("look_at")
        );
    }
}
