//! Arguments every rendering command shares: technique, image size, configuration
//! layers (preset, file, `--set`), camera placement. No technique's fields here: a
//! technique is reached through its name, its presets and its settings table.

use anyhow::Result;
use clap::Args;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use illume_core::Vec3;
pub(crate) use illume_core::{parse_point, parse_radiance};
use illume_engine::{Config, ConfigLayers, TechniqueKind};
use std::path::PathBuf;

/// `--technique`'s parser: the names of [`TechniqueKind::ALL`], listed in `--help`.
fn technique_parser() -> impl TypedValueParser<Value = TechniqueKind> {
    PossibleValuesParser::new(TechniqueKind::ALL.iter().map(|k| k.name()))
        .try_map(|name| name.parse::<TechniqueKind>())
}

/// The text after `--help`: every technique with its work unit and presets.
pub fn techniques_help() -> String {
    let mut s = String::from("Techniques (--technique NAME), their work unit and presets:\n");
    for &kind in TechniqueKind::ALL {
        s += &format!("  {kind}: {}\n", kind.summary());
        s += &format!("      (work unit: {})\n", kind.work_unit());
        for (name, what) in kind.presets() {
            s += &format!("      --preset {name:<14} {what}\n");
        }
    }
    s += "Any setting: --set TABLE.KEY=VALUE (e.g. --set photon_stream.vsl_count=50,\n\
          --set render.shadows=rays); the tables and keys are those of a --config file.";
    s
}

/// Technique, image size and configuration layers (each over the one before: the
/// technique's preset, the --config file, then --set in order; flags like --width last).
#[derive(Args, Clone, Default)]
pub struct SetupArgs {
    /// Technique supplying indirect light [default: the --config file's `technique`,
    /// else photon_stream]; `reference` renders everything with the reference path
    /// tracer.
    #[arg(long, value_parser = technique_parser())]
    pub technique: Option<TechniqueKind>,
    /// Image width [pixels].
    #[arg(long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height [pixels].
    #[arg(long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// TOML configuration: `technique`, `[render]` and one table per technique.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Named settings of the chosen technique (listed below); a --config file's table
    /// and --set override single keys of it.
    #[arg(long)]
    pub preset: Option<String>,
    /// Set one setting, TABLE.KEY=VALUE (repeatable; typed by the technique's
    /// settings; unknown keys are errors), e.g. `photon_stream.vsl_count=50`.
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    pub sets: Vec<String>,
    /// The `.illumepc` file of `--technique precomputed` (written by `illume
    /// precompute`); the same as `--set precomputed.data=FILE`.
    #[arg(long, value_name = "FILE")]
    pub data: Option<PathBuf>,
    /// Replace the scene's lights and emitters by one spot light near the top of its
    /// bounds, shining down (the photon-streaming paper's setup; for files without
    /// lights, such as Sponza, the bunny and the dragon).
    #[arg(long)]
    pub spot_from_above: bool,
    /// A texture file that is missing or cannot be decoded is an error (by default a
    /// warning naming it, and the material is rendered with its factors alone).
    #[arg(long)]
    pub strict: bool,
    /// How a glTF file's light intensities and emission are read: `radiometric` (W/sr,
    /// W/m², W/(m²·sr); files written for illume) or `photometric` (glTF's own cd, lx,
    /// cd/m², as Blender exports them, divided by 683 lm/W).
    #[arg(long, value_enum, default_value_t = Units::Radiometric)]
    pub units: Units,
    /// Camera position X,Y,Z [m] (with --look-at): replaces the scene's camera placement.
    #[arg(long, value_parser = parse_point, requires = "look_at", allow_hyphen_values = true)]
    pub look_from: Option<Vec3>,
    /// Point the camera looks at, X,Y,Z [m] (with --look-from).
    #[arg(long, value_parser = parse_point, requires = "look_from", allow_hyphen_values = true)]
    pub look_at: Option<Vec3>,
    /// A uniform sky of radiance R,G,B [W/(m²·sr)] (linear, each ≥ 0), replacing the
    /// scene's: escaping rays see it and it lights the scene.
    #[arg(
        long,
        value_parser = parse_radiance,
        value_name = "R,G,B",
        conflicts_with = "envmap",
        allow_hyphen_values = true
    )]
    pub sky: Option<Vec3>,
    /// An equirectangular environment map (linear .exr or Radiance .hdr) as the sky,
    /// replacing the scene's (mapping in the README, "Formats and units").
    #[arg(long, value_name = "FILE")]
    pub envmap: Option<std::path::PathBuf>,
    /// Radiance = this × the environment map's texels.
    #[arg(
        long,
        default_value_t = 1.0,
        requires = "envmap",
        allow_hyphen_values = true
    )]
    pub envmap_scale: f32,
    /// Turns the environment map about +Y by this many degrees (right-hand rule).
    #[arg(
        long,
        default_value_t = 0.0,
        requires = "envmap",
        allow_hyphen_values = true
    )]
    pub envmap_rotation: f32,
}

