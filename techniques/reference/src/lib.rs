//! The reference path tracer: illume's ground truth, against which every technique is
//! measured (`reference`; `shared/DESIGN.md`, "The reference is a peer").
//!
//! **What it computes.** The rendering equation (Kajiya 1986) by unidirectional path
//! tracing from the camera with next-event estimation at every vertex, multiple
//! importance sampling with the power heuristic (Veach 1997) between light sampling and
//! BSDF sampling for area lights (emissive triangles), Russian roulette after
//! [`ReferenceSettings::rr_start_depth`] bounces, and a box pixel filter (uniform jitter
//! within the pixel). It is unbiased under `shared/DESIGN.md`'s conventions and
//! deterministic per seed: sample `s` of pixel `p` uses PCG stream (`mix64(seed + s)`,
//! `p`), whatever the thread count.
//!
//! Every path contribution is filed by its number of bounces:
//! * **direct** image = emission seen from the camera + light reflected once (light →
//!   surface → eye);
//! * **indirect** image = light reflected two or more times;
//! * **full** = direct + indirect.
//!
//! | mechanism | module |
//! |---|---|
//! | path kernel: NEE + MIS + Russian roulette (shared with other techniques) | [`illume_transport::path`] |
//! | full-image progressive rendering, direct/indirect split | [`full_image`] |
//! | indirect light at G-buffer points, accumulated over frames ([`Technique`](illume_transport::Technique)) | [`state`] |
//! | scene changes → restart of the average | [`update`] |
//! | the still of `illume render`, plain or denoised (`--denoise`, `illume_render::denoise`) | `still` |
//! | settings and presets | [`settings`] |
//!
//! **Failure modes.** Noise, falling as 1/√spp; caustics through specular paths are
//! found only by BSDF sampling (slow); an animated scene restarts the average at every
//! change, so a moving scene is never converged in the frame loop.
//!
//! ```
//! use illume_reference::{ReferenceRenderer, ReferenceSettings};
//! use illume_transport::World;
//! let world = World::new(illume_scene::builtin::load("furnace").unwrap());
//! let mut r = ReferenceRenderer::new(ReferenceSettings::default(), 8, 8);
//! r.add_samples(&world, 64);
//! let mean = r.images().full.mean();
//! assert!((mean.x - 2.0).abs() < 0.1); // furnace: Le/(1 − ρ) = 2
//! ```

pub mod error;
pub mod full_image;
pub mod settings;
pub mod state;
mod still;
pub mod update;

pub use error::ReferenceError;
pub use full_image::{ReferenceRenderer, SplitImages};
pub use settings::ReferenceSettings;
pub use state::ReferenceTechnique;

/// The technique's one name: CLI value, settings table, counter and error prefix.
pub const NAME: &str = "reference";

/// The reference's registration: how the engine, the CLI and the window know it.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = ReferenceSettings;
    const SUMMARY: &'static str = "the reference path tracer (NEE + MIS): ground truth";
    const FRAME_HISTORY: illume_transport::FrameHistory =
        illume_transport::FrameHistory::RestartsOnChange;
    const NEEDS_TIMELINE: bool = false;
    // Another seed of the same estimator, 512 spp: only noise separates the two.
    const AGREEMENT: illume_transport::Agreement = illume_transport::Agreement::CornellSpot(
        illume_transport::AgreementSpec {
            sets: &["reference.spp_per_frame=256", "reference.seed=77"],
            frames: 2,
            max_energy_error: 0.02,
            max_block_error: 0.06,
            why: "another seed of the same estimator, 512 spp: only noise separates the two; \
                  the reference's own block noise at 512 spp is ≈ 0.02 (two independent \
                  halves, photon_stream's tests/photon_stream/reference.rs), its energy noise well below 1 %",
        },
    );
    const STILL: Option<illume_transport::StillFn<ReferenceSettings>> = Some(still::still);
    const DENOISED_STILL: Option<illume_transport::StillFn<ReferenceSettings>> =
        Some(still::denoised_still);

    fn build(
        _world: &illume_transport::SharedWorld,
        settings: &ReferenceSettings,
        _timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        Ok(Box::new(ReferenceTechnique::new(settings.clone())?))
    }
}
