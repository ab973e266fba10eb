//! The constant ambient term as a [`Technique`].

use crate::{AmbientError, AmbientSettings};
use illume_core::image::RgbImage;
use illume_core::{Counters, Rgb};
use illume_scene::SceneChange;
use illume_transport::{Budget, ChangeResponse, GBuffer, Technique, World};

/// Indirect light `ρ(x)·L_a` at every G-buffer point: stateless, so every change is
/// followed at once.
pub struct Ambient {
    radiance: f32,
}

impl Ambient {
    /// The term for `settings` (checked).
    pub fn new(settings: AmbientSettings) -> Result<Self, AmbientError> {
        settings.validate()?;
        Ok(Self {
            radiance: settings.radiance,
        })
    }
}

impl Technique for Ambient {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    fn scene_changed(&mut self, _world: &World, changes: &[SceneChange]) -> ChangeResponse {
        crate::update::respond(changes)
    }

    fn advance(&mut self, _world: &World, _budget: &Budget) {}

    fn indirect(&mut self, _world: &World, gbuffer: &GBuffer) -> RgbImage {
        let pixels = gbuffer
            .pixels
            .iter()
            .map(|p| {
                p.as_ref()
                    .map_or(Rgb::ZERO, |p| p.hit.albedo * self.radiance)
            })
            .collect();
        RgbImage::from_vec(gbuffer.width, gbuffer.height, pixels)
            .expect("one value per G-buffer pixel")
    }

    fn stats(&self) -> Counters {
        let mut c = Counters::new();
        c.set("radiance", f64::from(self.radiance));
        c
    }

    fn reset(&mut self) {}

    fn settled(&self) -> bool {
        true
    }
}