/// How a glTF file's light intensities are read (`--units`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Units {
    /// W/sr, W/m², W/(m²·sr).
    #[default]
    Radiometric,
    /// cd, lx, cd/m² ÷ 683 lm/W.
    Photometric,
}

impl Units {
    /// The loader's option.
    pub fn load(self) -> illume_scene::Units {
        match self {
            Units::Radiometric => illume_scene::Units::Radiometric,
            Units::Photometric => illume_scene::Units::Photometric,
        }
    }

    /// How `illume info` names the reading of `scene` (a path or `builtin:NAME`), in
    /// the terms of its own format: `--units` concerns glTF only.
    pub fn describe(self, scene: &std::path::Path) -> &'static str {
        let extension = scene
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match (extension.as_deref(), self) {
            (Some("obj"), _) => {
                "radiometric (OBJ/MTL emission Ke read as W/(m²·sr); --units is for glTF)"
            }
            (Some("ply"), _) => {
                "radiometric (PLY holds geometry only: no lights or emission; --units is for glTF)"
            }
            (Some("gltf" | "glb"), Units::Radiometric) => {
                "radiometric (glTF light intensities read as W/sr, W/m², emission as W/(m²·sr))"
            }
            (Some("gltf" | "glb"), Units::Photometric) => {
                "photometric (glTF cd, lx, cd/m² divided by 683 lm/W)"
            }
            _ => "radiometric (built-in scene: light intensities in W/sr, emission in W/(m²·sr))",
        }
    }
}

/// How 8-bit output (PNG, GIF, MP4) is exposed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum ExposureMode {
    /// Reinhard et al. 2002's key-value rule: the log-average luminance of the lit pixels
    /// maps to middle grey 0.18 (`illume_core::image::auto_exposure_ev`), computed per
    /// still; for a sequence once, on its first frame with light, and kept (no pumping).
    /// `--exposure` adds stops on top.
    #[default]
    Auto,
    /// Exposure 0 plus `--exposure` stops: radiance 1 W/(m²·sr) maps near white.
    Fixed,
}

impl ExposureMode {
    /// The exposure in stops for an image whose automatic exposure is `auto` (None: no
    /// light), plus `extra_ev`.
    pub fn stops(self, auto: Option<f32>, extra_ev: f32) -> f32 {
        match self {
            ExposureMode::Auto => auto.unwrap_or(0.0) + extra_ev,
            ExposureMode::Fixed => extra_ev,
        }
    }
}

/// An exposure in stops: finite and within ±64 (2⁶⁴ already maps every representable
/// radiance to black or white).
pub fn exposure_stops(s: &str) -> Result<f32, String> {
    let v = finite_f64(s)?;
    if v.abs() > 64.0 {
        return Err(format!("'{s}': exposure must be within ±64 stops"));
    }
    Ok(v as f32)
}

/// A finite number (NaN and ±inf are refused).
pub fn finite_f64(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(format!("'{s}': {v} is not a finite number")),
        Err(e) => Err(format!("'{s}': {e}")),
    }
}

