//! Arguments every rendering command shares: technique, image size, configuration file.

use anyhow::Result;
use clap::Args;
use illume_core::Vec3;
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
    /// Replace the scene's lights and emitters by one spot light near the top of its
    /// bounds, shining down (the photon-streaming paper's setup; for files without
    /// lights, such as Sponza, the bunny and the dragon).
    #[arg(long)]
    pub spot_from_above: bool,
    /// Camera position X,Y,Z [m] (with --look-at): replaces the scene's camera placement.
    #[arg(long, value_parser = parse_point, requires = "look_at", allow_hyphen_values = true)]
    pub look_from: Option<Vec3>,
    /// Point the camera looks at, X,Y,Z [m] (with --look-from).
    #[arg(long, value_parser = parse_point, requires = "look_from", allow_hyphen_values = true)]
    pub look_at: Option<Vec3>,
}

/// `X,Y,Z` as a point.
fn parse_point(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("'{s}': {e} (expected X,Y,Z)"))?;
    match v[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("'{s}': expected three finite numbers X,Y,Z")),
    }
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

    /// Applies --look-from/--look-at to a loaded scene.
    pub fn place_camera(&self, scene: &mut illume_scene::Scene) -> Result<()> {
        if let (Some(eye), Some(target)) = (self.look_from, self.look_at) {
            illume_scene::builtin::look_from(scene, eye, target).map_err(anyhow::Error::msg)?;
        }
        Ok(())
    }
}
