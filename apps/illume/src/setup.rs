//! Arguments every rendering command shares: technique, image size, configuration file.

use anyhow::Result;
use clap::Args;
use illume_engine::{Config, TechniqueKind};
use illume_photon_stream::PhotonStreamSettings;
use std::path::PathBuf;

/// Technique, image size and TOML configuration (flags override the file).
#[derive(Args, Clone)]
pub struct SetupArgs {
    /// Technique supplying indirect light; `reference` renders everything with the
    /// reference path tracer.
    #[arg(long, default_value = "photon_stream")]
    pub technique: TechniqueKind,
    /// Image width [pixels].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height [pixels].
    #[arg(long)]
    pub height: Option<u32>,
    /// TOML configuration (technique settings tables); flags override it.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Named photon_stream settings instead of a `[photon_stream]` table: `default`,
    /// `deterministic`, `interactive` or `quality` (200 VSLs, 10⁶-impact pool, VSL
    /// shadows, every pixel shaded). `render` uses `quality` with a shadow ray to
    /// every VSL, shot deterministically, when neither this nor --config is given.
    #[arg(long, conflicts_with = "config")]
    pub preset: Option<String>,
}

impl SetupArgs {
    /// The configuration file (or the defaults) with these flags applied.
    pub fn config(&self) -> Result<Config> {
        let mut config = match &self.config {
            Some(p) => Config::load(p)?,
            None => Config::default(),
        };
        config.technique = self.technique;
        if let Some(w) = self.width {
            config.render.width = w;
        }
        if let Some(h) = self.height {
            config.render.height = h;
        }
        if let Some(name) = &self.preset {
            config.photon_stream = PhotonStreamSettings::preset(name).ok_or_else(|| {
                anyhow::anyhow!(
                    "--preset {name}: unknown preset (default, deterministic, interactive, quality)"
                )
            })?;
        }
        Ok(config)
    }
}
