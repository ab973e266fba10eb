//! The benchmark harness behind `illume bench`: every claim illume makes about a
//! technique (quality, stability, latency, speed) comes from one scenario file that any
//! user can run.
//!
//! A [`Scenario`] names a scene, an animation or scripted edits, the techniques with
//! their settings and budgets, the frames and the converged reference. [`run()`] replays it:
//!
//! 1. the **converged reference** of every distinct frame state is rendered with the
//!    reference path tracer, or read from the [cache] (key: scene, state and
//!    settings);
//! 2. each **technique** runs through the frames in the engine, edits applied as frame
//!    time passes them ([`Replay`]); each frame is timed and measured against its
//!    converged reference (RMSE, relMSE, FLIP by default), with flicker against the
//!    previous frame and the technique's counters;
//! 3. with `equal_time`, the **progressive reference path tracer** gets the same
//!    cumulative wall-clock time as the technique, frame by frame, and is measured the
//!    same way: the technique against brute force at equal cost;
//! 4. [`write_report`] writes `report.md`, `results.csv` and SVG plots (error vs time,
//!    fps per frame, latency after each event).
//!
//! The converged references are the heavy part; [`references_shard`] renders one
//! shard's share of them into the cache (`illume bench --shard K/N`, a Slurm job array:
//! `scripts/slurm/bench_refs.sbatch`), so that the plain run after the N shards only reads them.
//!
//! ```no_run
//! use illume_bench::{RunOptions, Scenario, Silent, run, write_report};
//! let scenario = Scenario::load("scenarios/moving_sphere.toml".as_ref()).unwrap();
//! let options = RunOptions::for_scenario(&scenario);
//! let outcome = run(&scenario, &options, &mut Silent).unwrap();
//! let files = write_report(&scenario, &outcome, &options).unwrap();
//! println!("{}", files.report_md.display());
//! ```
//!
//! The scenario format and the outputs are documented in `docs/bench.md`.

pub mod cache;
pub mod error;
pub mod replay;
pub mod report;
pub mod run;
pub mod scenario;

pub use cache::{CacheKey, HalfImages, ReferenceCache};
pub use error::BenchError;
pub use illume_core::{Progress, Silent};
pub use replay::{EditTarget, Replay};
pub use report::{ReportFiles, write_report};
pub use run::{
    BenchOutcome, Event, FrameRecord, RunOptions, SeriesSummary, ShardOutcome, references_shard,
    run,
};
pub use scenario::{EditSpec, ReferenceSpec, Scenario, TechniqueSpec};
