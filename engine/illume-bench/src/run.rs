//! Running a scenario: converged references (cached), each technique frame by frame,
//! the equal-time path tracer, then the per-frame and per-series measurements.

use crate::cache::{CacheKey, HalfImages, ReferenceCache};
use crate::error::BenchError;
use crate::replay::Replay;
use crate::scenario::Scenario;
use illume_core::image::{RgbImage, ToneMap};
use illume_core::{Progress, Shard};
use illume_engine::{Config, Engine, StepRecord};
use illume_metrics::{Counters, Metric, compare_images, flicker, latency_after_event};
use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_scene::{Scene, Timeline};
use illume_transport::World;
use illume_transport::{Budget, Pacing};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where a run writes and what extra it keeps.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The report folder (`report.md`, `results.csv`, plots).
    pub output_dir: PathBuf,
    /// The converged-reference cache folder.
    pub cache_dir: PathBuf,
    /// Also write every frame of every series and of the reference as PNG under
    /// `output_dir/frames/SERIES/NNNN.png`.
    pub save_frames: bool,
    /// Lines added under the report's title (e.g. the command line).
    pub notes: Vec<String>,
}

impl RunOptions {
    /// The defaults for `scenario`: `out/bench/<name>/` and `out/cache/`.
    pub fn for_scenario(scenario: &Scenario) -> Self {
        Self {
            output_dir: Path::new("out/bench").join(file_safe(&scenario.name)),
            cache_dir: PathBuf::from("out/cache"),
            save_frames: false,
            notes: Vec::new(),
        }
    }
}

/// Seed offset of the equal-time path tracer, so its samples are independent of the
/// converged reference's (same seed would correlate the two and understate the error).
pub const EQUAL_TIME_SEED_OFFSET: u64 = 0x9e37_79b9_7f4a_7c15;

/// `(metric, value)` for each of a scenario's metrics, in its order.
pub type MetricValues = Vec<(Metric, f64)>;

/// One frame of one series, measured against the converged reference.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameRecord {
    /// The series: a technique's label, or `reference (equal time to LABEL)`.
    pub series: String,
    /// The technique name (`reference` for the equal-time path tracer).
    pub technique: String,
    /// Frame index.
    pub frame: usize,
    /// Scene time \[s\].
    pub time_s: f64,
    /// Wall-clock time of the frame \[ms\]: edits, time step, the technique's update and
    /// advance, and rendering (equal-time series: the path tracer's time).
    pub frame_ms: f64,
    /// Each scenario metric against the converged reference (empty on frames not in
    /// `reference_frames`).
    pub metrics: Vec<(Metric, f64)>,
    /// Each scenario metric against the technique's own converged image of the frame's
    /// state (`own_converged_frames`; empty when off or not measured).
    pub own_metrics: Vec<(Metric, f64)>,
    /// Flicker between this frame and the previous one (`None` on frame 0 and where
    /// either frame is not measured).
    pub flicker: Option<f64>,
    /// Technique counters after the frame, plus `engine.*` stage timings \[ms\].
    pub counters: Counters,
}

impl FrameRecord {
    /// The value of `metric`, if measured.
    pub fn metric(&self, metric: Metric) -> Option<f64> {
        self.metrics
            .iter()
            .find(|(m, _)| *m == metric)
            .map(|&(_, v)| v)
    }

    /// The value of `metric` against the technique's own converged image, if measured.
    pub fn own_metric(&self, metric: Metric) -> Option<f64> {
        self.own_metrics
            .iter()
            .find(|(m, _)| *m == metric)
            .map(|&(_, v)| v)
    }
}

/// How long the error took to settle after an event.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventLatency {
    /// Frames from the event's frame to the first measured frame from which the error
    /// stays below the threshold (up to the next event); `None` if it never settles or
    /// no frame after the event is measured.
    pub frames: Option<usize>,
    /// The same in scene seconds (difference of frame times).
    pub seconds: Option<f64>,
    /// The same in wall-clock seconds: the measured times of the frames rendered after
    /// the event's frame up to and including the settled one (precompute excluded) —
    /// how long a viewer waits, at this technique's speed.
    pub wall_seconds: Option<f64>,
}

/// A moment after which the error is expected to rise and then settle.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// `start`, `animation end`, or the edit's label.
    pub name: String,
    /// When it happens \[s\].
    pub at_s: f64,
    /// The first frame that shows it.
    pub frame: usize,
}

/// Everything measured for one series.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesSummary {
    /// The series name.
    pub series: String,
    /// The technique name.
    pub technique: String,
    /// Median frame time \[ms\] (precompute excluded).
    pub median_frame_ms: f64,
    /// Time in the technique's precompute phase \[ms\]: before the first frame and in
    /// rebuilds (counter `engine.precompute_ms`, summed over frames).
    pub precompute_ms: f64,
    /// `(metric, mean, max)` over the measured frames (NaN when none is measured).
    pub metrics: Vec<(Metric, f64, f64)>,
    /// `(metric, mean, max)` against the technique's own converged images (empty when
    /// `own_converged_frames` is 0).
    pub own_metrics: Vec<(Metric, f64, f64)>,
    /// `(mean, max)` flicker over consecutive frame pairs (`None` with one frame).
    pub flicker: Option<(f64, f64)>,
    /// Latency after each of [`BenchOutcome::events`], in the same order: until the
    /// error against the converged reference stays below `latency_threshold` up to the
    /// next event on a later frame (or the last frame).
    pub latencies: Vec<EventLatency>,
    /// Latency after each event against the technique's own converged images, with
    /// `own_latency_threshold` (empty when `own_converged_frames` is 0): the time to
    /// reach its own steady state.
    pub own_latencies: Vec<EventLatency>,
}

