//! Temporal radiance caching — Gautron, Bouatouch & Pattanaik, *Temporal Radiance
//! Caching* (INRIA research report PI 1796, 2006;
//! `shared/papers/temporal-radiance-caching.md`).
//!
//! **What it approximates.** The indirect light of an animation known in advance
//! (objects, lights and camera moving along the timeline): the reference's `indirect`
//! image, frame by frame. Irradiance caching (Ward et al. 1988) computes the incoming
//! light at sparse records by gathering a hemisphere of rays and interpolates it between
//! them with Ward & Heckbert's gradients; radiance caching (Křivánek et al. 2005) does
//! the same for glossy surfaces with hemispherical harmonics. The paper extends both
//! over time: a record estimates how fast its irradiance changes (τ, from a reprojected
//! next-frame estimate), which gives it a lifespan (the temporal weighting function,
//! Eq. 9–12); while it lives it is reused, following temporal gradients extrapolated
//! from the next-frame estimate or interpolated towards the record that replaces it at
//! the same place. Reused records cost nothing and keep their positions, so animations
//! are cheaper and flicker less than with a new cache per frame.
//!
//! **Status.** Every mechanism of the paper is built and selectable
//! (`--technique radiance_cache` in `illume render`, `illume animate` and `illume
//! bench`), in four temporal modes: `per_frame` (the paper's baseline), `reuse`
//! (Fig. 5c), `extrapolated` (one pass, Fig. 5d) and `interpolated` (two passes, Fig.
//! 5e; the default). Glossy surfaces get radiance records (hemispherical harmonics)
//! for their specular lobe. Beyond the paper: replacement only on a surface, replacements
//! with their predecessor's rays, surprise expiry and a work budget in records per
//! frame, a smallest sphere of use on the image ([`placement`]), and neighbour aging
//! (§7's future work, off by default) ([`expiry`], [`budget`]).
//!
//! | paper | here |
//! |---|---|
//! | §3, Eq. 1–4: records, Ward's weight, usable set, gradients, interpolation | [`record`] |
//! | §5 (CPU counterpart): which records' spheres of influence contain a point (WRC88 octree) | [`octree`] |
//! | §4.2, Eq. 5–12: change rate τ, temporal weight, lifespan | [`temporal`] |
//! | §4.4, Eq. 13–23: contribution over time, extrapolated and interpolated temporal gradients | [`temporal`] |
//! | §3, radiance records for glossy surfaces (KGPB05, GKPB04): hemispherical harmonics | [`hsh`], [`radiance`] |
//! | §4.3, §5, Fig. 7–8: next-frame estimate by reprojection, hole filling | [`reproject`] |
//! | §6: the paper's parameters and the reasoned ones; presets `paper`, `still`, `fast` | [`settings`] |
//! | §4.2, §5, Fig. 6, 9: expiry — lifespans, replacement, deletion; neighbour aging (§7) | [`expiry`] |
//! | §4.3, §5: coarse-to-fine placement, a new record's lifespan and gradient from the next frame | [`placement`] |
//! | §3, Eq. 1, 17: shading from the records, glossy surfaces | [`shading`] |
//! | §4.4, Fig. 5: the temporal modes, pass 1 of `interpolated` and its plan | [`plan`] |
//! | beyond the paper: a work budget in records (or ms) per frame | [`budget`] |
//! | scene changes on and off the timeline (surprises) | [`update`] |
//! | the `Technique` the renderer drives: the frame loop over the stages | [`state`] |
//!
//! **Failure modes known from the paper.** (1) Ghosts: a record reused after the light
//! around it changed keeps showing the old light; the temporal weight sees only the
//! change between its first two frames, so a change that starts later (an object
//! entering its hemisphere, Fig. 4) is caught only when δt_max ends its life.
//! (2) Newly visible objects: the reprojected next-frame estimate has holes where
//! surfaces appear; they are filled from neighbouring cells, so τ misjudges light from
//! things not yet seen. (3) Flicker at replacement: without temporal gradients (the
//! `reuse` mode) the value jumps when a record is replaced (Fig. 5c); extrapolated
//! gradients shrink the jump (Fig. 5d), only interpolated ones remove it (Fig. 5e) at
//! the price of a first pass over the whole timeline. (4) Fast-changing light (a moving
//! light source, the paper's Moving Light and the start of Japanese Interior): lifespans
//! are short and reuse saves little (Table 1: no faster than a new cache per frame,
//! but without its flicker). (5) Spatial
//! interpolation errors of irradiance caching remain: Eq. 3 has no test for records in
//! front of the point (WRC88's), so light can leak under thin objects; the weight is
//! discontinuous at the sphere's edge.
//!
//! ```
//! use illume_core::{Rgb, Vec3};
//! use illume_radiance_cache::record::{HemisphereGather, IrradianceRecord, RecordSettings};
//! use illume_radiance_cache::temporal::{change_rate, lifespan_frames};
//! // A record under uniform radiance 1: E = π, no gradient.
//! let settings = RecordSettings { theta_strata: 8, phi_strata: 16, ..Default::default() };
//! let gather = HemisphereGather::from_fn(Vec3::Y, &settings, 0, |_| (Rgb::ONE, 2.0)).unwrap();
//! let record = IrradianceRecord::from_gather(Vec3::ZERO, &gather, 0, None, &settings);
//! assert!((record.value.irradiance.x - std::f32::consts::PI).abs() < 1e-5);
//! assert_eq!(record.value.translation_gradient.max_length(), 0.0);
//! // Its irradiance grows 2 % in a frame: a^t = 0.05 keeps it for 3 frames.
//! let change = change_rate(record.value.irradiance, record.value.irradiance * 1.02);
//! assert_eq!(lifespan_frames(change, 0.05, 20), 3);
//! ```

