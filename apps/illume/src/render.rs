//! `illume render`.

use crate::progress;
use anyhow::{Context, Result, bail};
use clap::Args;
use illume_core::image::{RgbImage, ToneMap};
use illume_engine::{Engine, TechniqueKind};
use illume_photon_stream::{PhotonStreamSettings, StreamMode, VisibilityMode};
use illume_reference::ReferenceRenderer;
use illume_transport::World;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `illume render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME.
    pub scene: PathBuf,
    /// Technique, image size and configuration file.
    #[command(flatten)]
    pub setup: crate::setup::SetupArgs,
    /// Scene time [s] at which the active animation is evaluated.
    #[arg(long, default_value_t = 0.0)]
    pub time: f64,
    /// Animation to play (default: the scene's first).
    #[arg(long)]
    pub animation: Option<String>,
    /// Samples per pixel (reference path tracer).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Output image: .exr (linear radiance) or .png (tone-mapped sRGB).
    #[arg(long, short, default_value = "out/render.png")]
    pub output: PathBuf,
    /// Also write FILE_direct and FILE_indirect beside the output.
    #[arg(long)]
    pub split: bool,
    /// Exposure for PNG output [stops].
    #[arg(long, default_value_t = 0.0)]
    pub exposure: f32,
    /// Random seed.
    #[arg(long)]
    pub seed: Option<u64>,
}

/// Loads a scene given on the command line (file or builtin:NAME), selects its
/// animation and moves it to `time`, optionally relit by
/// [`illume_scene::builtin::spot_from_above`]; prints load warnings.
pub fn load_scene(
    path: &Path,
    animation: Option<&str>,
    time: f64,
    spot_from_above: bool,
) -> Result<illume_scene::Scene> {
    let t0 = Instant::now();
    let mut scene = illume_scene::load_scene(path)?;
    if spot_from_above {
        scene = illume_scene::builtin::spot_from_above(scene);
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(name) = animation {
        scene.select_animation(name).map_err(anyhow::Error::msg)?;
    }
    scene.set_time(time);
    if scene.lights.is_empty() && scene.materials.iter().all(|m| !m.is_emissive()) {
        eprintln!(
            "warning: {}: the scene has no lights and no emissive materials; it will render black (--spot-from-above adds a spot light)",
            path.display()
        );
    }
    let dt = t0.elapsed().as_secs_f64();
    if dt > 0.5 {
        eprintln!("loaded {} in {dt:.2} s", path.display());
    }
    Ok(scene)
}

/// `path` with `_suffix` added to the file stem.
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("render");
    let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("png");
    path.with_file_name(format!("{stem}_{suffix}.{ext}"))
}

fn write(img: &RgbImage, path: &Path, tone: &ToneMap) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    }
    img.write(path, tone)?;
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Runs `illume render`.
pub fn run(a: RenderArgs) -> Result<()> {
    let mut config = a.setup.config()?;
    if a.setup.config.is_none() && a.setup.preset.is_none() {
        // A still wants the converged look, not the interactive one, and the same
        // image on every run: the quality preset with a shadow ray to every VSL (no
        // visibility noise; 2.9 s for builtin:cornell-spot at 640×480 on 2 cores).
        config.photon_stream = PhotonStreamSettings {
            mode: StreamMode::Deterministic,
            visibility: VisibilityMode::All,
            ..PhotonStreamSettings::quality()
        };
    }
    if let Some(s) = a.spp {
        config.reference.spp = s;
    }
    if let Some(s) = a.seed {
        config.render.seed = s;
        config.reference.seed = s;
    }
    if config.render.width == 0 || config.render.height == 0 {
        bail!("image size must be at least 1×1");
    }
    config.reference.width = config.render.width;
    config.reference.height = config.render.height;
    let tone = ToneMap {
        exposure_ev: a.exposure,
        ..Default::default()
    };
    let mut scene = load_scene(
        &a.scene,
        a.animation.as_deref(),
        a.time,
        a.setup.spot_from_above,
    )?;
    a.setup.place_camera(&mut scene)?;
    let t0 = Instant::now();
    let (full, direct, indirect) = if config.technique == TechniqueKind::Reference {
        let world = World::new(scene);
        let mut r = ReferenceRenderer::new(config.reference.clone());
        let spp = config.reference.spp.max(1);
        let pb = progress::bar(spp as u64, "path tracing");
        // Chunks of samples keep the bar moving and the work parallel over pixels.
        let chunk = (spp / 32).max(1);
        while r.samples() < spp {
            let n = chunk.min(spp - r.samples());
            r.add_samples(&world, n);
            pb.set_position(r.samples() as u64);
        }
        pb.finish_and_clear();
        let imgs = r.images();
        (imgs.full, imgs.direct, imgs.indirect)
    } else {
        let spinner = progress::spinner(&format!(
            "{}: placing VSLs, shooting photons, shading",
            config.technique
        ));
        let mut engine = Engine::new(scene, &config)?;
        let out = engine.step(a.time);
        spinner.finish_and_clear();
        (out.frame.full, out.frame.direct, out.frame.indirect)
    };
    let secs = t0.elapsed().as_secs_f64();
    let m = full.mean();
    eprintln!(
        "{} {}×{} in {secs:.2} s; mean radiance ({:.5}, {:.5}, {:.5}) W/(m²·sr)",
        config.technique, config.render.width, config.render.height, m.x, m.y, m.z
    );
    write(&full, &a.output, &tone)?;
    if a.split {
        write(&direct, &with_suffix(&a.output, "direct"), &tone)?;
        write(&indirect, &with_suffix(&a.output, "indirect"), &tone)?;
    }
    Ok(())
}