/// The result of [`run`].
#[derive(Clone, Debug)]
pub struct BenchOutcome {
    /// The frame times \[s\].
    pub times_s: Vec<f64>,
    /// The events latency is measured after.
    pub events: Vec<Event>,
    /// One record per series per frame, series by series.
    pub records: Vec<FrameRecord>,
    /// One summary per series, in run order.
    pub summaries: Vec<SeriesSummary>,
    /// Converged references read from the cache.
    pub cache_hits: usize,
    /// Converged references rendered (and stored in the cache).
    pub cache_renders: usize,
    /// The cache key of each frame's converged reference.
    pub reference_keys: Vec<CacheKey>,
    /// The converged reference's own noise at each frame: `(metric, value)` between the
    /// two independent halves of its samples (⌊spp/2⌋ each), for each of the scenario's
    /// metrics. None for a frame not measured, or whose cached reference was stored
    /// without its half (rendered before halves were kept). A series whose error is
    /// near this is measuring the reference's noise, not its own.
    pub reference_noise: Vec<Option<MetricValues>>,
}

/// The converged reference settings of `scenario`.
pub fn reference_settings(scenario: &Scenario) -> ReferenceSettings {
    ReferenceSettings {
        spp: scenario.reference.spp,
        seed: scenario.reference.seed,
        rr_start_depth: scenario.reference.rr_start_depth,
        ..ReferenceSettings::default()
    }
}

