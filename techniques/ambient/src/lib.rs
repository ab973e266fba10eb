//! `ambient`: the smallest technique, for the engine's own tests — the indirect light of
//! every G-buffer point is a constant ambient radiance reflected by its albedo,
//! `ρ(x)·L_a` (a Lambertian surface under uniform incident radiance `L_a`).
//!
//! It is exact where the light arriving after at least one bounce is uniform: inside
//! `builtin:furnace` (a closed sphere of albedo ρ = 0.5 emitting L_e = 1 W/(m²·sr)) that
//! light is `L_e·ρ/(1 − ρ)` = 1, so `radiance = 1` gives the reference's indirect light,
//! `L_e·ρ²/(1 − ρ)` = 0.5, at every pixel. Anywhere else it is the classic "ambient
//! term": no shadows, no colour bleeding.
//!
//! It proves the registration path: this folder and one line in the engine's list
//! (under `#[cfg(test)]`, so users never see it) make it a technique of the engine.
//!
//! | mechanism | module |
//! |---|---|
//! | the constant term ([`Technique`](illume_transport::Technique)) | [`state`] |
//! | settings | [`settings`] |
//! | scene changes (nothing to invalidate) | [`update`] |

pub mod error;
pub mod settings;
pub mod state;
pub mod update;

pub use error::AmbientError;
pub use settings::AmbientSettings;
pub use state::Ambient;

/// The technique's one name: CLI value, settings table, counter and error prefix.
pub const NAME: &str = "ambient";

/// The ambient term's registration.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = AmbientSettings;
    const SUMMARY: &'static str = "a constant ambient radiance reflected by the albedo (tests)";
    const FRAME_HISTORY: illume_transport::FrameHistory =
        illume_transport::FrameHistory::RestartsOnChange;
    const NEEDS_TIMELINE: bool = false;
    const AGREEMENT: illume_transport::Agreement = illume_transport::Agreement::Elsewhere(
        "exact only where the bounced light is uniform: the engine's test on builtin:furnace",
    );

    fn build(
        _world: &illume_transport::SharedWorld,
        settings: &AmbientSettings,
        _timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        Ok(Box::new(Ambient::new(settings.clone())?))
    }
}
