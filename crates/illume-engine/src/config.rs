//! One TOML file configures a run: the technique, the renderer, and a table per
//! technique. Unknown keys are errors that name the file and the key.
//!
//! ```toml
//! technique = "reference"
//! [render]
//! width = 800
//! height = 600
//! [reference]
//! spp_per_frame = 8
//! ```

use crate::TechniqueKind;
use illume_photon_stream::PhotonStreamSettings;
use illume_reference::ReferenceSettings;
use illume_render::RenderSettings;
use illume_transport::Budget;
use std::path::{Path, PathBuf};

/// A whole run's configuration.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Config {
    /// The technique supplying indirect light. Default `photon_stream`.
    pub technique: TechniqueKind,
    /// The renderer (`[render]`).
    pub render: RenderSettings,
    /// The reference path tracer (`[reference]`).
    pub reference: ReferenceSettings,
    /// Photon streaming with VSLs (`[photon_stream]`).
    pub photon_stream: PhotonStreamSettings,
}

/// Why a configuration file was rejected.
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
}

impl Config {
    /// Reads a configuration file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Io {
            path: path.into(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses configuration text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        let config: Self = toml::from_str(text).map_err(|e| ConfigError::Parse {
            path: path.into(),
            message: e.to_string(),
        })?;
        // Values in range for serde but not for the renderer (shadow-map resolution…).
        config.render.validate().map_err(|e| ConfigError::Parse {
            path: path.into(),
            message: format!("[render] {e}"),
        })?;
        Ok(config)
    }

    /// The per-frame budget the configured technique gets by default.
    pub fn budget(&self) -> Budget {
        match self.technique {
            TechniqueKind::Reference => Budget {
                samples: Some(self.reference.spp_per_frame),
                ..Default::default()
            },
            // photon_stream: its own photons_per_frame (deterministic mode) or the stream.
            TechniqueKind::PhotonStream => Budget::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