pub mod budget;
pub mod error;
pub mod expiry;
pub mod hsh;
pub mod octree;
pub mod placement;
pub mod plan;
pub mod radiance;
pub mod record;
pub mod reproject;
pub mod settings;
pub mod shading;
pub mod state;
pub mod temporal;
pub mod update;

pub use error::RadianceCacheError;
pub use octree::Octree;
pub use record::{
    CellPath, HemisphereGather, IrradianceRecord, IrradianceValue, RecordSettings, RgbGradient,
};
pub use settings::{RadianceCacheSettings, TemporalMode};
pub use state::RadianceCache;

/// The technique's one name: CLI value, settings table, counter and error prefix.
pub const NAME: &str = "radiance_cache";

/// Temporal radiance caching's registration: how the engine, the CLI and the window know
/// it.
pub struct Descriptor;

impl illume_transport::Registration for Descriptor {
    type Settings = RadianceCacheSettings;
    const SUMMARY: &'static str = "temporal radiance caching (Gautron et al. 2006): \
        animations known in advance, built with the timeline";
    const FRAME_HISTORY: illume_transport::FrameHistory =
        illume_transport::FrameHistory::Carried("its cache records are reused from frame to frame");
    const NEEDS_TIMELINE: bool = true;
    const AGREEMENT: illume_transport::Agreement =
        illume_transport::Agreement::CornellSpot(illume_transport::AgreementSpec {
            sets: &["radiance_cache.temporal=per_frame"],
            frames: 1,
            max_energy_error: 0.03,
            max_block_error: 0.06,
            why: "per_frame, the paper's values (a = 0.2, 64×64 rays per record, R_k clamped \
                  to [1 %, 50 %] of the scene diagonal and to E/|∇_p E|): consistent up to \
                  interpolation between records (Eq. 1 with Ward–Heckbert gradients) and \
                  each record's gather noise (4096 rays, Russian roulette after 3 bounces), \
                  which the interpolation spreads over its sphere of influence as smooth \
                  blotches; measured +0.6 % energy and 0.016 block error (sky: +0.2 %, \
                  0.011); the bounds leave room for other seeds and the reference's own \
                  noise (block ≈ 0.006)",
        });

    fn build(
        world: &illume_transport::SharedWorld,
        settings: &RadianceCacheSettings,
        timeline: &illume_scene::Timeline,
    ) -> Result<Box<dyn illume_transport::Technique>, illume_transport::TechniqueError> {
        let world = world.read().unwrap_or_else(|e| e.into_inner());
        Ok(Box::new(RadianceCache::new(
            &world,
            timeline,
            settings.clone(),
        )?))
    }
}