/// Runs `scenario`: renders or reuses the converged references, runs each technique
/// (and, with `equal_time`, the path tracer at each technique's frame times), and
/// measures every frame. Writes only the cache and, with `save_frames`, the frames;
/// [`crate::write_report`] writes the report.
pub fn run(
    scenario: &Scenario,
    options: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<BenchOutcome, BenchError> {
    let times = scenario.frame_times();
    let scene = scenario.load_scene()?;
    for w in &scene.warnings {
        progress.message(&format!("warning: {w}"));
    }
    let identity = scenario.scene_identity()?;
    let settings = reference_settings(scenario);
    let keys = reference_keys(scenario, &scene, &identity, &settings, &times)?;
    let measured = scenario.measured_frames(times.len());
    let mut cache = ReferenceCache::new(&options.cache_dir);
    let references = converged_references(
        scenario,
        &scene,
        &times,
        &keys,
        &measured,
        &settings,
        Shard::default(),
        &mut cache,
        progress,
    )?;
    progress.message(&format!(
        "converged references: {} distinct, {} from the cache, {} rendered ({})",
        references.unique,
        cache.hits,
        cache.renders,
        cache.dir().display()
    ));
    let out = if options.save_frames {
        Some(illume_core::outputs::OutputDir::create(
            &options.output_dir,
        )?)
    } else {
        None
    };
    if let Some(out) = &out {
        for (i, r) in references.per_frame().enumerate() {
            if let Some(r) = r {
                save_frame(out, CONVERGED_FRAMES, i, r)?;
            }
        }
    }
    let events = events(scenario, &scene, &times, progress);

    let mut records = Vec::new();
    for k in 0..scenario.techniques.len() {
        let label = scenario.techniques[k].label().to_owned();
        let (technique_records, images) = run_technique(
            scenario,
            k,
            &scene,
            &times,
            &references,
            options.save_frames,
            progress,
        )?;
        let frame_ms: Vec<f64> = technique_records.iter().map(|r| r.frame_ms).collect();
        if let Some(out) = &out {
            for (i, img) in images.iter().enumerate() {
                save_frame(out, &file_safe(&label), i, img)?;
            }
        }
        records.extend(technique_records);
        if scenario.reference.equal_time {
            let (equal, images) = run_equal_time(
                scenario,
                &label,
                &scene,
                &times,
                &keys,
                &references,
                &frame_ms,
                options.save_frames,
                progress,
            )?;
            let series = equal_time_series(&label);
            if let Some(out) = &out {
                for (i, img) in images.iter().enumerate() {
                    save_frame(out, &file_safe(&series), i, img)?;
                }
            }
            records.extend(equal);
        }
    }
    let summaries = summarize(scenario, &records, &times, &events, &measured)?;
    let reference_noise = reference_noise(scenario, &references)?;
    Ok(BenchOutcome {
        times_s: times,
        events,
        records,
        summaries,
        cache_hits: cache.hits,
        cache_renders: cache.renders,
        reference_keys: keys,
        reference_noise,
    })
}

impl BenchOutcome {
    /// `(metric, mean, max, frames)` of [`BenchOutcome::reference_noise`] over the frames
    /// that have it, in the scenario's metric order; empty when no frame has it.
    pub fn reference_noise_summary(&self) -> Vec<(Metric, f64, f64, usize)> {
        let measured: Vec<&Vec<(Metric, f64)>> = self.reference_noise.iter().flatten().collect();
        let Some(first) = measured.first() else {
            return Vec::new();
        };
        first
            .iter()
            .enumerate()
            .map(|(j, &(metric, _))| {
                let values: Vec<f64> = measured.iter().map(|v| v[j].1).collect();
                let mean = values.iter().sum::<f64>() / values.len() as f64;
                let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                (metric, mean, max, values.len())
            })
            .collect()
    }
}

/// [`BenchOutcome::reference_noise`]: the scenario's metrics between each distinct
/// reference's halves, measured once and given to each frame that shows it.
fn reference_noise(
    scenario: &Scenario,
    references: &References,
) -> Result<Vec<Option<MetricValues>>, BenchError> {
    let per_image = references
        .halves
        .iter()
        .map(|h| {
            h.as_ref()
                .map(|h| compare_images(&h.first, &h.second, &scenario.metrics))
                .transpose()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(references
        .frame_image
        .iter()
        .map(|k| k.and_then(|k| per_image[k].clone()))
        .collect())
}

/// The series name of the equal-time path tracer matched to technique `label`.
pub fn equal_time_series(label: &str) -> String {
    format!("reference (equal time to {label})")
}

/// The cache key of each frame: the scene replayed through the scenario's edits and
/// times exactly as the techniques will see it.
fn reference_keys(
    scenario: &Scenario,
    scene: &Scene,
    identity: &str,
    settings: &ReferenceSettings,
    times: &[f64],
) -> Result<Vec<CacheKey>, BenchError> {
    let mut state = scene.clone();
    let mut replay = Replay::new(scenario);
    let mut keys = Vec::with_capacity(times.len());
    for &t in times {
        replay.apply_due(&mut state, t)?;
        state.set_time(t);
        keys.push(CacheKey::new(
            identity,
            &state,
            settings,
            (scenario.width, scenario.height),
        ));
    }
    Ok(keys)
}

/// What [`references_shard`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardOutcome {
    /// Distinct converged references of the whole scenario (all shards).
    pub distinct: usize,
    /// Those that belong to this shard.
    pub mine: usize,
    /// Of this shard's, how many the cache already held.
    pub cache_hits: usize,
    /// Of this shard's, how many were rendered (and stored).
    pub cache_renders: usize,
}

/// Renders shard `shard`'s share of `scenario`'s converged references into the cache
/// (`options.cache_dir`), and nothing else: no technique runs, no report is written.
///
/// The share: the scenario's distinct reference states (frames of a still scene share
/// one), numbered in frame order, those with number j mod N = K. Each image is what the
/// unsharded run renders (same state, settings and seed: the same cache key and pixels),
/// so after the N shards a plain [`run`] with the same cache finds every reference there.
pub fn references_shard(
    scenario: &Scenario,
    options: &RunOptions,
    shard: Shard,
    progress: &mut dyn Progress,
) -> Result<ShardOutcome, BenchError> {
    let times = scenario.frame_times();
    let scene = scenario.load_scene()?;
    let identity = scenario.scene_identity()?;
    let settings = reference_settings(scenario);
    let keys = reference_keys(scenario, &scene, &identity, &settings, &times)?;
    let measured = scenario.measured_frames(times.len());
    let mut cache = ReferenceCache::new(&options.cache_dir);
    let references = converged_references(
        scenario, &scene, &times, &keys, &measured, &settings, shard, &mut cache, progress,
    )?;
    Ok(ShardOutcome {
        distinct: references.unique,
        mine: references.images.iter().filter(|i| i.is_some()).count(),
        cache_hits: cache.hits,
        cache_renders: cache.renders,
    })
}

/// The converged references: distinct images and which one each frame uses.
/// Frames outside `reference_frames` have none; with a shard, only its images are there.
struct References {
    images: Vec<Option<RgbImage>>,
    /// Each image's two halves, when rendered (or cached) with them.
    halves: Vec<Option<HalfImages>>,
    frame_image: Vec<Option<usize>>,
    unique: usize,
}

impl References {
    fn frame(&self, i: usize) -> Option<&RgbImage> {
        self.frame_image[i].and_then(|k| self.images[k].as_ref())
    }

    fn per_frame(&self) -> impl Iterator<Item = Option<&RgbImage>> {
        self.frame_image
            .iter()
            .map(|k| k.and_then(|k| self.images[k].as_ref()))
    }
}

#[expect(
    clippy::too_many_arguments,
    reason = "the run's shared inputs; bundling them would only rename them"
)]
fn converged_references(
    scenario: &Scenario,
    scene: &Scene,
    times: &[f64],
    keys: &[CacheKey],
    measured: &[bool],
    settings: &ReferenceSettings,
    shard: Shard,
    cache: &mut ReferenceCache,
    progress: &mut dyn Progress,
) -> Result<References, BenchError> {
    let mut unique: HashMap<u64, usize> = HashMap::new();
    let mut to_render = 0u64;
    for (k, _) in keys.iter().zip(measured).filter(|(_, m)| **m) {
        if !unique.contains_key(&k.hash) {
            let slot = unique.len();
            unique.insert(k.hash, slot);
            if shard.owns(slot) && !cache.contains(k) {
                to_render += 1;
            }
        }
    }
    let spp = settings.spp;
    if to_render > 0 {
        progress.begin("converged reference", to_render * u64::from(spp));
    }
    let mut images: Vec<Option<RgbImage>> = vec![None; unique.len()];
    let mut halves: Vec<Option<HalfImages>> = vec![None; unique.len()];
    let mut world = World::new(scene.clone());
    let mut replay = Replay::new(scenario);
    let mut rendered = 0u64;
    for ((key, &t), _) in keys.iter().zip(times).zip(measured).filter(|(_, m)| **m) {
        replay.apply_due(&mut world, t)?;
        world.set_time(t);
        let slot = unique[&key.hash];
        // The world above still steps through every measured frame, as unsharded.
        if images[slot].is_some() || !shard.owns(slot) {
            continue;
        }
        let size = (scenario.width, scenario.height);
        let (image, first_half) = cache.get_or_render(key, size, || {
            let mut r = ReferenceRenderer::new(settings.clone(), scenario.width, scenario.height);
            // Chunks keep the bar moving; the image does not depend on the chunking, so
            // stopping at the half to keep its mean changes nothing.
            let chunk = (spp / 16).max(1);
            let half_spp = spp / 2;
            let mut first_half = None;
            while r.samples() < spp {
                let until = if r.samples() < half_spp {
                    half_spp
                } else {
                    spp
                };
                r.add_samples(&world, chunk.min(until - r.samples()));
                if r.samples() == half_spp {
                    first_half = Some(r.images().full);
                }
                progress.set(rendered * u64::from(spp) + u64::from(r.samples()));
            }
            rendered += 1;
            (r.images().full, first_half)
        })?;
        halves[slot] = first_half.and_then(|h| HalfImages::new(&image, h, spp));
        images[slot] = Some(image);
    }
    if to_render > 0 {
        progress.end();
    }
    let frame_image = keys
        .iter()
        .zip(measured)
        .map(|(k, &m)| m.then(|| unique[&k.hash]))
        .collect();
    Ok(References {
        images,
        halves,
        frame_image,
        unique: unique.len(),
    })
}

