//! The integration tests of illume-render, one binary: one module per mechanism of the CPU
//! renderer.
//!
//! Each module is one mechanism; the tests of all modules run in parallel threads of
//! one process (a test that needs the process to itself says so in its module).

mod glossy;
mod jitter;
mod shadow_maps;
mod sky;
mod terminator;

/// A technique with no indirect light that asks for interactive defaults (so
/// `shadows = "auto"` chooses by cost, as for `photon_stream`).
pub(crate) struct InteractiveBlack;

impl illume_transport::Technique for InteractiveBlack {
    fn name(&self) -> &'static str {
        "interactive_black"
    }
    fn scene_changed(
        &mut self,
        _: &illume_transport::World,
        _: &[illume_scene::SceneChange],
    ) -> illume_transport::ChangeResponse {
        illume_transport::ChangeResponse::Updated
    }
    fn advance(&mut self, _: &illume_transport::World, _: &illume_transport::Budget) {}
    fn indirect(
        &mut self,
        _: &illume_transport::World,
        g: &illume_transport::GBuffer,
    ) -> illume_core::image::RgbImage {
        illume_core::image::RgbImage::black(g.width, g.height)
    }
    fn stats(&self) -> illume_core::Counters {
        illume_core::Counters::default()
    }
    fn reset(&mut self) {}
    fn interactive(&self) -> bool {
        true
    }
}
