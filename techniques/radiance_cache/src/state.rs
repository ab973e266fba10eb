//! The technique: [`RadianceCache`], the frame loop over the G-buffer in the four
//! temporal modes.
//!
//! Each frame t ([`Technique::indirect`]):
//! 1. **Expiry** (§4.2, §5 Fig. 9, [`crate::expiry`]): records whose lifespan ended are
//!    deleted or replaced at the same position and normal; `per_frame` (the paper's
//!    baseline) drops every record each frame instead. In pass 2 of `interpolated` the
//!    plan's records made at this frame enter instead ([`crate::plan`]).
//! 2. **Placement, coarse to fine** ([`crate::placement`]): new records where none is
//!    usable (Eq. 2–3), each with its future from the reprojected next frame (§4.3).
//! 3. **Shading** ([`crate::shading`]): Eq. 1 over the usable records, each contributing
//!    by Eq. 17; glossy surfaces add their specular part.
//!
//! The frame's work budget is in [`crate::budget`], pass 1 of `interpolated` in
//! [`crate::plan`], what a scene change does to the cache in [`crate::update`].

use crate::octree::Octree;
use crate::radiance::{GlossyShading, RadianceData};
use crate::record::{IrradianceRecord, RecordSettings};
use crate::settings::{RadianceCacheSettings, TemporalMode};
use crate::{NAME, RadianceCacheError};
use illume_core::Counters;
use illume_core::image::RgbImage;
use illume_core::progress::Progress;
use illume_scene::{InstanceId, SceneChange, Timeline};
use illume_transport::{Budget, ChangeResponse, GBuffer, Technique, TechniqueError, World};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

pub use crate::placement::PLACEMENT_SPACINGS_PX;

/// Counters of the last frame and since construction.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct FrameCounters {
    pub(crate) created: u64,
    pub(crate) replaced: u64,
    pub(crate) deleted: u64,
    pub(crate) admitted: u64,
    pub(crate) reused: u64,
    pub(crate) expired: u64,
    pub(crate) surprise_expired: u64,
    pub(crate) failed: u64,
    pub(crate) holes: u64,
    /// Records whose lives a new neighbour shortened (`neighbour_aging`).
    pub(crate) aged: u64,
    /// Replacements the work budget put off to a later frame.
    pub(crate) deferred: u64,
    /// New records the work budget left out of the placement passes.
    pub(crate) skipped: u64,
    /// Pixels no record reached that took their neighbours' light (budget fill).
    pub(crate) filled: u64,
    /// Pixels no record reached and the fill did not reach either.
    pub(crate) unfilled: u64,
    pub(crate) created_total: u64,
    pub(crate) replaced_total: u64,
    pub(crate) deleted_total: u64,
    pub(crate) lifespan_sum: u64,
    pub(crate) lifespan_count: u64,
    pub(crate) record_ms: f64,
    pub(crate) place_ms: f64,
    pub(crate) shade_ms: f64,
    /// Wall time of the frame's gathers (replacements and new records).
    pub(crate) gather_ms: f64,
}

/// A record in the cache, with what the frame loop needs besides Eq. 1–4.
#[derive(Clone, Debug)]
pub(crate) struct Slot {
    pub(crate) record: IrradianceRecord,
    /// The key its gather was traced with (a replacement may reuse it).
    pub(crate) key: u64,
    /// Instances its gather rays hit first, sorted (surprise expiry).
    pub(crate) seen: Vec<InstanceId>,
    /// Its entry in the pass-1 history (`interpolated`), if recorded.
    pub(crate) history: Option<u32>,
    /// The real-time age clock when it was made (see `RadianceCache::age_clock`).
    pub(crate) made_clock: u32,
    /// Incoming radiance in hemispherical harmonics (a radiance record, made where a
    /// glossy surface needed one), in the frame `Frame::from_normal(record.normal)`.
    pub(crate) radiance: Option<Box<RadianceData>>,
}

impl Slot {
    /// When its record was made, in what records age by: the age clock in real time,
    /// frames otherwise.
    pub(crate) fn made(&self, real_time: bool) -> u32 {
        if real_time {
            self.made_clock
        } else {
            self.record.frame
        }
    }
}

/// A record made by pass 1 of `interpolated`, and the one that replaced it.
#[derive(Clone, Debug)]
pub(crate) struct Planned {
    pub(crate) slot: Slot,
    pub(crate) successor: Option<u32>,
}

