//! illume's foundation, shared by every other crate: math types and conventions
//! ([`math`]), index-addressable random and quasi-random sample sources with their
//! warps ([`sampling`]), HDR images with tone mapping and EXR/PNG I/O ([`image`]), named
//! counters ([`Counters`]), progress reports of long work ([`progress`]), guarded
//! reads of input files ([`files`]) and the `--shard K/N` split of offline work
//! ([`shard`]).
//!
//! Conventions (see `shared/DESIGN.md`): metres and seconds, right-handed with +Y up,
//! cameras look down −Z, colour is linear Rec.709 RGB radiometry, time is `f64` seconds.
//!
//! ```
//! use illume_core::sampling::{Pcg32, SampleStream};
//! let mut a = Pcg32::new(7, 42);
//! let mut b = Pcg32::new(7, 42);
//! assert_eq!(a.next_1d(), b.next_1d()); // same seed and stream ⇒ same numbers
//! ```

pub mod atomic;
pub mod counters;
pub mod cpu_time;
pub mod files;
pub mod image;
pub mod math;
pub mod outputs;
pub mod prefetch;
pub mod progress;
pub mod sampling;
pub mod shard;

pub use counters::Counters;
pub use math::*;
pub use prefetch::{PREFETCH_AHEAD, prefetch};
pub use progress::{Progress, Silent};
pub use shard::Shard;