impl SetupArgs {
    /// Loads the scene `path` with these arguments' load options (`--strict`,
    /// `--units`, `--spot-from-above`), selects `animation`, moves it to `time` and
    /// places the camera (`--look-from`/`--look-at`).
    pub fn load_scene(
        &self,
        path: &std::path::Path,
        animation: Option<&str>,
        time: f64,
    ) -> Result<illume_scene::Scene> {
        let mut scene = crate::render::load_scene_with(
            path,
            animation,
            time,
            self.spot_from_above,
            &self.load_options(),
        )?;
        self.place_camera(&mut scene)?;
        Ok(scene)
    }

    /// The scene loader's options from `--strict` and `--units`.
    pub fn load_options(&self) -> illume_scene::LoadOptions {
        illume_scene::LoadOptions {
            strict: self.strict,
            units: self.units.load(),
            ..Default::default()
        }
    }

    /// The configuration these arguments give. `default_preset` is used when neither
    /// --preset nor --config is given and the chosen technique has a preset of that
    /// name (`render` asks for `still`).
    pub fn config(&self, default_preset: Option<&str>) -> Result<Config> {
        let technique = match (self.technique, &self.config) {
            (Some(k), _) => k,
            (None, Some(path)) => Config::load(path)?.technique,
            (None, None) => TechniqueKind::default(),
        };
        let preset = self.preset.as_deref().or_else(|| {
            default_preset.filter(|p| self.config.is_none() && technique.preset_table(p).is_some())
        });
        let mut config = Config::layered(&ConfigLayers {
            technique: self.technique,
            file: self.config.as_deref(),
            preset,
            sets: &self.sets,
        })?;
        if let Some(file) = &self.data {
            let kind = config.technique;
            let Some(key) = kind.data_key() else {
                let readers: Vec<&str> = TechniqueKind::ALL
                    .iter()
                    .filter(|k| k.data_key().is_some())
                    .map(|k| k.name())
                    .collect();
                anyhow::bail!(
                    "--data {}: a data file is read by --technique {}, not {kind}",
                    file.display(),
                    readers.join(" or ")
                );
            };
            let argument = format!("--data {}", file.display());
            let path = [kind.name().to_owned(), key.to_owned()];
            let value = toml::Value::String(file.to_string_lossy().into_owned());
            config = config.with_value(&argument, &path, value)?;
        }
        if let Some(w) = self.width {
            config.render.width = w;
        }
        if let Some(h) = self.height {
            config.render.height = h;
        }
        illume_render::check_image_size(config.render.width, config.render.height)
            .map_err(|m| anyhow::anyhow!("--width/--height: {m}"))?;
        Ok(config)
    }

    /// Applies --look-from/--look-at and --sky/--envmap to a loaded scene, and warns when
    /// the result has no light at all.
    pub fn place_camera(&self, scene: &mut illume_scene::Scene) -> Result<()> {
        if let (Some(eye), Some(target)) = (self.look_from, self.look_at) {
            illume_scene::builtin::look_from(scene, eye, target)
                .map_err(|m| anyhow::anyhow!("--look-from/--look-at: {m}"))?;
        }
        if let Some(radiance) = self.sky {
            scene.replace_sky(illume_scene::Sky::Uniform { radiance });
        }
        if let Some(file) = &self.envmap {
            scene.replace_sky(illume_scene::load_envmap(
                file,
                self.envmap_scale,
                self.envmap_rotation,
            )?);
        }
        let sky_lit = scene
            .sky
            .as_ref()
            .is_some_and(|sky| sky.integral().max_element() > 0.0);
        if scene.lights.is_empty() && scene.materials.iter().all(|m| !m.is_emissive()) && !sky_lit {
            eprintln!(
                "warning: {}: the scene has no lights, no emissive materials and no sky; it will render black (--spot-from-above adds a spot light, --sky a sky)",
                scene.source
            );
        }
        Ok(())
    }
}
