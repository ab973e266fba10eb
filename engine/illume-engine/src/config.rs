//! One TOML configuration drives a run: the technique, the renderer, and a table per
//! technique. Unknown keys are errors that name the file (or `--set` argument) and the
//! key.
//!
//! ```toml
//! technique = "reference"
//! [render]
//! width = 800
//! height = 600
//! [reference]
//! spp_per_frame = 8
//! ```
//!
//! A run's configuration is layered ([`Config::layered`]), each layer over the one
//! before: the defaults; the chosen technique's preset (`--preset NAME`); the
//! configuration file (`--config FILE`); then each `--set TABLE.KEY=VALUE` in order.
//! The technique is `--technique` if given, else the file's `technique`, else the
//! default (`photon_stream`). No layer knows a technique's fields: presets and `--set`
//! go through the TOML tables, typed by the technique's own settings struct.

pub use crate::Config;
use crate::TechniqueKind;
use illume_transport::{Budget, Pacing, TechniqueError, TechniqueSettings};
use std::path::{Path, PathBuf};

/// Why a configuration was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The TOML is malformed, has an unknown key or a bad value.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message (names the key and line).
        message: String,
    },
    /// A `--set TABLE.KEY=VALUE` argument is malformed, names an unknown key or gives a
    /// value of the wrong type.
    #[error("--set {argument}: {message}")]
    Set {
        /// The argument as given.
        argument: String,
        /// What is wrong (names the key).
        message: String,
    },
    /// `--preset NAME` names no preset of the chosen technique.
    #[error("--preset {name}: {technique} has no such preset (have: {available})")]
    UnknownPreset {
        /// The technique.
        technique: TechniqueKind,
        /// The name given.
        name: String,
        /// The technique's presets, comma-separated.
        available: String,
    },
}

/// The layers of a run's configuration, from the command line.
#[derive(Clone, Debug, Default)]
pub struct ConfigLayers<'a> {
    /// `--technique`: overrides the file's `technique`.
    pub technique: Option<TechniqueKind>,
    /// `--config FILE`.
    pub file: Option<&'a Path>,
    /// `--preset NAME`, looked up in the chosen technique's presets.
    pub preset: Option<&'a str>,
    /// `--set TABLE.KEY=VALUE`, applied in order after everything else.
    pub sets: &'a [String],
}

/// The operations the shared layers need on any technique's settings; every
/// [`TechniqueSettings`] has them.
pub trait AnySettings {
    /// See [`TechniqueSettings::check`].
    fn check(&self) -> Result<(), TechniqueError>;
    /// The settings as [`std::any::Any`], for the technique's registration to downcast.
    fn as_any(&self) -> &dyn std::any::Any;
    /// See [`TechniqueSettings::pace`].
    fn pace(&mut self, pacing: Pacing);
    /// See [`TechniqueSettings::default_budget`].
    fn default_budget(&self) -> Budget;
    /// See [`TechniqueSettings::set_seed`].
    fn set_seed(&mut self, seed: u64);
    /// See [`TechniqueSettings::set_samples_per_pixel`].
    fn set_samples_per_pixel(&mut self, spp: u32) -> bool;
    /// See [`TechniqueSettings::adapt_to_interactive`].
    fn adapt_to_interactive(&mut self) -> Option<String>;
    /// See [`TechniqueSettings::miniature`].
    fn miniature(&mut self);
}

impl<T: TechniqueSettings> AnySettings for T {
    fn check(&self) -> Result<(), TechniqueError> {
        TechniqueSettings::check(self)
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn pace(&mut self, pacing: Pacing) {
        TechniqueSettings::pace(self, pacing);
    }
    fn default_budget(&self) -> Budget {
        TechniqueSettings::default_budget(self)
    }
    fn set_seed(&mut self, seed: u64) {
        TechniqueSettings::set_seed(self, seed);
    }
    fn set_samples_per_pixel(&mut self, spp: u32) -> bool {
        TechniqueSettings::set_samples_per_pixel(self, spp)
    }
    fn adapt_to_interactive(&mut self) -> Option<String> {
        TechniqueSettings::adapt_to_interactive(self)
    }
    fn miniature(&mut self) {
        TechniqueSettings::miniature(self);
    }
}

impl Config {
    /// Reads a configuration file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        Self::parse(&read(path)?, path)
    }