/// The events: `start` (frame 0), `animation end` when the animation ends inside the run,
/// and each scripted edit that falls inside the run.
fn events(
    scenario: &Scenario,
    scene: &Scene,
    times: &[f64],
    progress: &mut dyn Progress,
) -> Vec<Event> {
    let first_frame_at = |t: f64| times.iter().position(|&ft| ft >= t);
    let mut events = vec![Event {
        name: if scenario.animation.is_some() {
            "start (animation starts)".into()
        } else {
            "start".into()
        },
        at_s: times[0],
        frame: 0,
    }];
    if scenario.animation.is_some() {
        let end = scene.animation_duration();
        if let Some(frame) = first_frame_at(end).filter(|&f| f > 0) {
            events.push(Event {
                name: "animation end".into(),
                at_s: end,
                frame,
            });
        }
    }
    for index in scenario.edit_order() {
        let at_s = scenario.edits[index].at_s;
        match first_frame_at(at_s) {
            Some(frame) => events.push(Event {
                name: scenario.edit_label(index),
                at_s,
                frame,
            }),
            None => progress.message(&format!(
                "warning: {}: edit[{index}] at {at_s} s is after the last frame; never applied",
                scenario.file.display()
            )),
        }
    }
    events
}

/// One timed frame before measurement.
struct TimedFrame {
    time_s: f64,
    frame_ms: f64,
    image: RgbImage,
    counters: Counters,
}

/// Runs technique entry `k` over the frames and measures them; returns its records and,
/// with `keep_frames`, its frames. The frames are measured after the timed loop, so a
/// technique with a background thread (photon streaming) gets no untimed work time
/// between frames.
fn run_technique(
    scenario: &Scenario,
    k: usize,
    scene: &Scene,
    times: &[f64],
    references: &References,
    keep_frames: bool,
    progress: &mut dyn Progress,
) -> Result<(Vec<FrameRecord>, Vec<RgbImage>), BenchError> {
    let spec = &scenario.techniques[k];
    let config = scenario.technique_config(k)?;
    let technique_error = |e: illume_engine::EngineError| BenchError::Technique {
        path: scenario.file.clone(),
        index: k,
        name: spec.name.clone(),
        message: e.to_string(),
    };
    let mut engine = technique_engine(scenario, k, &config, scene, times)?;
    engine.set_budget(scenario.technique_budget(k, &config));
    let precompute_ms = engine.precompute(progress).map_err(technique_error)?;
    let mut replay = Replay::new(scenario);
    let mut frames = Vec::with_capacity(times.len());
    progress.begin(spec.label(), times.len() as u64);
    for (i, &t) in times.iter().enumerate() {
        let start = Instant::now();
        replay.apply_due(&mut engine, t)?;
        let out = engine.step(t).map_err(technique_error)?;
        let frame_ms = start.elapsed().as_secs_f64() * 1e3 - out.precompute_ms;
        let mut counters = out.stats.clone();
        // The precompute phase is timed apart from the frames: it is on frame 0's row
        // (plus any rebuild a frame's changes caused), not in its frame_ms.
        let earlier_ms = if i == 0 { precompute_ms } else { 0.0 };
        StepRecord::from_step(t, &out, earlier_ms).set_engine_counters(&mut counters);
        frames.push(TimedFrame {
            time_s: t,
            frame_ms,
            image: out.frame.full,
            counters,
        });
        progress.set(i as u64 + 1);
    }
    progress.end();
    // Stop the technique (and any thread it runs) before measuring.
    drop(engine);
    // A supersampled entry's frames, averaged back to the scenario's pixels (after the
    // timed loop: the averaging is the bench's, not the technique's).
    let supersample = spec.supersample();
    if supersample > 1 {
        for f in &mut frames {
            f.image = f.image.box_downsample(supersample);
        }
    }
    let own = if scenario.own_converged_frames > 0 {
        Some(own_converged_images(
            scenario, k, &config, scene, times, references, progress,
        )?)
    } else {
        None
    };
    measure_series(
        scenario,
        spec.label(),
        &spec.name,
        frames,
        references,
        own.as_deref(),
        keep_frames,
    )
}

