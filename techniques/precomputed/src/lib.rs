//! `precomputed`: precomputed indirect light for a day of sun, PCA-compressed, interpolated
//! at run time — Bahnsen, Dewilde, Pedersen, Tranchet & Madsen, *Realtime global
//! illumination using compressed pre-computed indirect illumination textures*, WSCG 2012.
//!
//! A frame at time t is Eq. 2 of the paper:
//! `L(t) = L_direct(t) + s(t)·L_sky + (1 − α)·L_N + α·L_{N+1}`:
//! the sun's direct light and shadows are the renderer's, the sky is rendered once and
//! scaled by s(t) ([`illume_scene::sun::sky_scale`]), and the sun's indirect light is
//! interpolated between the two nearest precomputed key frames.
//!
//! This crate holds the parts that do not need a renderer:
//!
//! - [`pca`]: the PCA of the key images (§3.2, Fig. 5);
//! - [`schedule`]: uniform (Eq. 1, 3) and adaptive (§3.2, Fig. 6) key times, and the
//!   binary search + α of non-uniform keys;
//! - [`file`](mod@file): the versioned `.illumepc` file (magic, TOML header, checksummed
//!   sections);
//! - [`shard`]: `--shard K/N` over machines, the adaptive schedule level by level
//!   (`--level L`), and the merge; bit for bit the unsharded file;
//! - [`domain`]: where keys live (`screen`, `cube`, `atlas`) and how each renders them;
//! - [`atlas`]: the `atlas` domain's lightmap coordinates and probe grid.
//! - [`cli`]: `illume precompute` (render keys, `merge`, `info`), the registration's
//!   offline command that the CLI mounts;
//!
//! and the run time (the [`Technique`](illume_transport::Technique), [`state`]):
//!
//! - [`load`]: the file checked against the scene, camera and image size (§4.2);
//! - [`reconstruct`]: Eq. 2 — coefficients interpolated between keys, texels rebuilt (§3.1);
//! - [`lookup`]: per domain, which texels a pixel reads;
//! - [`update`]: scene changes → a stale file (warned, never rebuilt).
//!
//! # Limits (as in the paper)
//! One day and one place per file; static geometry; Lambertian materials only (§3.1: no
//! reflective objects); dynamic objects leave the indirect light unchanged (they neither
//! block it nor bleed colour).

pub mod atlas;
pub mod cli;
pub mod domain;
pub mod error;
pub mod file;
pub mod load;
pub mod lookup;
pub mod pca;
pub mod precompute;
pub mod reconstruct;
pub mod schedule;
pub mod settings;
pub mod shard;
pub mod state;
pub mod update;

pub use error::PrecomputedError;
pub use settings::PrecomputedSettings;
pub use state::Precomputed;

/// The technique's one name.
pub const NAME: &str = "precomputed";

/// Precomputed indirect light's registration: how the engine, the CLI and the window
/// know it.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = PrecomputedSettings;
    const SUMMARY: &'static str = "precomputed indirect light for a day of sun, PCA-compressed \
        (Bahnsen et al. 2012): needs a scene with a [sun] and a .illumepc file (--data)";
    const FRAME_HISTORY: illume_transport::FrameHistory = illume_transport::FrameHistory::Carried(
        "it is interactive: the renderer picks shadow maps or rays per frame from costs \
         measured on the frames before",
    );
    const NEEDS_TIMELINE: bool = true;
    const AGREEMENT: illume_transport::Agreement = illume_transport::Agreement::Elsewhere(
        "needs a scene with a sun path and a precomputed day, which cornell-spot has not: \
         techniques/precomputed/tests/sun_room.rs",
    );

    const DATA_KEY: Option<&'static str> = Some("data");
    const OFFLINE: Option<illume_transport::OfflineCommand> = Some(cli::OFFLINE);

    fn build(
        world: &illume_transport::SharedWorld,
        settings: &PrecomputedSettings,
        timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        let world = world.read().unwrap_or_else(|e| e.into_inner());
        Ok(Box::new(Precomputed::new(
            &world,
            settings.clone(),
            timeline.width(),
            timeline.height(),
        )?))
    }

    /// With a file: a scene without a `[sun]` gets the file's sun (the direct light must
    /// follow the sun the keys were rendered with).
    fn prepare_scene(
        scene: &mut illume_scene::Scene,
        settings: &PrecomputedSettings,
    ) -> Result<(), illume_transport::TechniqueError> {
        state::attach_file_sun(scene, settings)?;
        Ok(())
    }
}