    /// Parses configuration text; `path` names it in errors. A value of the wrong type
    /// or an unknown key is named with its table, its value and its line
    /// (`photon_stream.vsl_count = "x": invalid type: …, expected u32 (line 5, column 13)`).
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let config: Self = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.into(),
            message: typed_error_message::<Self>(text, &e),
        })?;
        config.validate(&path.display().to_string())
    }

    /// The configuration the command-line layers give (see the module documentation).
    pub fn layered(layers: &ConfigLayers<'_>) -> Result<Self, ConfigError> {
        let mut table = toml::Table::new();
        let file_config = match layers.file {
            Some(path) => {
                let text = read(path)?;
                // Parsed once as a whole for errors with the line and key…
                let config = Self::parse(&text, path)?;
                // …and kept as a table so that only its keys override the preset.
                table = toml::from_str(&text).map_err(|e| ConfigError::Parse {
                    path: path.into(),
                    message: e.to_string(),
                })?;
                Some(config)
            }
            None => None,
        };
        let technique = layers
            .technique
            .or(file_config.map(|c| c.technique))
            .unwrap_or_default();
        table.insert("technique".into(), technique.name().into());
        if let Some(name) = layers.preset {
            let preset =
                technique
                    .preset_table(name)
                    .ok_or_else(|| ConfigError::UnknownPreset {
                        technique,
                        name: name.to_owned(),
                        available: technique
                            .presets()
                            .iter()
                            .map(|(n, _)| *n)
                            .collect::<Vec<_>>()
                            .join(", "),
                    })?;
            let mut merged = preset;
            if let Some(toml::Value::Table(file)) = table.remove(technique.name()) {
                merge(&mut merged, file);
            }
            table.insert(technique.name().into(), toml::Value::Table(merged));
        }
        for argument in layers.sets {
            apply_set(&mut table, technique, argument)?;
        }
        let config: Self = from_table(table.clone()).map_err(|message| ConfigError::Set {
            argument: layers.sets.join(" "),
            message: match refused_key::<Self>(&table) {
                Some((key, value)) => format!("{key} = {value}: {message}"),
                None => message,
            },
        })?;
        config.validate("--set")
    }

    /// This configuration with one more `--set TABLE.KEY=VALUE` layer over it (a
    /// setting edited in a window): typed by the table's settings, unknown keys refused,
    /// the whole checked as [`Config::layered`] checks it. Fields that are no setting
    /// (`#[serde(skip)]`, e.g. what pacing set) are taken from the defaults.
    pub fn with_set(&self, argument: &str) -> Result<Config, ConfigError> {
        let (path, value) = parse_set(argument)?;
        self.with_value(argument, &path, value)
    }

    /// This configuration with `value` at the key `path` (`["precomputed", "data"]`),
    /// as [`Config::with_set`] sets it; `argument` names the change in errors.
    pub fn with_value(
        &self,
        argument: &str,
        path: &[String],
        value: toml::Value,
    ) -> Result<Config, ConfigError> {
        let error = |message: String| ConfigError::Set {
            argument: argument.to_owned(),
            message,
        };
        let mut table = toml::Table::try_from(self).map_err(|e| error(e.to_string()))?;
        insert_checked(&mut table, self.technique, argument, path, value)?;
        let config: Self = from_table(table).map_err(error)?;
        config.validate("--set")
    }

    /// Checks the values that are in range for serde but not for the renderer or a
    /// technique (shadow-map resolution, image size, a NaN…): every table, the chosen
    /// technique's and the others', so that a bad value is reported where it was written
    /// rather than when a technique is built. The message names the table and key.
    pub fn check(&self) -> Result<(), String> {
        self.render
            .validate()
            .map_err(|e| format!("[render] {e}"))?;
        illume_render::check_image_size(self.render.width, self.render.height)
            .map_err(|m| format!("[render] width/height: {m}"))?;
        for &kind in TechniqueKind::ALL {
            self.settings_of(kind).check().map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// [`Config::check`], the error naming `source` (the file, or `--set`).
    fn validate(self, source: &str) -> Result<Self, ConfigError> {
        self.check().map_err(|message| ConfigError::Parse {
            path: source.into(),
            message,
        })?;
        Ok(self)
    }

    /// The chosen technique's settings.
    pub fn technique_settings(&self) -> &dyn AnySettings {
        self.settings_of(self.technique)
    }

    /// Applies the CLI's pacing to the chosen technique (`--realtime`,
    /// `--work-per-frame N`) and checks the result with the setting's own validation
    /// ([`AnySettings::check`]), as a settings file's value would be: an amount the
    /// setting refuses (0 samples per pixel) is refused, and so is one the setting
    /// cannot hold (its budget is not `N`: `reference.spp_per_frame` is 32-bit). The
    /// error names the flag, its value and the technique's setting's message.
    pub fn pace(&mut self, pacing: Pacing) -> Result<(), String> {
        self.technique_settings_mut().pace(pacing);
        let Pacing::FixedWork {
            work_per_frame: Some(n),
        } = pacing
        else {
            return Ok(());
        };
        let technique = self.technique;
        let flag = format!("--work-per-frame {n}");
        self.technique_settings()
            .check()
            .map_err(|e| format!("{flag}: {e}"))?;
        let held = self.technique_settings().default_budget().work;
        if held != Some(n) {
            return Err(format!(
                "{flag}: {technique} cannot do {n} {} per frame: its setting holds {} \
                 (the same limit a settings file has)",
                technique.work_unit(),
                held.map_or("no fixed amount".to_owned(), |h| format!("at most {h}"))
            ));
        }
        Ok(())
    }

    /// The chosen technique's settings, to change.
    pub fn technique_settings_mut(&mut self) -> &mut dyn AnySettings {
        self.settings_of_mut(self.technique)
    }

    /// The per-frame budget the chosen technique's settings give.
    pub fn budget(&self) -> Budget {
        self.technique_settings().default_budget()
    }

    /// Seeds the renderer and the chosen technique (`--seed`).
    pub fn set_seed(&mut self, seed: u64) {
        self.render.seed = seed;
        self.technique_settings_mut().set_seed(seed);
    }
}

/// A configuration file's text: a regular file (not a pipe or device) of at most
/// [`illume_core::files::MAX_SETTINGS_BYTES`], UTF-8.
fn read(path: &Path) -> Result<String, ConfigError> {
    illume_core::files::read_regular_text(path, illume_core::files::MAX_SETTINGS_BYTES).map_err(
        |source| ConfigError::Io {
            path: path.into(),
            source,
        },
    )
}

fn from_table<T: serde::de::DeserializeOwned>(table: toml::Table) -> Result<T, String> {
    toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_owned())
}