/// Temporal radiance caching (see the module docs).
pub struct RadianceCache {
    pub(crate) settings: RadianceCacheSettings,
    pub(crate) record_settings: RecordSettings,
    pub(crate) timeline: Timeline,
    /// Records by id (the octree's ids); `None` for free slots.
    pub(crate) slots: Vec<Option<Slot>>,
    /// Pixels that used each record in the last frame shaded, by id.
    pub(crate) uses: Vec<AtomicU32>,
    pub(crate) free: Vec<u32>,
    pub(crate) octree: Octree,
    /// Frames shaded so far: the next frame's index.
    pub(crate) frame: u32,
    /// The world of timeline frame `.0` (the next frame's, for reprojection), kept
    /// between frames; `.1` false when the scene does not change from frame `.0 − 1`.
    pub(crate) next_world: Option<(u32, World, bool)>,
    /// Pass 1's records (`interpolated`), in the order made; empty otherwise.
    pub(crate) history: Vec<Planned>,
    /// Pass 2's plan: history indices by the frame they are made at; `None` when
    /// running online (other modes, or after a surprise).
    pub(crate) plan: Option<Vec<Vec<u32>>>,
    /// Pass 1 is running: record every record made into `history`.
    pub(crate) recording: bool,
    /// A scene change expired every record; done at the next frame.
    pub(crate) expire_all: bool,
    /// Instances whose records (on them, or whose rays hit them) a surprise expired.
    pub(crate) expire_instances: Vec<InstanceId>,
    /// The first frame rendered after the last change of anything but the camera.
    pub(crate) last_world_change: Option<u32>,
    /// In real time, what records age by instead of frames: it ticks once a frame while
    /// the world changes and for δt_max − 1 frames after the last change, then stops. A
    /// record made since then sees the world as it still is and lives until the next
    /// change, so a still world settles (nothing computed, the same image every frame)
    /// instead of replacing every record each δt_max frames with new noise. δt_max
    /// exists for changes a record's rays do not see yet (an object entering its
    /// hemisphere, Fig. 4): every record made before a change still expires within
    /// δt_max frames of it. On a timeline (the paper's setting) records age by frames.
    /// Starts at δt_max, so that ages can be spread back from it (`stagger_ages`).
    pub(crate) age_clock: u32,
    /// A scene change (the camera's too) came after the last frame.
    pub(crate) changed_since_frame: bool,
    pub(crate) counters: FrameCounters,
    pub(crate) glossy: GlossyShading,
    /// Records a frame may compute (the last `advance`'s `Budget::work`, or the
    /// settings' `records_per_frame_max`); `None`: no limit.
    pub(crate) work_cap: Option<u64>,
    /// The last `advance`'s `Budget::time_ms`: a wall-clock limit on a frame's gathers.
    pub(crate) time_cap_ms: Option<f64>,
    /// Measured wall time of one record's gather \[ms\] (smoothed over frames), which
    /// turns `time_cap_ms` into a record count; `None` until a frame has made some.
    pub(crate) ms_per_record: Option<f64>,
    /// What is left of the frame's record cap in the frame being made.
    pub(crate) work_left: Option<u64>,
}

impl RadianceCache {
    /// The technique for `world` with `settings`, for the frames of `timeline` (the
    /// temporal modes reproject into its next frames; `interpolated` runs its pass 1 over
    /// it in [`Technique::precompute`]). Errors on invalid settings
    /// (`radiance_cache.FIELD: …`).
    pub fn new(
        world: &World,
        timeline: &Timeline,
        settings: RadianceCacheSettings,
    ) -> Result<Self, RadianceCacheError> {
        settings.validate()?;
        let settings_order = settings.hsh_order as usize;
        let max_age_frames = settings.max_age_frames;
        let work_cap =
            (settings.records_per_frame_max > 0).then_some(settings.records_per_frame_max);
        let bounds = world.scene.bounds();
        let diagonal = (bounds.max - bounds.min).length();
        let diagonal = if diagonal.is_finite() && diagonal > 0.0 {
            diagonal
        } else {
            1.0
        };
        Ok(Self {
            record_settings: settings.record_settings(diagonal),
            settings,
            timeline: timeline.clone(),
            slots: Vec::new(),
            uses: Vec::new(),
            free: Vec::new(),
            octree: Octree::new(),
            frame: 0,
            next_world: None,
            history: Vec::new(),
            plan: None,
            recording: false,
            expire_all: false,
            last_world_change: None,
            age_clock: max_age_frames,
            changed_since_frame: true,
            expire_instances: Vec::new(),
            counters: FrameCounters::default(),
            glossy: GlossyShading::new(settings_order)?,
            work_cap,
            time_cap_ms: None,
            ms_per_record: None,
            work_left: None,
        })
    }

    /// Records alive.
    pub fn records_alive(&self) -> usize {
        self.octree.len()
    }

