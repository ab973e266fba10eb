//! The reference path tracer: illume's ground truth, against which every technique is
//! measured.
//!
//! Unidirectional path tracing from the camera with next-event estimation at every
//! vertex, multiple importance sampling (power heuristic) between light sampling and
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
//! As a [`Technique`](illume_transport::Technique) (`reference`), it supplies the
//! indirect light of G-buffer points by path tracing from them, accumulating over frames
//! while nothing changes.
//!
//! ```
//! use illume_reference::{ReferenceRenderer, ReferenceSettings};
//! use illume_transport::World;
//! let world = World::new(illume_scene::builtin::load("furnace").unwrap());
//! let mut r = ReferenceRenderer::new(ReferenceSettings { width: 8, height: 8, ..Default::default() });
//! r.add_samples(&world, 64);
//! let mean = r.images().full.mean();
//! assert!((mean.x - 2.0).abs() < 0.1); // furnace: Le/(1 − ρ) = 2
//! ```

pub mod settings;
pub mod state;
pub mod trace;
pub mod update;

pub use settings::ReferenceSettings;
pub use state::{ReferenceRenderer, SplitImages};
pub use update::ReferenceTechnique;