/// An engine for technique entry `k` with `config` on `scene`, whose timeline is the
/// scenario's frame times (scripted edits stay surprises).
fn technique_engine(
    scenario: &Scenario,
    k: usize,
    config: &Config,
    scene: &Scene,
    times: &[f64],
) -> Result<Engine, BenchError> {
    let error = |message: String| BenchError::Technique {
        path: scenario.file.clone(),
        index: k,
        name: scenario.techniques[k].name.clone(),
        message,
    };
    // The size the technique renders at (K times the scenario's when supersampled).
    let timeline = Timeline::new(
        scene.clone(),
        times.to_vec(),
        config.render.width,
        config.render.height,
    )
    .map_err(|e| error(e.to_string()))?;
    Engine::with_timeline(scene.clone(), config, timeline).map_err(|e| error(e.to_string()))
}

/// Technique entry `k`'s own converged image of each measured frame's state: the same
/// technique and settings built fresh on the scene with the scenario's edits due at the
/// frame's time already applied (so the technique never sees them as changes), then
/// `own_converged_frames` frames at that time with fixed work per frame (the technique's
/// default budget), so the result does not depend on the machine's speed. The last of
/// them is rendered with the measured frame's index, so the renderer's random numbers
/// (area-light samples) are the measured frame's.
fn own_converged_images(
    scenario: &Scenario,
    k: usize,
    config: &Config,
    scene: &Scene,
    times: &[f64],
    references: &References,
    progress: &mut dyn Progress,
) -> Result<Vec<Option<RgbImage>>, BenchError> {
    let spec = &scenario.techniques[k];
    let technique_error = |e: illume_engine::EngineError| BenchError::Technique {
        path: scenario.file.clone(),
        index: k,
        name: spec.name.clone(),
        message: format!("own converged image: {e}"),
    };
    let mut config = config.clone();
    config.technique_settings_mut().pace(Pacing::FixedWork {
        work_per_frame: None,
    });
    let budget = Budget {
        work: config.technique_settings().default_budget().work,
        time_ms: None,
    };
    let wanted: Vec<usize> = (0..times.len())
        .filter(|&i| references.frame(i).is_some())
        .collect();
    let steps = u64::from(scenario.own_converged_frames);
    progress.begin(
        &format!("{} own converged", spec.label()),
        wanted.len() as u64 * steps,
    );
    let mut images = vec![None; times.len()];
    for (n, &i) in wanted.iter().enumerate() {
        let t = times[i];
        // The technique starts on the edited scene: the state is its starting point, not
        // a change it would have to catch up with.
        let mut state = scene.clone();
        Replay::new(scenario).apply_due(&mut state, t)?;
        let mut engine = technique_engine(scenario, k, &config, &state, times)?;
        engine.set_budget(budget);
        let mut last = None;
        for step in 0..steps {
            if step + 1 == steps {
                // The measured frame's random numbers (area-light samples), so that
                // direct-light noise does not count as distance from the steady state.
                engine.set_frame_index(i as u64);
            }
            last = Some(engine.step(t).map_err(technique_error)?.frame.full);
            progress.set(n as u64 * steps + step + 1);
        }
        if let Some(image) = &mut last
            && spec.supersample() > 1
        {
            *image = image.box_downsample(spec.supersample());
        }
        images[i] = last;
    }
    progress.end();
    Ok(images)
}

/// Measures each frame against its converged reference and the previous frame (flicker).
fn measure_series(
    scenario: &Scenario,
    series: &str,
    technique: &str,
    frames: Vec<TimedFrame>,
    references: &References,
    own: Option<&[Option<RgbImage>]>,
    keep_frames: bool,
) -> Result<(Vec<FrameRecord>, Vec<RgbImage>), BenchError> {
    let mut records = Vec::with_capacity(frames.len());
    for (i, f) in frames.iter().enumerate() {
        let reference = references.frame(i);
        let metrics = match reference {
            Some(r) => compare_images(r, &f.image, &scenario.metrics)?,
            None => Vec::new(),
        };
        let own_metrics = match own.and_then(|o| o[i].as_ref()) {
            Some(o) => compare_images(o, &f.image, &scenario.metrics)?,
            None => Vec::new(),
        };
        let flicker = match (i, reference) {
            (0, _) | (_, None) => None,
            (_, Some(reference)) => match references.frame(i - 1) {
                None => None,
                Some(previous) => Some(
                    flicker(
                        &[frames[i - 1].image.clone(), f.image.clone()],
                        &[previous.clone(), reference.clone()],
                    )?
                    .mean,
                ),
            },
        };
        records.push(FrameRecord {
            series: series.to_owned(),
            technique: technique.to_owned(),
            frame: i,
            time_s: f.time_s,
            frame_ms: f.frame_ms,
            metrics,
            own_metrics,
            flicker,
            counters: f.counters.clone(),
        });
    }
    let kept = if keep_frames {
        frames.into_iter().map(|f| f.image).collect()
    } else {
        Vec::new()
    };
    Ok((records, kept))
}