    /// Records computed since construction (or the last reset), replacements included;
    /// pass 1's records are counted by [`RadianceCache::records_planned`].
    pub fn records_created(&self) -> u64 {
        self.counters.created_total + self.counters.replaced_total
    }

    /// Records pass 1 of `interpolated` computed (0 in the other modes).
    pub fn records_planned(&self) -> usize {
        self.history.len()
    }

    /// The live records, in id order.
    pub fn records(&self) -> impl Iterator<Item = &IrradianceRecord> {
        self.slots.iter().flatten().map(|s| &s.record)
    }

    /// The live records with the instances their gather rays hit first (sorted), in
    /// id order.
    pub fn records_with_seen(&self) -> impl Iterator<Item = (&IrradianceRecord, &[InstanceId])> {
        self.slots
            .iter()
            .flatten()
            .map(|s| (&s.record, s.seen.as_slice()))
    }

    pub(crate) fn temporal(&self) -> bool {
        self.settings.temporal != TemporalMode::PerFrame
    }

    pub(crate) fn remove(&mut self, id: u32) {
        if self.slots[id as usize].take().is_some() {
            self.octree.remove(id);
            self.free.push(id);
        }
    }

    pub(crate) fn insert(&mut self, slot: Slot) -> Result<u32, RadianceCacheError> {
        let id = match self.free.pop() {
            Some(id) => id,
            None => {
                self.slots.push(None);
                self.uses.push(AtomicU32::new(0));
                (self.slots.len() - 1) as u32
            }
        };
        let radius = slot.record.influence_radius_m(self.settings.accuracy);
        if let Err(e) = self.octree.insert(id, slot.record.position, radius) {
            self.free.push(id);
            return Err(e);
        }
        self.uses[id as usize].store(0, Ordering::Relaxed);
        self.slots[id as usize] = Some(slot);
        Ok(id)
    }

    /// Inserts a new record, into pass 1's history too when recording.
    pub(crate) fn admit(&mut self, mut slot: Slot) -> Result<u32, RadianceCacheError> {
        if self.recording {
            slot.history = Some(self.history.len() as u32);
            self.history.push(Planned {
                slot: slot.clone(),
                successor: None,
            });
        }
        self.counters.lifespan_sum += slot.record.lifespan_frames as u64;
        self.counters.lifespan_count += 1;
        let id = self.insert(slot)?;
        if self.settings.neighbour_aging {
            self.age_neighbours(id);
        }
        Ok(id)
    }

    /// One frame: expiry (or the plan's admissions), placement, shading.
    pub(crate) fn frame_step(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        self.frame_step_reporting(world, gbuffer, None)
    }

    /// [`RadianceCache::frame_step`], the records' making reported to `progress` (a
    /// phase per placement pass that makes any): the same cache and image.
    pub(crate) fn frame_step_reporting(
        &mut self,
        world: &World,
        gbuffer: &GBuffer,
        progress: Option<&mut dyn Progress>,
    ) -> RgbImage {
        let t0 = Instant::now();
        let before = self.octree.len() as u64;
        let keep_total = (
            self.counters.created_total,
            self.counters.replaced_total,
            self.counters.deleted_total,
            self.counters.lifespan_sum,
            self.counters.lifespan_count,
        );
        self.counters = FrameCounters {
            created_total: keep_total.0,
            replaced_total: keep_total.1,
            deleted_total: keep_total.2,
            lifespan_sum: keep_total.3,
            lifespan_count: keep_total.4,
            ..FrameCounters::default()
        };
        if self.plan.is_some() && self.frame as usize >= self.timeline.len() {
            // Past the planned frames: online from here.
            self.plan = None;
        }
        // Pass 1 of `interpolated` is precompute work: no budget.
        self.work_left = if self.recording {
            None
        } else {
            self.frame_cap()
        };
        if self.age_clock_running() {
            self.age_clock += 1;
        }
        self.prepare_next(world);
        self.expire(world);
        self.counters.reused = before - self.counters.expired;
        self.admit_planned();
        let t1 = Instant::now();
        self.place(world, gbuffer, progress);
        let (made, gather_ms) = (
            self.counters.created + self.counters.replaced,
            self.counters.gather_ms,
        );
        self.measure_gathers(made, gather_ms);
        let c = &mut self.counters;
        c.created_total += c.created;
        c.replaced_total += c.replaced;
        c.deleted_total += c.deleted;
        let t2 = Instant::now();
        let mut img = self.shade(world, gbuffer);
        if self.settings.show_records {
            self.draw_records(world, gbuffer, &mut img);
        }
        self.counters.record_ms = (t1 - t0).as_secs_f64() * 1e3;
        self.counters.place_ms = (t2 - t1).as_secs_f64() * 1e3;
        self.counters.shade_ms = t2.elapsed().as_secs_f64() * 1e3;
        self.frame += 1;
        self.changed_since_frame = false;
        img
    }

