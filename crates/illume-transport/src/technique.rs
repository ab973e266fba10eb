//! The contract every global-illumination technique implements.
//!
//! The renderer owns direct light (with shadows) and emission; a technique owns the
//! indirect light: radiance leaving each G-buffer point towards the camera after at
//! least two bounces from a light (light → surface → surface → eye and longer paths).
//! The frame loop calls, in order: [`Technique::scene_changed`] (after the world was
//! updated), [`Technique::advance`], [`Technique::indirect`], [`Technique::stats`].
//! Interactive techniques must not look at future scene states.

use crate::gbuffer::GBuffer;
use crate::world::World;
use illume_core::image::RgbImage;
use illume_scene::SceneChange;

/// How much work [`Technique::advance`] may do. Unset fields are unlimited; a technique
/// honours the ones that make sense for it and documents which.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Budget {
    /// Photons to shoot (photon techniques).
    pub photons: Option<u64>,
    /// Samples per pixel to add (path tracing).
    pub samples: Option<u32>,
    /// Wall-clock limit \[ms\].
    pub time_ms: Option<f64>,
}

/// Counters a technique reports, names prefixed with the technique's name
/// (`photon_stream.photons_per_s`), values in the unit the name says.
pub type TechniqueStats = Vec<(String, f64)>;

/// A global-illumination technique.
pub trait Technique: Send {
    /// The technique's one name (module, settings table, CLI value, metric prefix).
    fn name(&self) -> &'static str;

    /// The world changed (time step or edit); `world` is already up to date.
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]);

    /// Advances the simulation within `budget`.
    fn advance(&mut self, world: &World, budget: &Budget);

    /// Indirect radiance [W/(m²·sr)] leaving each G-buffer point towards the camera
    /// (black where the pixel sees nothing).
    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage;

    /// Current counters.
    fn stats(&self) -> TechniqueStats;

    /// Drops all accumulated state, as if just constructed.
    fn reset(&mut self);

    /// The frame loop is about to take the shared world's write lock (a time step or an
    /// edit). Techniques whose threads read the world should let go of it promptly, so
    /// the frame loop does not wait for their work in progress. Default: nothing.
    fn before_world_write(&self) {}

    /// True for techniques meant for interactive frame rates: the renderer's automatic
    /// choices then favour speed over exactness (shadow maps instead of shadow rays).
    /// Default false.
    fn interactive(&self) -> bool {
        false
    }
}
