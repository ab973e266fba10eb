//! Photon streaming with virtual surface lights — Meneveaux & Bridault, *Photon
//! Streaming for Interactive Global Illumination in Dynamic Scenes* (2008,
//! hal-00331236; `shared/papers/photon-streaming-vsl.md`). illume's default technique.
//!
//! **What it approximates.** The indirect light: radiance reflected two or more times
//! (light → surface → G-buffer point → eye and longer), for Lambertian surfaces — the
//! reference's `indirect` image. A simulation thread shoots photons continuously into a
//! fixed FIFO pool; each impact deposits the flux *leaving* its surface (ρ·Φ, every
//! bounce 0, 1, 2, …) on the nearest pre-placed VSL of the same object, and the evicted
//! photon subtracts its own. Frames shade every pixel with the VSLs as surface-element
//! lights, `ρ(x)/π · Σ Φ_s cosθ_i cosθ' / (π r² + A_s)`; direct light with shadows is
//! the renderer's.
//!
//! | paper | here |
//! |---|---|
//! | §0.4.2, Algorithm 1: VSL placement, removal of close VSLs | [`placement`] |
//! | §0.3, §0.5, Algorithm 2: photon pool, O(1) VSL updates | [`pool`] |
//! | §0.7.1: photon tracing with Russian roulette | [`emit`] |
//! | §0.7.2: simulation thread, mutual exclusion | [`stream`] |
//! | §0.4.1, §0.6: VSL shading, tile by tile | [`shade`] |
//! | §0.7.3: ε culling of VSLs per tile | [`cull`] |
//! | beyond the paper: shadow rays to VSLs, near-field gather, shading stride | [`visibility`], [`near_field`], [`interpolate`] |
//! | §0.5, §0.9.1: dynamic scenes, latency, flush | [`update`] |
//! | the [`Technique`](illume_transport::Technique) the renderer drives | [`state`] |
//! | settings (a tuning guide) and presets | [`settings`] |
//!
//! **Failure modes.** (1) No VSL visibility (the paper's choice, [`VisibilityMode::Off`]):
//! VSLs light points they cannot see — over-illumination behind occluders (Figure 7);
//! [`VisibilityMode::All`]/[`VisibilityMode::Stochastic`] remove it at the cost of
//! shadow rays. (2) Energy is concentrated at VSL centres with the VSL's normal: at a
//! corner, photons landing on one face near another face's VSL leave with the wrong
//! normal, and few VSLs blur indirect detail (colour bleeding is low-frequency).
//! (3) Latency: after a change the pool still holds old photons for pool size / impact
//! rate seconds (ghost light of a moved object), unless [`ChangePolicy::Flush`].
//! (4) Noise: VSL powers fluctuate with the pool's photon count (√K), seen as slow
//! flicker of whole regions when the pool is small. (5) Glossy transport is not
//! modelled (Lambertian only).
//!
//! ```
//! use illume_photon_stream::{PhotonStream, PhotonStreamSettings};
//! use illume_transport::{Budget, GBuffer, Technique, World};
//! let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
//! let settings = PhotonStreamSettings { vsl_count: 20, warm_up: false, ..PhotonStreamSettings::deterministic() };
//! let mut ps = PhotonStream::new(&world, settings).unwrap();
//! let w = world.read().unwrap();
//! ps.advance(&w, &Budget { work: Some(2000), ..Default::default() });
//! let g = GBuffer::render(&w, 16, 12, illume_core::Vec2::splat(0.5));
//! let indirect = ps.indirect(&w, &g);
//! assert!(indirect.mean().x > 0.0);
//! ps.validate().unwrap(); // Σ VSL power = Σ pooled photon power, exactly
//! ```

pub mod cull;
pub mod emit;
pub mod error;
pub mod interpolate;
pub mod near_field;
pub mod placement;
pub mod pool;
pub mod settings;
pub mod shade;
pub mod state;
pub mod stream;
pub mod update;
pub mod visibility;

pub use error::PhotonStreamError;
pub use placement::{Vsl, VslSet};
pub use pool::PhotonPool;
pub use settings::{
    ChangePolicy, PhotonStreamSettings, StreamMode, StreamPriority, VisibilityMode,
};
pub use state::PhotonStream;

/// The technique's one name: CLI value, settings table, counter and error prefix.
pub const NAME: &str = "photon_stream";

/// Photon streaming's registration: how the engine, the CLI and the window know it.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = PhotonStreamSettings;
    const SUMMARY: &'static str =
        "photon streaming with virtual surface lights (Meneveaux & Bridault 2008): interactive";
    const FRAME_HISTORY: illume_transport::FrameHistory = illume_transport::FrameHistory::Carried(
        "its photon pool and virtual surface lights build up over the frames",
    );
    const NEEDS_TIMELINE: bool = false;
    const AGREEMENT: illume_transport::Agreement =
        illume_transport::Agreement::CornellSpot(illume_transport::AgreementSpec {
            sets: &[
                "photon_stream.mode=deterministic",
                "photon_stream.pool_size=1000000",
                "photon_stream.photons_per_frame=400000",
                "photon_stream.warm_up=false",
            ],
            frames: 1,
            max_energy_error: 0.15,
            max_block_error: 0.32,
            why: "the paper's approximations are biased (100 VSLs for 27 m² of surface, one \
                  normal per VSL, no VSL visibility: over-illumination behind occluders); \
                  measured +6 % energy and 0.25 block error (docs/techniques/photon_stream.md)",
        });

    fn build(
        world: &illume_transport::SharedWorld,
        settings: &PhotonStreamSettings,
        _timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        Ok(Box::new(PhotonStream::new(world, settings.clone())?))
    }
}
