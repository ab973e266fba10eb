//! Light transport shared by every technique.
//!
//! * [`World`] — a scene together with its [`Tracer`](illume_accel::Tracer) and
//!   [`LightSet`], kept consistent under time changes and edits.
//! * [`SurfaceHit`] — what a ray hit: position, normals, albedo, emission, sidedness.
//! * [`hit_tables`] — per-instance frames and packed textures behind cheap photon hits.
//! * [`lights`] — light selection proportional to power, direct-light sampling (next-event
//!   estimation) and emission sampling for every light type.
//! * [`bsdf`] — the Lambertian BSDF with cosine-weighted sampling, Russian roulette.
//! * [`metal_rough`] — the glTF 2.0 metallic-roughness BRDF (GGX, height-correlated
//!   Smith, Schlick Fresnel): evaluation, visible-normal sampling and its pdf.
//! * [`nearest`] — exact nearest-point indices (grid + k-d tree) over fixed points.
//! * [`path`] — radiance arriving along a ray: path tracing with next-event estimation
//!   and MIS, shared by the reference and every technique that gathers radiance.
//! * [`flux`] — signed fixed-point photon power: exact, order-independent adding and
//!   removing of photons.
//! * [`photon`] — the photon-path generator: a pure function of an addressable
//!   [`SampleStream`](illume_core::sampling::SampleStream) (same index ⇒ same path).
//! * [`gbuffer`] — the per-pixel primary-hit buffer a technique shades.
//! * [`raster`] — the CPU visibility-buffer rasterizer behind [`GBuffer::rasterize`].
//! * [`technique`] — the [`Technique`] trait every GI technique implements.
//!
//! Radiometric conventions follow `shared/DESIGN.md`: lights and pixels carry linear RGB
//! radiometry (W, W/sr, W/m², W/(m²·sr)).

pub mod bsdf;
pub mod camera;
pub mod directional_albedo;
pub mod flux;
pub mod gbuffer;
pub mod hit_tables;
pub mod lights;
pub mod metal_rough;
pub mod mip;
pub mod nearest;
pub mod path;
pub mod photon;
pub mod raster;
pub mod surface;
pub mod technique;
pub mod world;

pub use camera::CameraRays;
pub use gbuffer::{GBuffer, GBufferPixel, TextureFilter};
pub use lights::{EmissionSample, LightSample, LightSet};
pub use raster::VisibilityBuffer;
pub use surface::SurfaceHit;
pub use technique::{
    Agreement, AgreementSpec, Applies, Budget, ChangeResponse, FrameHistory, OfflineCommand,
    OfflineError, OfflineHost, OfflineProgress, OfflineSettings, Pacing, Registration,
    SettingBound, SettingBounds, SettingField, SettingValues, SettingsTable, StillFn, StillImages,
    Technique, TechniqueError, TechniqueSettings,
};
pub use world::{SharedWorld, World};
