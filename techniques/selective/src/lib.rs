//! Selective photon tracing — Dmitriev, Brabec, Myszkowski & Seidel, *Interactive
//! Global Illumination Using Selective Photon Tracing* (EGWR 2002;
//! `shared/papers/selective-photon-tracing.md`).
//!
//! **What it approximates.** The indirect light of Lambertian surfaces — the
//! reference's `indirect` image — from a fixed pool of N = N_g·N_p·R quasi-random
//! photon paths (photon `i` follows the scrambled Halton point `i`), bucketed on the
//! fly into mesh elements (no photon is stored). After a scene change only the paths
//! it touched are re-traced: pilot photons find which groups of similar paths a change
//! concerns (Halton periodicity, Eq. 3 and Eq. 6), the most visible and most affected
//! groups are re-traced first, each photon with negative energy along its old path and
//! positive energy along its new one, from the first segment that met the change. After
//! N_g groups every photon is current, exactly as a from-scratch trace would leave it.
//! Direct light with shadows is the renderer's.
//!
//! | paper | here |
//! |---|---|
//! | §4.1–4.2, Eqs. 1–5: Halton paths, periodicity, N_g | [`qmc`] |
//! | §5.1, Fig. 1: pilot and corrective groups | [`groups`] |
//! | §5.2, Algorithm 1: phantoms, detection, negative/positive re-tracing | [`retrace`] |
//! | §5.1: the pool filled in index order | [`fill`] |
//! | §5.2–§5.3, Eq. 6: the next stale group by priorities P and V, re-tracing, raising P | [`groups::Priority`], [`selection`] |
//! | §5.3: visual masking by textures, Δp/T_e | [`masking`] |
//! | §1, §3, §6: mesh elements, Gouraud display | [`elements`], [`shade`] |
//! | §5.2 (BSDF changes), light changes (beyond the paper) | [`update`] |
//! | the [`Technique`](illume_transport::Technique) the renderer drives | [`state`] |
//! | §6: the solution on its own thread beside the frame loop | [`stream`] |
//! | beyond the paper: frames shown through a noise-aware temporal filter while groups are stale | [`temporal`] |
//! | settings (a tuning guide) and presets | [`settings`] |
//!
//! **Failure modes.** (1) Element-scale blur and leaks at contacts: irradiance is
//! constant per element and Gouraud-interpolated, so detail smaller than an element
//! is lost and light bleeds between touching objects (the paper's "most severe
//! limitation"); elements are noisy (the pool holds `min_photons_per_element` photons
//! per element on average). (2) Detection is not conservative: a change no pilot meets is found
//! only when its groups come up in order (N_g groups after the change at worst).
//! (3) Coherence fades with bounces: with N_g = 288 only the light choice and the
//! emission direction are coherent within a group, so objects lit only indirectly are
//! found late (N_g = 10 080 keeps the first bounce, Fig. 5). (4) N_g grows with the
//! number of lights. (5) Light changes that carry much of the power restart the
//! solution. (6) Irradiance keeps no direction: a glossy surface shows what its BRDF
//! reflects of uniform light (its directional albedo, `directional_albedo`), no
//! highlight. (7) Texture masking (Δp/T_e, §5.3) is a simpler model than the paper's VDP:
//! per texture and MIP level, the mean of Daly's contrast-masking function over the
//! Peli band contrast of a box pyramid of luminance, frequencies finer than an element
//! removed, one contrast sensitivity for every frequency (no CSF, no orientation or
//! colour channels); the MIP level of a hit comes from its distance and angle to the
//! camera. A texture that masks less than the model says delays visible updates (only
//! the order of re-tracing is affected). (8) The default streaming mode's frames depend
//! on the machine's speed (the thread re-traces while frames render, §6);
//! [`SelectiveMode::Deterministic`] frames do not.
//!
//! ```
//! use illume_selective::{Selective, SelectiveSettings};
//! use illume_transport::{Budget, GBuffer, Technique, World};
//! let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
//! let settings = SelectiveSettings {
//!     pilots_per_group: 8,
//!     ratio: 4,
//!     // A tiny pool for the example: not raised to 16 photons per element.
//!     min_photons_per_element: 0,
//!     warm_up: false,
//!     ..SelectiveSettings::deterministic()
//! };
//! let mut sel = Selective::for_world(&world, settings).unwrap();
//! sel.converge(&world);
//! assert_eq!(sel.filled(), sel.layout().pool());
//! let g = GBuffer::render(&world, 16, 12, illume_core::Vec2::splat(0.5));
//! assert!(sel.indirect(&world, &g).mean().x > 0.0);
//! ```

pub mod elements;
pub mod emission;
pub mod error;
pub mod fill;
pub mod groups;
pub mod masking;
pub mod qmc;
pub mod retrace;
pub mod selection;
pub mod settings;
pub mod shade;
pub mod state;
pub mod stream;
pub mod temporal;
pub mod update;

pub use error::SelectiveError;
pub use settings::{GroupOrder, SelectiveMode, SelectiveSettings};
pub use state::Selective;
pub use stream::{Streaming, build};

/// The technique's one name: CLI value, settings table, counter and error prefix.
pub const NAME: &str = "selective";

/// Selective photon tracing's registration: how the engine, the CLI and the window know it.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = SelectiveSettings;
    const SUMMARY: &'static str = "selective photon tracing with Halton pilot and corrective \
        groups (Dmitriev et al. 2002): interactive";
    const FRAME_HISTORY: illume_transport::FrameHistory = illume_transport::FrameHistory::Carried(
        "its photons and corrective groups build up over the frames",
    );
    const NEEDS_TIMELINE: bool = false;
    const AGREEMENT: illume_transport::Agreement =
        illume_transport::Agreement::CornellSpot(illume_transport::AgreementSpec {
            sets: &[
                "selective.mode=deterministic",
                "selective.pilots_per_group=1000",
            ],
            frames: 1,
            max_energy_error: 0.05,
            max_block_error: 0.15,
            why: "every photon of a 1.15 M pool (N_g = 72, N_p = 1000, R = 16) bucketed in \
                  12 400 elements: unbiased up to element-scale blur (irradiance constant per \
                  element, Gouraud-smoothed) and the element noise of ≈ 90 impacts per \
                  element; issue 10's bounds: energy ±5 %, block error ≤ 0.15",
        });

    fn build(
        world: &illume_transport::SharedWorld,
        settings: &SelectiveSettings,
        _timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        Ok(build(world, settings.clone())?)
    }
}