/// Longest value quoted in a message about a key \[characters\].
const QUOTED_VALUE_CHARS: usize = 40;

/// The key of `table` that `T` refuses — its dotted path (`photon_stream.vsl_count`)
/// and its value as TOML (cut to 40 characters) — found by deserialising each key alone
/// (and, in a table, each of its keys alone, recursively). `None` when every key is
/// accepted alone (the error is in their combination) or when `T` does not accept an
/// empty table (a required field: keys cannot be tried alone).
///
/// A value deserialised from a `toml::Value` (a bench scenario's technique settings, a
/// `--set` layer) has no position, and serde's message names the value's type but not
/// its key: this names the key.
pub fn refused_key<T: serde::de::DeserializeOwned>(
    table: &toml::Table,
) -> Option<(String, String)> {
    fn alone<T: serde::de::DeserializeOwned>(path: &[String], value: &toml::Value) -> bool {
        let mut t = toml::Table::new();
        insert_path(&mut t, path, value.clone());
        from_table::<T>(t).is_ok()
    }
    fn walk<T: serde::de::DeserializeOwned>(
        table: &toml::Table,
        prefix: &[String],
    ) -> Option<(Vec<String>, toml::Value)> {
        for (key, value) in table {
            let mut path = prefix.to_vec();
            path.push(key.clone());
            if alone::<T>(&path, value) {
                continue;
            }
            if let toml::Value::Table(inner) = value
                && let Some(found) = walk::<T>(inner, &path)
            {
                return Some(found);
            }
            return Some((path, value.clone()));
        }
        None
    }
    from_table::<T>(toml::Table::new()).ok()?;
    let (path, value) = walk::<T>(table, &[])?;
    let text = value.to_string();
    let quoted = match text.char_indices().nth(QUOTED_VALUE_CHARS) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text,
    };
    Some((path.join("."), quoted))
}

