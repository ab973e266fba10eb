//! One still image with any technique: what `illume render` does.

use crate::{Config, Engine, EngineError};
use illume_core::Progress;
use illume_core::image::RgbImage;
use illume_scene::Scene;

/// A rendered still, split as the reference splits light.
pub struct Still {
    /// direct + indirect.
    pub full: RgbImage,
    /// Emission seen directly plus light reflected once.
    pub direct: RgbImage,
    /// Light reflected two or more times.
    pub indirect: RgbImage,
    /// Time in the technique's precompute phase \[ms\] (0 for a technique's own route).
    pub precompute_ms: f64,
}

/// Renders `scene` at its current time with `config`'s technique at the configured
/// size. A technique with its own route to a still ([`TechniqueKind::has_own_still`](crate::TechniqueKind::has_own_still):
/// the reference renders the whole image by path tracing, `[reference] spp` samples per
/// pixel) takes it, its settings checked first (`spp` 0 is an error, not one sample); any
/// other technique runs its precompute and one frame, both with progress.
pub fn render_still(
    scene: Scene,
    config: &Config,
    progress: &mut dyn Progress,
) -> Result<Still, EngineError> {
    let kind = config.technique;
    if kind.has_own_still() {
        return own_still(scene, config, false, progress);
    }
    let t = scene.time;
    let mut engine = Engine::new(scene, config)?;
    engine.set_split(true);
    let precompute_ms = engine.precompute(progress)?;
    let out = engine.step_with_progress(t, progress)?;
    Ok(Still {
        full: out.frame.full,
        direct: out.frame.direct,
        indirect: out.frame.indirect,
        precompute_ms: precompute_ms + out.precompute_ms,
    })
}

/// [`render_still`], denoised by the technique's own route (`illume render --denoise`;
/// [`TechniqueKind::has_denoised_still`](crate::TechniqueKind::has_denoised_still): the
/// reference's path-traced still through `illume_render::denoise`). A technique without
/// one is refused, naming those that have one. Never ground truth (the bench and the
/// tests take [`render_still`]'s).
pub fn render_denoised_still(
    scene: Scene,
    config: &Config,
    progress: &mut dyn Progress,
) -> Result<Still, EngineError> {
    let kind = config.technique;
    if !kind.has_denoised_still() {
        let have: Vec<&str> = crate::TechniqueKind::ALL
            .iter()
            .filter(|k| k.has_denoised_still())
            .map(|k| k.name())
            .collect();
        return Err(EngineError::NoDenoisedStill {
            technique: kind.name(),
            have: have.join(", "),
        });
    }
    own_still(scene, config, true, progress)
}

/// The technique's own still: its settings checked and the scene validated first.
fn own_still(
    scene: Scene,
    config: &Config,
    denoised: bool,
    progress: &mut dyn Progress,
) -> Result<Still, EngineError> {
    let kind = config.technique;
    config
        .technique_settings()
        .check()
        .map_err(|source| kind.error(source))?;
    scene
        .validate()
        .map_err(|e| EngineError::InvalidScene(format!("{}: {e}", scene.source)))?;
    let i = kind.own_still(scene, config, denoised, progress)?;
    Ok(Still {
        full: i.full,
        direct: i.direct,
        indirect: i.indirect,
        precompute_ms: 0.0,
    })
}
