//! Arguments every rendering command shares: technique, image size, configuration file.

use anyhow::Result;
use clap::Args;
use illume_engine::{Config, TechniqueKind};
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
        Ok(config)
    }
}