/// The message of `error`, from deserialising `text` as `T`: when one key is to blame
/// ([`refused_key`]), `KEY = VALUE: MESSAGE (line L, column C)` on one line; otherwise
/// (a syntax error, a combination) the parser's own message, which shows the line.
fn typed_error_message<T: serde::de::DeserializeOwned>(
    text: &str,
    error: &toml::de::Error,
) -> String {
    let Some((key, value)) = toml::from_str::<toml::Table>(text)
        .ok()
        .and_then(|table| refused_key::<T>(&table))
    else {
        return error.to_string();
    };
    let place = error.span().map_or_else(String::new, |span| {
        let before = text.get(..span.start).unwrap_or(text);
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        format!(" (line {line}, column {column})")
    });
    format!("{key} = {value}: {}{place}", error.message())
}

/// Sets `TABLE.KEY=VALUE` (`argument`) in `table`, a configuration of `technique`;
/// checked alone first, so that an unknown key or a wrong type names this argument.
fn apply_set(
    table: &mut toml::Table,
    technique: TechniqueKind,
    argument: &str,
) -> Result<(), ConfigError> {
    let (path, value) = parse_set(argument)?;
    insert_checked(table, technique, argument, &path, value)
}

/// Sets `value` at `path` in `table` (see [`apply_set`]).
fn insert_checked(
    table: &mut toml::Table,
    technique: TechniqueKind,
    argument: &str,
    path: &[String],
    value: toml::Value,
) -> Result<(), ConfigError> {
    let mut alone = toml::Table::new();
    insert_path(&mut alone, path, value.clone());
    if path[0] != "technique" {
        alone.insert("technique".into(), technique.name().into());
    }
    from_table::<Config>(alone).map_err(|message| ConfigError::Set {
        argument: argument.to_owned(),
        message,
    })?;
    insert_path(table, path, value);
    Ok(())
}

/// `TABLE.KEY=VALUE` → the key path and the value: TOML when it parses as a TOML value
/// (`50`, `true`, `0.5`, `"text"`, `[1, 2]`), else the text as a string (so
/// `--set photon_stream.mode=deterministic` needs no quotes).
fn parse_set(argument: &str) -> Result<(Vec<String>, toml::Value), ConfigError> {
    let error = |message: &str| ConfigError::Set {
        argument: argument.to_owned(),
        message: message.to_owned(),
    };
    let (key, text) = argument
        .split_once('=')
        .ok_or_else(|| error("expected TABLE.KEY=VALUE"))?;
    let path: Vec<String> = key.trim().split('.').map(|s| s.trim().to_owned()).collect();
    if path.iter().any(String::is_empty) {
        return Err(error("empty key (expected TABLE.KEY=VALUE)"));
    }
    let text = text.trim();
    let value = toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_owned()));
    Ok((path, value))
}