/// The progressive reference path tracer at equal cost: frame `i` adds `frame_ms[i]`
/// of wall-clock credit, and the tracer runs whole passes (one sample per pixel each)
/// while the remaining credit covers at least half a pass (the last pass predicts the
/// next), so its total time tracks the technique's total to within half a pass. Frames
/// the credit does not cover show the last image, as an interactive path tracer would;
/// the first frame always gets one pass (a debt repaid by later frames). Accumulation
/// restarts, at the next pass, when the frame's converged-reference key (the scene
/// state) changes; until that pass the stale image stays on screen.
#[expect(
    clippy::too_many_arguments,
    reason = "the run's shared inputs; bundling them would only rename them"
)]
fn run_equal_time(
    scenario: &Scenario,
    label: &str,
    scene: &Scene,
    times: &[f64],
    keys: &[CacheKey],
    references: &References,
    frame_ms: &[f64],
    keep_frames: bool,
    progress: &mut dyn Progress,
) -> Result<(Vec<FrameRecord>, Vec<RgbImage>), BenchError> {
    let series = equal_time_series(label);
    let mut settings = reference_settings(scenario);
    settings.seed = settings.seed.wrapping_add(EQUAL_TIME_SEED_OFFSET);
    let mut tracer = ReferenceRenderer::new(settings, scenario.width, scenario.height);
    let mut world = World::new(scene.clone());
    let mut replay = Replay::new(scenario);
    let mut frames: Vec<TimedFrame> = Vec::with_capacity(times.len());
    let mut credit_ms = 0.0;
    let mut pass_ms = 0.0;
    let mut stale = false;
    progress.begin(&series, times.len() as u64);
    for (i, &t) in times.iter().enumerate() {
        let start = Instant::now();
        credit_ms += frame_ms[i];
        replay.apply_due(&mut world, t)?;
        world.set_time(t);
        stale |= i > 0 && keys[i].hash != keys[i - 1].hash;
        let mut passes = 0u32;
        while i == 0 && passes == 0
            || credit_ms - start.elapsed().as_secs_f64() * 1e3 >= 0.5 * pass_ms
        {
            if stale {
                tracer.reset();
                stale = false;
            }
            let pass = Instant::now();
            tracer.add_samples(&world, 1);
            pass_ms = pass.elapsed().as_secs_f64() * 1e3;
            passes += 1;
        }
        let image = match frames.last() {
            Some(previous) if passes == 0 => previous.image.clone(),
            _ => tracer.images().full,
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        credit_ms -= ms;
        let mut counters = Counters::for_technique("equal_time");
        counters.set("spp", f64::from(tracer.samples()));
        counters.set("spp_added", f64::from(passes));
        counters.set("budget_ms", frame_ms[i]);
        counters.set("credit_ms", credit_ms);
        frames.push(TimedFrame {
            time_s: t,
            frame_ms: ms,
            image,
            counters,
        });
        progress.set(i as u64 + 1);
    }
    progress.end();
    measure_series(
        scenario,
        &series,
        "reference",
        frames,
        references,
        None,
        keep_frames,
    )
}

/// Per-series summaries: median frame time, mean/max of each metric over the measured
/// frames, flicker, latency after each event (against the reference and, when measured,
/// against the technique's own converged images).
fn summarize(
    scenario: &Scenario,
    records: &[FrameRecord],
    times: &[f64],
    events: &[Event],
    measured: &[bool],
) -> Result<Vec<SeriesSummary>, BenchError> {
    let mut names: Vec<&str> = Vec::new();
    for r in records {
        if !names.contains(&r.series.as_str()) {
            names.push(&r.series);
        }
    }
    let stats = |values: Vec<f64>| {
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (mean, if values.is_empty() { f64::NAN } else { max })
    };
    names
        .into_iter()
        .map(|name| {
            let rs: Vec<&FrameRecord> = records.iter().filter(|r| r.series == name).collect();
            let metrics = scenario
                .metrics
                .iter()
                .map(|&m| {
                    let (mean, max) = stats(rs.iter().filter_map(|r| r.metric(m)).collect());
                    (m, mean, max)
                })
                .collect();
            let has_own = rs.iter().any(|r| !r.own_metrics.is_empty());
            let own_metrics = if has_own {
                scenario
                    .metrics
                    .iter()
                    .map(|&m| {
                        let (mean, max) =
                            stats(rs.iter().filter_map(|r| r.own_metric(m)).collect());
                        (m, mean, max)
                    })
                    .collect()
            } else {
                Vec::new()
            };
            let pairs: Vec<f64> = rs.iter().filter_map(|r| r.flicker).collect();
            let flicker = (!pairs.is_empty()).then(|| {
                (
                    pairs.iter().sum::<f64>() / pairs.len() as f64,
                    pairs.iter().copied().fold(0.0, f64::max),
                )
            });
            let frame_ms: Vec<f64> = rs.iter().map(|r| r.frame_ms).collect();
            let errors: Vec<f64> = rs
                .iter()
                .map(|r| r.metric(scenario.error_metric).unwrap_or(f64::NAN))
                .collect();
            let latencies = event_latencies(
                &errors,
                times,
                &frame_ms,
                events,
                measured,
                scenario.latency_threshold,
            )?;
            let own_latencies = if has_own {
                let own_errors: Vec<f64> = rs
                    .iter()
                    .map(|r| r.own_metric(scenario.error_metric).unwrap_or(f64::NAN))
                    .collect();
                let own_measured: Vec<bool> =
                    rs.iter().map(|r| !r.own_metrics.is_empty()).collect();
                event_latencies(
                    &own_errors,
                    times,
                    &frame_ms,
                    events,
                    &own_measured,
                    scenario.own_latency_threshold(),
                )?
            } else {
                Vec::new()
            };
            Ok(SeriesSummary {
                series: name.to_owned(),
                technique: rs[0].technique.clone(),
                // The equal-time path tracer renders whole passes on some frames and
                // nothing on others: its typical frame is the mean over the run (≈ the
                // technique's frame time by construction), not the median of mostly
                // empty frames.
                median_frame_ms: if rs
                    .iter()
                    .any(|r| r.counters.get("equal_time.budget_ms").is_some())
                {
                    frame_ms.iter().sum::<f64>() / frame_ms.len().max(1) as f64
                } else {
                    median(frame_ms)
                },
                precompute_ms: rs
                    .iter()
                    .filter_map(|r| r.counters.get("engine.precompute_ms"))
                    .sum(),
                metrics,
                own_metrics,
                flicker,
                latencies,
                own_latencies,
            })
        })
        .collect()
}

/// Latency after each event until `errors` stays below `threshold`, judged on the
/// measured frames only, up to the next event that shows on a later frame (or the last
/// frame).
fn event_latencies(
    errors: &[f64],
    times: &[f64],
    frame_ms: &[f64],
    events: &[Event],
    measured: &[bool],
    threshold: f64,
) -> Result<Vec<EventLatency>, BenchError> {
    events
        .iter()
        .map(|e| {
            let end = events
                .iter()
                .map(|o| o.frame)
                .filter(|&f| f > e.frame)
                .min()
                .unwrap_or(errors.len());
            // The measured frames of the window, and their errors and times.
            let frames: Vec<usize> = (e.frame..end).filter(|&i| measured[i]).collect();
            if frames.is_empty() {
                return Ok(EventLatency::default());
            }
            let window_errors: Vec<f64> = frames.iter().map(|&i| errors[i]).collect();
            let window_times: Vec<f64> = frames.iter().map(|&i| times[i]).collect();
            let l = latency_after_event(&window_errors, &window_times, 0, threshold)?;
            let settled = l.frames.map(|k| frames[k]);
            Ok(EventLatency {
                frames: settled.map(|s| s - e.frame),
                seconds: settled.map(|s| times[s] - times[e.frame]),
                wall_seconds: settled
                    .map(|s| frame_ms[e.frame + 1..=s.max(e.frame)].iter().sum::<f64>() / 1e3),
            })
        })
        .collect()
}

/// The median (mean of the middle two for an even count); NaN when empty.
pub fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The folder under `frames/` of the converged reference's frames. Its space is a
/// character [`file_safe`] never leaves, so no series' folder can be it (a series
/// labelled `reference` once wrote its frames over the converged ones).
pub const CONVERGED_FRAMES: &str = "converged reference";

/// `text` with every character outside `[A-Za-z0-9._-]` replaced by `_`.
pub fn file_safe(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes `frames/SERIES/NNNN.png` under `out`, recorded in its manifest (a file there
/// that illume did not write is refused, untouched).
fn save_frame(
    out: &illume_core::outputs::OutputDir,
    series: &str,
    i: usize,
    image: &RgbImage,
) -> Result<(), BenchError> {
    let dir = out.dir().join("frames").join(series);
    std::fs::create_dir_all(&dir).map_err(|e| BenchError::io(&dir, e))?;
    // The PNG to look at, the EXR (linear) for `illume compare`'s per-channel means.
    for ext in ["png", "exr"] {
        let name = format!("frames/{series}/{i:04}.{ext}");
        out.intend(&name)?;
        image.write(&out.dir().join(&name), &ToneMap::default())?;
        out.written(&name)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_is_judged_up_to_the_next_event() {
        let scenario = Scenario {
            metrics: vec![Metric::Flip],
            ..Scenario::default()
        };
        let errors = [0.5, 0.05, 0.05, 0.5, 0.3, 0.05];
        let times: Vec<f64> = (0..errors.len()).map(|i| i as f64 * 0.5).collect();
        let records: Vec<FrameRecord> = errors
            .iter()
            .enumerate()
            .map(|(i, &e)| FrameRecord {
                series: "s".into(),
                technique: "reference".into(),
                frame: i,
                time_s: times[i],
                frame_ms: 10.0 + i as f64,
                metrics: vec![(Metric::Flip, e)],
                own_metrics: Vec::new(),
                flicker: (i > 0).then_some(0.01),
                counters: Counters::new(),
            })
            .collect();
        let event = |frame: usize| Event {
            name: format!("e{frame}"),
            at_s: times[frame],
            frame,
        };
        let all = vec![true; errors.len()];
        let s = summarize(&scenario, &records, &times, &[event(0), event(3)], &all).unwrap();
        // Window [0, 3): 0.5, 0.05, 0.05 settles at frame 1 (the later rise belongs to
        // the second event). Window [3, 6): 0.5, 0.3, 0.05 settles at frame 5.
        assert_eq!(s[0].latencies[0].frames, Some(1));
        assert_eq!(s[0].latencies[1].frames, Some(2));
        assert_eq!(s[0].latencies[1].seconds, Some(1.0));
        // Wall clock: frames 4 and 5 rendered after the event's frame 3 (14 + 15 ms).
        assert_eq!(s[0].latencies[1].wall_seconds, Some(0.029));
        assert_eq!(s[0].latencies[0].wall_seconds, Some(0.011));
        // Measuring only frames 0, 2, 3 and 5: the first window settles at frame 2 (the
        // first measured frame below the threshold), the second at 5; the means are over
        // the measured frames.
        let mut some = all.clone();
        some[1] = false;
        some[4] = false;
        let sparse: Vec<FrameRecord> = records
            .iter()
            .map(|r| FrameRecord {
                metrics: if some[r.frame] {
                    r.metrics.clone()
                } else {
                    Vec::new()
                },
                ..r.clone()
            })
            .collect();
        let s2 = summarize(&scenario, &sparse, &times, &[event(0), event(3)], &some).unwrap();
        assert_eq!(s2[0].latencies[0].frames, Some(2));
        assert_eq!(s2[0].latencies[1].frames, Some(2));
        let (_, mean, _) = s2[0].metrics[0];
        assert!((mean - 1.1 / 4.0).abs() < 1e-12, "{mean}");
        assert_eq!(s[0].median_frame_ms, 12.5);
        let (metric, mean, max) = s[0].metrics[0];
        assert_eq!((metric, max), (Metric::Flip, 0.5));
        assert!((mean - 1.45 / 6.0).abs() < 1e-12, "{mean}");
        assert_eq!(s[0].flicker, Some((0.01, 0.01)));
    }

    /// The equal-time series reports its mean frame time: most of its frames render no
    /// pass and cost nothing (issue 14 item 14: it reported "9787 fps").
    #[test]
    fn equal_time_series_reports_its_mean_frame_time() {
        let scenario = Scenario {
            metrics: vec![Metric::Flip],
            ..Scenario::default()
        };
        let times = [0.0, 0.5, 1.0, 1.5];
        let records: Vec<FrameRecord> = [10.0, 0.1, 0.1, 10.0]
            .iter()
            .enumerate()
            .map(|(i, &ms)| {
                let mut counters = Counters::for_technique("equal_time");
                counters.set("budget_ms", 5.0);
                FrameRecord {
                    series: "reference (equal time to x)".into(),
                    technique: "reference".into(),
                    frame: i,
                    time_s: times[i],
                    frame_ms: ms,
                    metrics: vec![(Metric::Flip, 0.05)],
                    own_metrics: Vec::new(),
                    flicker: None,
                    counters,
                }
            })
            .collect();
        let s = summarize(&scenario, &records, &times, &[], &[true; 4]).unwrap();
        assert!(
            (s[0].median_frame_ms - 5.05).abs() < 1e-12,
            "{}",
            s[0].median_frame_ms
        );
    }

    /// The latency to the own steady state is judged with `own_latency_threshold`, the
    /// latency against the converged reference with `latency_threshold`.
    #[test]
    fn own_latency_uses_its_own_threshold() {
        // Against the path tracer the error sits at its bias floor (0.15); against its own
        // converged image it falls from 0.3 to 0.03 after the event at frame 0.
        let reference = [0.3, 0.15, 0.15, 0.15, 0.15, 0.15];
        let own = [0.3, 0.12, 0.08, 0.04, 0.03, 0.03];
        let times: Vec<f64> = (0..own.len()).map(|i| i as f64 * 0.1).collect();
        let records: Vec<FrameRecord> = (0..own.len())
            .map(|i| FrameRecord {
                series: "s".into(),
                technique: "selective".into(),
                frame: i,
                time_s: times[i],
                frame_ms: 20.0,
                metrics: vec![(Metric::Flip, reference[i])],
                own_metrics: vec![(Metric::Flip, own[i])],
                flicker: None,
                counters: Counters::new(),
            })
            .collect();
        let start = [Event {
            name: "start".into(),
            at_s: 0.0,
            frame: 0,
        }];
        let all = [true; 6];
        let mut scenario = Scenario {
            metrics: vec![Metric::Flip],
            latency_threshold: 0.2,
            own_converged_frames: 4,
            own_latency_threshold: Some(0.05),
            ..Scenario::default()
        };
        let s = summarize(&scenario, &records, &times, &start, &all).unwrap();
        assert_eq!(s[0].latencies[0].frames, Some(1), "0.15 < 0.2 from frame 1");
        assert_eq!(s[0].latencies[0].wall_seconds, Some(0.02));
        assert_eq!(
            s[0].own_latencies[0].frames,
            Some(3),
            "0.04 < 0.05 from frame 3"
        );
        assert_eq!(s[0].own_latencies[0].wall_seconds, Some(0.06));
        // Without it, latency_threshold serves both.
        scenario.own_latency_threshold = None;
        let s = summarize(&scenario, &records, &times, &start, &all).unwrap();
        assert_eq!(
            s[0].own_latencies[0].frames,
            Some(1),
            "0.12 < 0.2 from frame 1"
        );
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
        assert_eq!(
            file_safe("reference (equal time to a/b)"),
            "reference__equal_time_to_a_b_"
        );
    }
}
