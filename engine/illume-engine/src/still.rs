//! One still image with any technique: what `illume render` does.

use crate::{Config, Engine, EngineError, TechniqueKind};
use illume_core::Progress;
use illume_core::image::RgbImage;
use illume_reference::ReferenceRenderer;
use illume_scene::Scene;
use illume_transport::World;

/// A rendered still, split as the reference splits light.
pub struct Still {
    /// direct + indirect.
    pub full: RgbImage,
    /// Emission seen directly plus light reflected once.
    pub direct: RgbImage,
    /// Light reflected two or more times.
    pub indirect: RgbImage,
    /// Time in the technique's precompute phase \[ms\] (0 for the reference).
    pub precompute_ms: f64,
}

/// Renders `scene` at its current time with `config`'s technique at the configured
/// size. The reference renders the whole image by path tracing
/// ([`ReferenceRenderer`], `[reference] spp` samples per pixel, progress per chunk of
/// samples; its settings are validated first: `spp` 0 is an error, not one sample);
/// any other technique runs its precompute (with progress) and one frame.
pub fn render_still(
    scene: Scene,
    config: &Config,
    progress: &mut dyn Progress,
) -> Result<Still, EngineError> {
    let (w, h) = (config.render.width, config.render.height);
    if config.technique == TechniqueKind::Reference {
        config
            .reference
            .validate()
            .map_err(|e| EngineError::Technique {
                technique: illume_reference::NAME,
                source: Box::new(e),
            })?;
        scene
            .validate()
            .map_err(|e| EngineError::InvalidScene(format!("{}: {e}", scene.source)))?;
        let world = World::new(scene);
        let mut r = ReferenceRenderer::new(config.reference.clone(), w, h);
        let spp = config.reference.spp;
        progress.begin("path tracing", spp as u64);
        // Chunks of samples keep the bar moving and the work parallel over pixels; the
        // image does not depend on the chunking.
        let chunk = (spp / 32).max(1);
        while r.samples() < spp {
            r.add_samples(&world, chunk.min(spp - r.samples()));
            progress.set(r.samples() as u64);
        }
        progress.end();
        let i = r.images();
        return Ok(Still {
            full: i.full,
            direct: i.direct,
            indirect: i.indirect,
            precompute_ms: 0.0,
        });
    }
    let t = scene.time;
    let mut engine = Engine::new(scene, config)?;
    let precompute_ms = engine.precompute(progress)?;
    let out = engine.step(t)?;
    Ok(Still {
        full: out.frame.full,
        direct: out.frame.direct,
        indirect: out.frame.indirect,
        precompute_ms: precompute_ms + out.precompute_ms,
    })
}