/// Sets `value` at `path` inside `table`, creating tables on the way (a non-table in
/// the way is replaced).
fn insert_path(table: &mut toml::Table, path: &[String], value: toml::Value) {
    let (last, parents) = path.split_last().expect("a non-empty key path");
    let mut t = table;
    for p in parents {
        let entry = t
            .entry(p.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if !entry.is_table() {
            *entry = toml::Value::Table(toml::Table::new());
        }
        t = entry.as_table_mut().expect("made a table above");
    }
    t.insert(last.clone(), value);
}

/// `over`'s keys replace `base`'s, recursively for tables: how a preset's table and the
/// keys set over it (a configuration file's, a bench scenario's) combine.
pub fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_photon_stream::PhotonStreamSettings;

    #[test]
    fn parses_tables_and_rejects_unknown_keys() {
        let c = Config::parse(
            "technique = \"reference\"\n[render]\nwidth = 10\n[reference]\nspp = 3\n",
            Path::new("a.toml"),
        )
        .unwrap();
        assert_eq!((c.render.width, c.reference.spp), (10, 3));
        let e = Config::parse("[render]\nwidht = 10\n", Path::new("cfg/a.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("cfg/a.toml") && e.contains("widht"), "{e}");
        let c = Config::parse(
            "technique = \"photon_stream\"\n[photon_stream]\nvsl_count = 42\n",
            Path::new("c.toml"),
        )
        .unwrap();
        assert_eq!(
            (c.technique, c.photon_stream.vsl_count),
            (TechniqueKind::PhotonStream, 42)
        );
        let e = Config::parse("[photon_stream]\nvsl_cuont = 1\n", Path::new("d.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("d.toml") && e.contains("vsl_cuont"), "{e}");
        let e = Config::parse("technique = \"nope\"\n", Path::new("b.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.toml") && e.contains("nope"), "{e}");
    }

    /// Issue 38: a value of the wrong type inside a table is named — table, key and
    /// value — on the message's first line, from a file and from a table alike.
    #[test]
    fn a_type_error_in_a_table_names_the_key_and_the_value() {
        let e = Config::parse(
            "[render]\nwidth = 8\n[photon_stream]\nvsl_count = \"x\"\n",
            Path::new("cfg/c.toml"),
        )
        .unwrap_err()
        .to_string();
        let first = e.lines().next().unwrap_or_default();
        assert!(
            first.contains("cfg/c.toml")
                && first.contains("photon_stream.vsl_count = \"x\"")
                && first.contains("line 4"),
            "{e}"
        );
        let mut table: toml::Table =
            toml::from_str("[render.shadow_maps]\nresolution = 512\npcf_texels = [1]\n").unwrap();
        assert_eq!(
            refused_key::<Config>(&table),
            Some(("render.shadow_maps.pcf_texels".into(), "[1]".into()))
        );
        table.remove("render");
        assert_eq!(refused_key::<Config>(&table), None);
    }

    #[test]
    fn primary_visibility_is_a_snake_case_name() {
        use illume_render::PrimaryVisibility;
        let c = Config::parse(
            "[render]\nprimary_visibility = \"rays\"\n",
            Path::new("a.toml"),
        )
        .unwrap();
        assert_eq!(c.render.primary_visibility, PrimaryVisibility::Rays);
        let c = Config::parse("[render]\n", Path::new("a.toml")).unwrap();
        assert_eq!(c.render.primary_visibility, PrimaryVisibility::Raster);
        assert!(
            Config::parse(
                "[render]\nprimary_visibility = \"Raster\"\n",
                Path::new("a.toml")
            )
            .is_err()
        );
    }

    #[test]
    fn shadow_settings_parse_and_out_of_range_values_name_the_key() {
        use illume_render::ShadowMode;
        let c = Config::parse(
            "[render]\nshadows = \"maps\"\n[render.shadow_maps]\nresolution = 512\n",
            Path::new("s.toml"),
        )
        .unwrap();
        assert_eq!(
            (c.render.shadows, c.render.shadow_maps.resolution),
            (ShadowMode::Maps, 512)
        );
        let e = Config::parse(
            "[render.shadow_maps]\nresolution = 0\n",
            Path::new("cfg/s.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("cfg/s.toml") && e.contains("resolution"), "{e}");
    }

    fn sets(args: &[&str]) -> Vec<String> {
        args.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn set_is_typed_by_the_settings_and_names_unknown_keys() {
        let s = sets(&[
            "photon_stream.vsl_count=50",
            "photon_stream.mode=deterministic",
            "render.shadow_maps.resolution=256",
        ]);
        let c = Config::layered(&ConfigLayers {
            sets: &s,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(c.photon_stream.vsl_count, 50);
        assert_eq!(
            c.photon_stream.mode,
            illume_photon_stream::StreamMode::Deterministic
        );
        assert_eq!(c.render.shadow_maps.resolution, 256);
        for (arg, key) in [
            ("reference.nope=1", "nope"),
            ("photon_stream.vsl_count=many", "vsl_count"),
            ("selective.pilot_per_group=5", "pilot_per_group"),
            ("selective.order=fastest", "order"),
            ("nosuchtable.x=1", "nosuchtable"),
        ] {
            let s = sets(&[arg]);
            let e = Config::layered(&ConfigLayers {
                sets: &s,
                ..Default::default()
            })
            .unwrap_err()
            .to_string();
            assert!(e.contains(arg) && e.contains(key), "{arg}: {e}");
        }
        let s = sets(&["novalue"]);
        assert!(
            Config::layered(&ConfigLayers {
                sets: &s,
                ..Default::default()
            })
            .is_err()
        );
    }

    #[test]
    fn layers_apply_in_order_preset_file_set() {
        let dir = std::env::temp_dir().join(format!("illume-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("c.toml");
        std::fs::write(
            &file,
            "technique = \"reference\"\n[photon_stream]\npool_size = 1234\n",
        )
        .unwrap();
        // The file's technique is honoured when --technique is not given.
        let c = Config::layered(&ConfigLayers {
            file: Some(&file),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(c.technique, TechniqueKind::Reference);
        // --technique overrides it; the preset is the base, the file's keys override the
        // preset's, --set overrides both.
        let s = sets(&["photon_stream.vsl_count=7"]);
        let c = Config::layered(&ConfigLayers {
            technique: Some(TechniqueKind::PhotonStream),
            file: Some(&file),
            preset: Some("quality"),
            sets: &s,
        })
        .unwrap();
        let quality = PhotonStreamSettings::quality();
        assert_eq!(c.technique, TechniqueKind::PhotonStream);
        assert_eq!(c.photon_stream.pool_size, 1234);
        assert_eq!(c.photon_stream.vsl_count, 7);
        assert_eq!(c.photon_stream.shading_stride, quality.shading_stride);
        assert_eq!(c.photon_stream.visibility, quality.visibility);
        let e = Config::layered(&ConfigLayers {
            preset: Some("fastest"),
            ..Default::default()
        })
        .unwrap_err()
        .to_string();
        assert!(e.contains("fastest") && e.contains("quality"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn with_set_layers_one_setting_over_a_configuration() {
        let mut base = Config::default();
        base.photon_stream.pool_size = 1234;
        base.render.width = 40;
        let c = base.with_set("photon_stream.vsl_count=7").unwrap();
        assert_eq!(
            (
                c.photon_stream.vsl_count,
                c.photon_stream.pool_size,
                c.render.width
            ),
            (7, 1234, 40)
        );
        let e = base
            .with_set("photon_stream.vsl_cuont=7")
            .unwrap_err()
            .to_string();
        assert!(e.contains("vsl_cuont"), "{e}");
        let e = base
            .with_set("photon_stream.triangle_scale=2")
            .unwrap_err()
            .to_string();
        assert!(e.contains("photon_stream.triangle_scale"), "{e}");
    }

    #[test]
    fn every_preset_of_every_technique_round_trips_through_its_table() {
        for &kind in TechniqueKind::ALL {
            assert_eq!(kind.presets()[0].0, "default", "{kind}");
            for (name, _) in kind.presets() {
                let c = Config::layered(&ConfigLayers {
                    technique: Some(kind),
                    preset: Some(name),
                    ..Default::default()
                })
                .unwrap_or_else(|e| panic!("{kind} preset {name}: {e}"));
                assert_eq!(c.technique, kind);
            }
        }
    }
}