    /// Drops the cache (records, octree, frame count, pending expiries), keeping the
    /// plan and the history.
    pub(crate) fn clear_cache(&mut self) {
        self.slots.clear();
        self.uses.clear();
        self.free.clear();
        self.octree = Octree::new();
        self.frame = 0;
        self.next_world = None;
        self.expire_all = false;
        self.expire_instances.clear();
        self.last_world_change = None;
        self.age_clock = self.settings.max_age_frames;
        self.changed_since_frame = true;
        self.counters = FrameCounters::default();
    }
}

impl Technique for RadianceCache {
    fn name(&self) -> &'static str {
        NAME
    }

    /// In real time only (a timeline ages every record): the records have stopped
    /// ageing, the last frame computed, replaced, expired and left out none, and nothing
    /// changed since, so the next frame would shade the same records into the same image.
    fn settled(&self) -> bool {
        let c = &self.counters;
        self.settings.paced_real_time
            && self.frame > 0
            && !self.changed_since_frame
            && !self.age_clock_running()
            && !self.expire_all
            && self.expire_instances.is_empty()
            && c.created + c.replaced + c.expired + c.deferred + c.skipped + c.failed == 0
    }

    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), TechniqueError> {
        if self.settings.temporal == TemporalMode::Interpolated {
            self.plan_timeline(world, progress)?;
        }
        Ok(())
    }

    /// See [`crate::update`].
    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        self.on_changes(world, changes)
    }

    /// Records nothing: the frame's records are computed in `indirect`, where the
    /// G-buffer says where. Keeps `budget.work` as the number of records the next
    /// frames may compute (`None`: no limit), replacing `records_per_frame_max`, and
    /// `budget.time_ms` as a limit on their gathers' wall time (turned into a record
    /// count by the measured cost of a record; see the module doc).
    fn advance(&mut self, _world: &World, budget: &Budget) {
        self.work_cap = budget.work;
        self.time_cap_ms = budget.time_ms;
    }

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        self.frame_step(world, gbuffer)
    }

    /// The frame's records (most of a still's time: 64×64 rays each) reported pass by
    /// pass ([`crate::placement`]).
    fn indirect_with_progress(
        &mut self,
        world: &World,
        gbuffer: &GBuffer,
        progress: &mut dyn Progress,
    ) -> RgbImage {
        self.frame_step_reporting(world, gbuffer, Some(progress))
    }

    fn stats(&self) -> Counters {
        let c = &self.counters;
        let mut out = Counters::new();
        let memory = self.slots.capacity() * std::mem::size_of::<Option<Slot>>()
            + self
                .slots
                .iter()
                .flatten()
                .map(|s| s.seen.capacity() * 4)
                .sum::<usize>()
            + self.octree.node_count() * 128
            + self.octree.len() * 16;
        let mean_lifespan = if c.lifespan_count > 0 {
            c.lifespan_sum as f64 / c.lifespan_count as f64
        } else {
            0.0
        };
        for (name, x) in [
            ("records_alive", self.octree.len() as f64),
            ("records_created", c.created as f64),
            ("records_replaced", c.replaced as f64),
            ("records_deleted", c.deleted as f64),
            ("records_admitted", c.admitted as f64),
            ("records_reused", c.reused as f64),
            ("records_expired", c.expired as f64),
            ("records_surprise_expired", c.surprise_expired as f64),
            ("records_failed", c.failed as f64),
            ("records_aged", c.aged as f64),
            ("records_deferred", c.deferred as f64),
            ("records_skipped", c.skipped as f64),
            ("pixels_filled", c.filled as f64),
            ("pixels_unfilled", c.unfilled as f64),
            ("records_created_total", c.created_total as f64),
            ("records_replaced_total", c.replaced_total as f64),
            ("records_deleted_total", c.deleted_total as f64),
            ("records_planned", self.history.len() as f64),
            ("mean_lifespan_frames", mean_lifespan),
            ("reprojection_holes", c.holes as f64),
            ("memory_bytes", memory as f64),
            ("expire_ms", c.record_ms),
            ("place_ms", c.place_ms),
            ("shade_ms", c.shade_ms),
            ("gather_ms", c.gather_ms),
        ] {
            out.set(name, x);
        }
        out
    }

    fn reset(&mut self) {
        self.clear_cache();
    }
}
