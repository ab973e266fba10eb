//! The technique: [`RadianceCache`], the frame loop over the G-buffer in the four
//! temporal modes.
//!
//! Each frame t ([`Technique::indirect`]):
//! 1. **Expiry** (§4.2). A record lives `lifespan_frames` frames from its own (Eq. 10
//!    and Eq. 12 through τ, [`crate::temporal`]). When its life ends it is:
//!    * **deleted** (§5, Fig. 9) when no pixel used it in the last frame shaded
//!      (`deletion`; the exact use count stands in for the paper's occlusion query), or
//!      when no surface facing its normal lies at its position any more
//!      (`replace_only_on_surface`, beyond the paper);
//!    * otherwise **replaced** by a new record at the same position and normal (§4.2,
//!      Fig. 6), traced with its predecessor's directions and random numbers
//!      (`reuse_directions`), so the difference between the two is change, not noise.
//!
//!    `per_frame` (the paper's baseline) drops every record each frame instead.
//! 2. **Placement, coarse to fine.** Grids of spacing 32, 16, 8, 4, 2 and 1 px; a pixel
//!    of a pass gets a new record only if no record is usable there (w ≥ 1/a, Eq. 2–3).
//!    Which pixels get one is decided from the cache before the pass, then the records
//!    are computed in parallel and inserted in pixel order: records are pure functions
//!    of (seed, key, cell), the key is (frame, pixel), so the cache and the image do not
//!    depend on the thread count.
//! 3. **Shading**: Eq. 1 over the usable records, each contributing by Eq. 17 (Eq. 4
//!    moved along its temporal gradient by t − t_k); indirect radiance = ρ/π·E. Each
//!    record counts the pixels that used it (for deletion).
//!
//! **A new record's future** (§4.3): in the temporal modes its gather is reprojected into
//! the next timeline frame's world ([`crate::reproject`]), giving E(t + 1), hence τ and
//! the lifespan, and the extrapolated temporal gradient (Eq. 18–20). Where the next frame
//! is unknown (the last frame, a frame off the timeline) or the scene does not change
//! between the two, τ = 1 and the record lives δt_max frames.
//!
//! **Modes.** `reuse`: lifespans and replacement, no temporal gradient (Fig. 5c).
//! `extrapolated`: also the extrapolated gradients (Fig. 5d), one pass. `interpolated`
//! (Fig. 5e): [`Technique::precompute`] runs the extrapolated loop over the whole
//! timeline (pass 1) on a private world, keeping every record with its successor; each
//! replaced record's temporal gradient then becomes the interpolated one towards its
//! replacement (Eq. 21–23), and the frames (pass 2) replay that plan: a frame admits
//! the records made at it and drops the expired, with no new gather except for pixels
//! the plan does not cover (counted as `records_created`).
//!
//! **Surprises** (changes not on the timeline: edits, frames off it): the plan is
//! dropped and the loop goes on online (as `extrapolated`). With `expire_on_surprise`, a
//! moved, added or removed instance expires the records on it and the records whose
//! rays hit it; a light, sky or material change expires every record. Camera moves
//! expire nothing (records are world-space). Changes on the timeline are what τ and
//! the lifespans are for, and expire nothing.
//!
//! **Neighbour aging** (`neighbour_aging`, §7's future work): a new record whose
//! lifespan is shorter than δt_max ends the lives of the records usable at its position
//! no later than its own.
//!
//! **Glossy surfaces** ([`crate::radiance`]): the BRDF's Lambertian part ρ_d/π·E comes
//! from irradiance records; the specular part from radiance records (hemispherical
//! harmonics; a record made at a glossy pixel carries both, from one gather, and its
//! replacements too) where the roughness is at least `traced_roughness_max`, from
//! `traced_rays` rays per pixel below it. Surfaces rougher than `glossy_roughness_max`
//! are shaded Lambertian with the BRDF's approximate albedo.
//!
//! **Budget.** A frame's records are computed in [`Technique::indirect`] (the G-buffer
//! says where). [`Budget::work`] (from [`Technique::advance`], else the settings'
//! `records_per_frame_max`) caps the records a frame computes: replacements first, in
//! record order (those past the cap live one frame longer: `records_deferred`), then
//! new records pass by pass, coarse to fine, spread evenly over a pass's pixels
//! (`records_skipped` counts those left out; a later frame places them). Pixels that
//! no record reaches then take the mean light of their neighbours on the same surface,
//! pass after pass (`pixels_filled`, `pixels_unfilled`). Pass 1 of `interpolated` and
//! the planned records pass 2 admits are not capped. [`Budget::time_ms`] becomes a
//! record cap the same way: the limit divided by the cost of a record measured on the
//! previous frames (the gathers' wall time over the records made, smoothed; at least
//! one record per frame), the smaller of the two caps when both are set. The first
//! frame, with no cost measured yet, is capped by `Budget::work` alone. The time limit
//! covers the records' gathers only: expiry, reprojection and shading are not in it.

use crate::octree::Octree;
use crate::radiance::{GlossyShading, RadianceData, diffuse_albedo};
use crate::record::{IrradianceRecord, RecordSettings, WeightedSum, usable};
use crate::reproject::reproject;
use crate::settings::{RadianceCacheSettings, TemporalMode};
use crate::temporal::{
    change_rate, contribution, interpolated_gradient, is_valid, lifespan_frames,
};
use crate::{HemisphereGather, NAME, RadianceCacheError};
use illume_core::image::RgbImage;
use illume_core::progress::Progress;
use illume_core::sampling::mix64;
use illume_core::{Counters, Frame, INV_PI, Ray, Rgb, Vec3};
use illume_scene::{InstanceId, Scene, SceneChange, Timeline};
use illume_transport::metal_rough::{DIELECTRIC_F0, MetalRough};
use illume_transport::{
    Budget, ChangeResponse, GBuffer, GBufferPixel, Technique, TechniqueError, World,
};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

/// Grid spacings of the placement passes, coarse to fine \[px\].
pub const PLACEMENT_SPACINGS_PX: [u32; 6] = [32, 16, 8, 4, 2, 1];

/// Counters of the last frame and since construction.
#[derive(Clone, Copy, Debug, Default)]
struct FrameCounters {
    created: u64,
    replaced: u64,
    deleted: u64,
    admitted: u64,
    reused: u64,
    expired: u64,
    surprise_expired: u64,
    failed: u64,
    holes: u64,
    /// Records whose lives a new neighbour shortened (`neighbour_aging`).
    aged: u64,
    /// Replacements the work budget put off to a later frame.
    deferred: u64,
    /// New records the work budget left out of the placement passes.
    skipped: u64,
    /// Pixels no record reached that took their neighbours' light (budget fill).
    filled: u64,
    /// Pixels no record reached and the fill did not reach either.
    unfilled: u64,
    created_total: u64,
    replaced_total: u64,
    deleted_total: u64,
    lifespan_sum: u64,
    lifespan_count: u64,
    record_ms: f64,
    place_ms: f64,
    shade_ms: f64,
    /// Wall time of the frame's gathers (replacements and new records).
    gather_ms: f64,
}

/// A record in the cache, with what the frame loop needs besides Eq. 1–4.
#[derive(Clone, Debug)]
struct Slot {
    record: IrradianceRecord,
    /// The key its gather was traced with (a replacement may reuse it).
    key: u64,
    /// Instances its gather rays hit first, sorted (surprise expiry).
    seen: Vec<InstanceId>,
    /// Its entry in the pass-1 history (`interpolated`), if recorded.
    history: Option<u32>,
    /// The real-time age clock when it was made (see `RadianceCache::age_clock`).
    made_clock: u32,
    /// Incoming radiance in hemispherical harmonics (a radiance record, made where a
    /// glossy surface needed one), in the frame `Frame::from_normal(record.normal)`.
    radiance: Option<Box<RadianceData>>,
}

impl Slot {
    /// When its record was made, in what records age by: the age clock in real time,
    /// frames otherwise.
    fn made(&self, real_time: bool) -> u32 {
        if real_time {
            self.made_clock
        } else {
            self.record.frame
        }
    }
}

/// A record made by pass 1 of `interpolated`, and the one that replaced it.
#[derive(Clone, Debug)]
struct Planned {
    slot: Slot,
    successor: Option<u32>,
}

/// A pixel of a placement pass that needs a new record.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    p: Vec3,
    n: Vec3,
    instance: InstanceId,
    key: u64,
    glossy: bool,
}

/// A new record and what its making found.
struct Made {
    slot: Slot,
    holes: u32,
}

/// Temporal radiance caching (see the module docs).
pub struct RadianceCache {
    settings: RadianceCacheSettings,
    record_settings: RecordSettings,
    timeline: Timeline,
    /// Records by id (the octree's ids); `None` for free slots.
    slots: Vec<Option<Slot>>,
    /// Pixels that used each record in the last frame shaded, by id.
    uses: Vec<AtomicU32>,
    free: Vec<u32>,
    octree: Octree,
    /// Frames shaded so far: the next frame's index.
    frame: u32,
    /// The world of timeline frame `.0` (the next frame's, for reprojection), kept
    /// between frames; `.1` false when the scene does not change from frame `.0 − 1`.
    next_world: Option<(u32, World, bool)>,
    /// Pass 1's records (`interpolated`), in the order made; empty otherwise.
    history: Vec<Planned>,
    /// Pass 2's plan: history indices by the frame they are made at; `None` when
    /// running online (other modes, or after a surprise).
    plan: Option<Vec<Vec<u32>>>,
    /// Pass 1 is running: record every record made into `history`.
    recording: bool,
    /// A scene change expired every record; done at the next frame.
    expire_all: bool,
    /// Instances whose records (on them, or whose rays hit them) a surprise expired.
    expire_instances: Vec<InstanceId>,
    /// The first frame rendered after the last change of anything but the camera.
    last_world_change: Option<u32>,
    /// In real time, what records age by instead of frames: it ticks once a frame while
    /// the world changes and for δt_max − 1 frames after the last change, then stops. A
    /// record made since then sees the world as it still is and lives until the next
    /// change, so a still world settles (nothing computed, the same image every frame)
    /// instead of replacing every record each δt_max frames with new noise. δt_max
    /// exists for changes a record's rays do not see yet (an object entering its
    /// hemisphere, Fig. 4): every record made before a change still expires within
    /// δt_max frames of it. On a timeline (the paper's setting) records age by frames.
    /// Starts at δt_max, so that ages can be spread back from it (`stagger_ages`).
    age_clock: u32,
    /// A scene change (the camera's too) came after the last frame.
    changed_since_frame: bool,
    counters: FrameCounters,
    glossy: GlossyShading,
    /// Records a frame may compute (the last `advance`'s `Budget::work`, or the
    /// settings' `records_per_frame_max`); `None`: no limit.
    work_cap: Option<u64>,
    /// The last `advance`'s `Budget::time_ms`: a wall-clock limit on a frame's gathers.
    time_cap_ms: Option<f64>,
    /// Measured wall time of one record's gather \[ms\] (smoothed over frames), which
    /// turns `time_cap_ms` into a record count; `None` until a frame has made some.
    ms_per_record: Option<f64>,
    /// What is left of the frame's record cap in the frame being made.
    work_left: Option<u64>,
}

/// How a pixel's surface is shaded (see the module docs).
#[derive(Clone, Copy, Debug)]
enum Surface {
    /// ρ/π·E only: Lambertian, or rougher than `glossy_roughness_max` (ρ the BRDF's
    /// approximate albedo).
    Diffuse(Rgb),
    /// ρ_d/π·E plus the specular part, from radiance records (`traced` false) or rays.
    Glossy {
        diffuse: Rgb,
        brdf: MetalRough,
        traced: bool,
    },
}

/// The shading point and normal of a pixel, or `None` where nothing reflects: the normal
/// is the shading normal turned to the side the camera sees.
fn shading_point(p: &GBufferPixel) -> Option<(Vec3, Vec3)> {
    let hit = &p.hit;
    if !hit.reflects || hit.albedo == Rgb::ZERO {
        return None;
    }
    let n = if hit.front_face {
        hit.shading_normal
    } else {
        -hit.shading_normal
    };
    Some((hit.position, n))
}

/// The albedo a non-Lambertian surface shaded as Lambertian gets: ρ_d plus the
/// specular lobe's normal-incidence reflectance, (1 − m)·F0 + m·base.
fn lambertian_albedo(brdf: &MetalRough) -> Rgb {
    diffuse_albedo(brdf)
        + Rgb::splat((1.0 - brdf.metallic) * DIELECTRIC_F0)
        + brdf.base_color * brdf.metallic
}

/// True when the parts of `a` that records depend on (instances, lights, materials,
/// sky) equal `b`'s: the camera and the time may differ.
fn same_lighting(a: &Scene, b: &Scene) -> bool {
    a.instances == b.instances
        && a.lights == b.lights
        && a.materials == b.materials
        && a.sky == b.sky
}

/// Largest distance of a neighbouring pixel's point from a pixel's tangent plane that
/// the budget fill crosses, in units of R_min (`r_min_fraction` of the scene's
/// diagonal): a pixel takes light from its own surface (however grazing the view), not
/// across a depth jump between parallel surfaces.
const FILL_PLANE_R_MIN: f32 = 1.0;

/// Smallest cosine between neighbouring pixels' normals that the budget fill's second
/// round crosses (60°): pixels the first round (normals within acos(1 − a²)) left
/// without light, on curved surfaces or small faces, take it across creases.
const FILL_CREASE_COS: f32 = 0.5;

/// Fills `values` where `wants` and no value, pass after pass, with the mean of the
/// 3×3 neighbours that have one and lie on the same surface (points at most
/// `max_step_m` from the pixel's tangent plane, normals with a cosine of at least
/// `min_cos`): the image-space
/// counterpart of the reprojection's hole filling, for pixels the work budget left
/// without records. Returns the pixels filled and those still without a value.
fn fill_from_neighbours(
    gbuffer: &GBuffer,
    values: &mut [Option<Rgb>],
    wants: &[bool],
    max_step_m: f32,
    min_cos: f32,
) -> (u64, u64) {
    let (w, h) = (gbuffer.width as usize, gbuffer.height as usize);
    let point = |i: usize| gbuffer.pixels[i].as_ref().and_then(shading_point);
    let mut filled = 0u64;
    for _ in 0..w.max(h) {
        let before: Vec<Option<Rgb>> = values.to_vec();
        let new: Vec<(usize, Rgb)> = (0..w * h)
            .into_par_iter()
            .filter(|&i| wants[i] && before[i].is_none())
            .filter_map(|i| {
                let (p, n) = point(i)?;
                let (x, y) = (i % w, i / w);
                let (mut sum, mut count) = (Rgb::ZERO, 0u32);
                for ny in y.saturating_sub(1)..(y + 2).min(h) {
                    for nx in x.saturating_sub(1)..(x + 2).min(w) {
                        let j = ny * w + nx;
                        let (Some(v), Some((q, m))) = (before[j], point(j)) else {
                            continue;
                        };
                        if (q - p).dot(n).abs() <= max_step_m && m.dot(n) >= min_cos {
                            sum += v;
                            count += 1;
                        }
                    }
                }
                (count > 0).then(|| (i, sum * (1.0 / count as f32)))
            })
            .collect();
        if new.is_empty() {
            break;
        }
        filled += new.len() as u64;
        for (i, v) in new {
            values[i] = Some(v);
        }
    }
    let unfilled = (0..w * h)
        .filter(|&i| wants[i] && values[i].is_none())
        .count() as u64;
    (filled, unfilled)
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

    /// How the surface of `hit` is shaded.
    fn surface(&self, hit: &illume_transport::SurfaceHit) -> Surface {
        let brdf = hit.brdf();
        if brdf.is_lambertian() {
            return Surface::Diffuse(brdf.base_color);
        }
        if brdf.roughness > self.settings.glossy_roughness_max {
            return Surface::Diffuse(lambertian_albedo(&brdf));
        }
        Surface::Glossy {
            diffuse: diffuse_albedo(&brdf),
            brdf,
            traced: brdf.roughness < self.settings.traced_roughness_max,
        }
    }

    /// True when the pixel's surface needs radiance records.
    fn needs_radiance(&self, hit: &illume_transport::SurfaceHit) -> bool {
        matches!(self.surface(hit), Surface::Glossy { traced: false, .. })
    }

    fn temporal(&self) -> bool {
        self.settings.temporal != TemporalMode::PerFrame
    }

    fn remove(&mut self, id: u32) {
        if self.slots[id as usize].take().is_some() {
            self.octree.remove(id);
            self.free.push(id);
        }
    }

    fn insert(&mut self, slot: Slot) -> Result<u32, RadianceCacheError> {
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
    fn admit(&mut self, mut slot: Slot) -> Result<u32, RadianceCacheError> {
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

    /// `neighbour_aging`: the records usable at new record `id`'s position end their
    /// lives no later than it, when its lifespan is shorter than `max_age_frames`.
    fn age_neighbours(&mut self, id: u32) {
        let real_time = self.settings.paced_real_time;
        let Some((new, new_made)) = self.slots[id as usize]
            .as_ref()
            .map(|s| (s.record, s.made(real_time)))
        else {
            return;
        };
        if new.lifespan_frames >= self.settings.max_age_frames {
            return;
        }
        let end = new_made + new.lifespan_frames;
        let mut neighbours = Vec::new();
        self.octree.for_each_containing(new.position, |k| {
            if k != id {
                neighbours.push(k);
            }
        });
        neighbours.sort_unstable();
        for k in neighbours {
            let accuracy = self.settings.accuracy;
            let Some(slot) = self.slots[k as usize].as_mut() else {
                continue;
            };
            let made = slot.made(real_time);
            let r = &mut slot.record;
            if usable(r.ward_error(new.position, new.normal), accuracy)
                && made + r.lifespan_frames > end
            {
                r.lifespan_frames = end.saturating_sub(made).max(1);
                self.counters.aged += 1;
            }
        }
    }

    /// The world of timeline frame `frame + 1`, for reprojecting records made at
    /// `frame`, and whether the scene changes between the two; `None` past the
    /// timeline's end.
    fn prepare_next(&mut self, world: &World) {
        if !self.temporal() {
            return;
        }
        let next = self.frame + 1;
        if self.next_world.as_ref().is_some_and(|(f, _, _)| *f == next) {
            return;
        }
        self.next_world = self.timeline.times().get(next as usize).map(|&t| {
            let mut scene = world.scene.clone();
            let changes = scene.set_time(t);
            let changed = !changes.is_empty() && !same_lighting(&scene, &world.scene);
            (next, world.with_scene(scene), changed)
        });
    }

    /// Makes a record at `p` with normal `n` at the current frame (see the module docs:
    /// its lifespan and extrapolated gradient from the reprojection when the next frame
    /// is known and differs).
    fn make(
        &self,
        world: &World,
        p: Vec3,
        n: Vec3,
        instance: Option<InstanceId>,
        key: u64,
        glossy: bool,
    ) -> Result<Made, RadianceCacheError> {
        let rs = &self.record_settings;
        let (gather, paths) = HemisphereGather::trace_keeping_paths(world, p, n, key, rs)?;
        let mut record = IrradianceRecord::from_gather(p, &gather, self.frame, instance, rs);
        let mut seen: Vec<InstanceId> = paths
            .iter()
            .filter_map(|c| c.hit.map(|h| h.instance))
            .collect();
        seen.sort_unstable();
        seen.dedup();
        seen.shrink_to_fit();
        let mut holes = 0;
        let s = &self.settings;
        let mut radiance = glossy.then(|| Box::new(self.glossy.project(&gather, rs.r_min_m)));
        record.lifespan_frames = match (s.temporal, &self.next_world) {
            (TemporalMode::PerFrame, _) => 1,
            (_, Some((_, next, true))) => {
                let r = reproject(world, next, p, &gather, &paths, rs, s.hole_fill_max_passes);
                holes = r.holes;
                let next_value =
                    IrradianceRecord::from_gather(p, &r.gather, self.frame + 1, instance, rs).value;
                if s.temporal != TemporalMode::Reuse {
                    record.temporal_gradient = next_value - record.value;
                    if let Some(data) = &mut radiance {
                        let next = self.glossy.project(&r.gather, rs.r_min_m);
                        data.temporal_gradient = next
                            .coefficients
                            .iter()
                            .zip(&data.coefficients)
                            .map(|(a, b)| *a - *b)
                            .collect();
                    }
                }
                let change = change_rate(record.value.irradiance, next_value.irradiance);
                lifespan_frames(change, s.temporal_accuracy, s.max_age_frames)
            }
            // The next frame unknown, or no change: τ = 1.
            _ => s.max_age_frames,
        };
        Ok(Made {
            slot: Slot {
                record,
                key,
                seen,
                history: None,
                made_clock: self.age_clock,
                radiance,
            },
            holes,
        })
    }

    /// True when a surface facing `n` lies at `p` in `world` (within 0.1 % of the
    /// scene's size, normals within 25°).
    fn surface_at(&self, world: &World, p: Vec3, n: Vec3) -> bool {
        let eps = self.record_settings.r_min_m.max(1e-4);
        let origin = p + n * eps;
        let Some(hit) = world.trace(&Ray::new(origin, -n), illume_scene::MASK_DEFAULT) else {
            return false;
        };
        let facing = if hit.front_face {
            hit.shading_normal
        } else {
            -hit.shading_normal
        };
        hit.t <= 2.0 * eps && hit.reflects && facing.dot(n) >= 25f32.to_radians().cos()
    }

    /// Step 1: the records that leave the cache before the current frame, and their
    /// replacements (see the module docs).
    fn expire(&mut self, world: &World) {
        let frame = self.frame;
        let per_frame = !self.temporal();
        let all = self.expire_all;
        let (real_time, now) = (self.settings.paced_real_time, self.age_now());
        let replaying = self.plan.is_some();
        let mut doomed = Vec::new();
        let mut successors = Vec::new();
        for (id, slot) in self.slots.iter().enumerate() {
            let Some(slot) = slot else { continue };
            let r = &slot.record;
            let surprised = all
                || (!self.expire_instances.is_empty()
                    && (r
                        .instance
                        .is_some_and(|i| self.expire_instances.contains(&i))
                        || slot.seen.iter().any(|i| self.expire_instances.contains(i))));
            if surprised {
                self.counters.surprise_expired += 1;
                doomed.push(id as u32);
            } else if per_frame || !is_valid(slot.made(real_time), r.lifespan_frames, now) {
                doomed.push(id as u32);
                if !per_frame && !replaying {
                    successors.push(id as u32);
                }
            }
        }
        // Which expired records are replaced (the others are deleted), decided from the
        // cache's state now.
        let this = &*self;
        let replace: Vec<bool> = successors
            .par_iter()
            .map(|&id| {
                let slot = this.slots[id as usize].as_ref().expect("live slot");
                let unused =
                    this.settings.deletion && this.uses[id as usize].load(Ordering::Relaxed) == 0;
                !(unused
                    || (this.settings.replace_only_on_surface
                        && !this.surface_at(world, slot.record.position, slot.record.normal)))
            })
            .collect();
        // The work budget: replacements in id order; those past it live one frame more.
        let mut traced = Vec::new();
        let mut deferred = Vec::new();
        for (&id, replace) in successors.iter().zip(replace) {
            if !replace {
                self.counters.deleted += 1;
            } else if self.take_work() {
                traced.push(id);
            } else {
                deferred.push(id);
            }
        }
        for &id in &deferred {
            if let Some(slot) = self.slots[id as usize].as_mut() {
                slot.record.lifespan_frames += 1;
            }
        }
        // Both lists are in id order.
        doomed.retain(|id| deferred.binary_search(id).is_err());
        self.counters.deferred = deferred.len() as u64;
        self.counters.expired = doomed.len() as u64;
        // Replacements, computed from the cache's state now, in id order.
        let this = &*self;
        let gathers = Instant::now();
        let made: Vec<(u32, Result<Made, RadianceCacheError>)> = traced
            .par_iter()
            .map(|&id| {
                let slot = this.slots[id as usize].as_ref().expect("live slot");
                let key = if this.settings.reuse_directions {
                    slot.key
                } else {
                    mix64(slot.key ^ ((frame as u64) << 40))
                };
                let r = &slot.record;
                let glossy = slot.radiance.is_some();
                let result = this.make(world, r.position, r.normal, r.instance, key, glossy);
                (id, result)
            })
            .collect();
        self.counters.gather_ms += gathers.elapsed().as_secs_f64() * 1e3;
        let mut predecessors = Vec::new();
        for (id, result) in made {
            let predecessor = self.slots[id as usize].as_ref().and_then(|s| s.history);
            match result {
                Ok(m) => {
                    self.counters.holes += m.holes as u64;
                    predecessors.push((predecessor, m.slot));
                }
                Err(_) => self.counters.failed += 1,
            }
        }
        for id in doomed {
            self.remove(id);
        }
        for (predecessor, slot) in predecessors {
            match self.admit(slot) {
                Ok(id) => {
                    self.counters.replaced += 1;
                    if let (Some(p), Some(h)) = (
                        predecessor,
                        self.slots[id as usize].as_ref().and_then(|s| s.history),
                    ) {
                        self.history[p as usize].successor = Some(h);
                    }
                }
                Err(_) => self.counters.failed += 1,
            }
        }
        self.expire_all = false;
        self.expire_instances.clear();
    }

    /// Pass 2 of `interpolated`: the planned records made at the current frame enter.
    fn admit_planned(&mut self) {
        let Some(plan) = &self.plan else { return };
        let Some(ids) = plan.get(self.frame as usize) else {
            return;
        };
        let slots: Vec<Slot> = ids
            .iter()
            .map(|&h| self.history[h as usize].slot.clone())
            .collect();
        for slot in slots {
            match self.insert(slot) {
                Ok(_) => self.counters.admitted += 1,
                Err(_) => self.counters.failed += 1,
            }
        }
    }

    /// True when a record of the cache is usable at `p` with normal `n` (Eq. 3), and,
    /// with `radiance`, a radiance record too.
    fn covered(&self, p: Vec3, n: Vec3, radiance: bool) -> bool {
        let (mut any, mut with_radiance) = (false, false);
        self.octree.for_each_containing(p, |id| {
            if let Some(s) = &self.slots[id as usize]
                && usable(s.record.ward_error(p, n), self.settings.accuracy)
            {
                any = true;
                with_radiance |= s.radiance.is_some();
            }
        });
        any && (with_radiance || !radiance)
    }

    /// The records this frame may compute: the smaller of `work_cap` and the time
    /// limit over the measured cost of a record (at least one); `None`: no limit.
    fn frame_cap(&self) -> Option<u64> {
        let by_time = match (self.time_cap_ms, self.ms_per_record) {
            (Some(limit), Some(ms)) if ms > 0.0 => Some(((limit / ms).floor() as u64).max(1)),
            _ => None,
        };
        match (self.work_cap, by_time) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// Folds a frame's gathers (`made` records in `ms`) into the cost per record that
    /// turns `Budget::time_ms` into a record cap. Frames of fewer than 4 records say
    /// too little and are skipped.
    fn measure_gathers(&mut self, made: u64, ms: f64) {
        if made < 4 || !ms.is_finite() {
            return;
        }
        let now = ms / made as f64;
        self.ms_per_record = Some(match self.ms_per_record {
            Some(old) => 0.5 * (old + now),
            None => now,
        });
    }

    /// Takes one record from the frame's work budget; false when it is spent.
    fn take_work(&mut self) -> bool {
        match &mut self.work_left {
            None => true,
            Some(0) => false,
            Some(n) => {
                *n -= 1;
                true
            }
        }
    }

    /// The placements of one pass the frame's work budget allows: all of them, or as
    /// many as are left, spread evenly over the pass's list (pixel order); the others
    /// are counted as skipped.
    fn within_budget(&mut self, wanted: Vec<Candidate>) -> Vec<Candidate> {
        let Some(left) = self.work_left else {
            return wanted;
        };
        let (len, take) = (wanted.len() as u64, (wanted.len() as u64).min(left));
        self.work_left = Some(left - take);
        self.counters.skipped += len - take;
        if take == len {
            return wanted;
        }
        // The middle element of each of `take` equal runs of the list.
        (0..take)
            .map(|i| wanted[((2 * i + 1) * len / (2 * take)) as usize])
            .collect()
    }

    /// Step 2: coarse-to-fine placement over `gbuffer`.
    fn place(&mut self, world: &World, gbuffer: &GBuffer) {
        let (w, h) = (gbuffer.width, gbuffer.height);
        let frame = self.frame;
        let coarsest = PLACEMENT_SPACINGS_PX[0];
        for spacing in PLACEMENT_SPACINGS_PX {
            // The pixels of this pass's grid not already on a coarser one.
            let pixels: Vec<(u32, u32)> = (0..h)
                .step_by(spacing as usize)
                .flat_map(|y| (0..w).step_by(spacing as usize).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    spacing == coarsest || x % (2 * spacing) != 0 || y % (2 * spacing) != 0
                })
                .collect();
            let this = &*self;
            // Decided from the cache before the pass, computed in parallel, kept in order.
            let wanted: Vec<Candidate> = pixels
                .par_iter()
                .filter_map(|&(x, y)| {
                    let px = gbuffer.get(x, y)?;
                    let (p, n) = shading_point(px)?;
                    let glossy = this.needs_radiance(&px.hit);
                    if this.covered(p, n, glossy) {
                        return None;
                    }
                    let key = ((frame as u64) << 32) | (y as u64 * w as u64 + x as u64);
                    Some(Candidate {
                        p,
                        n,
                        instance: px.hit.instance,
                        key,
                        glossy,
                    })
                })
                .collect();
            let chosen = self.within_budget(wanted);
            let this = &*self;
            let gathers = Instant::now();
            let new: Vec<Result<Made, RadianceCacheError>> = chosen
                .par_iter()
                .map(|c| this.make(world, c.p, c.n, Some(c.instance), c.key, c.glossy))
                .collect();
            self.counters.gather_ms += gathers.elapsed().as_secs_f64() * 1e3;
            for r in new {
                match r.and_then(|m| {
                    self.counters.holes += m.holes as u64;
                    self.admit(m.slot)
                }) {
                    Ok(_) => self.counters.created += 1,
                    Err(_) => self.counters.failed += 1,
                }
            }
        }
    }

    /// Step 3: Eq. 1 with Eq. 17 at every pixel, times ρ/π, plus the specular part of
    /// glossy pixels; counts each record's uses. When the work budget left records out
    /// of this frame, pixels no record reaches take their neighbours' light
    /// ([`fill_from_neighbours`]).
    fn shade(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let w = gbuffer.width.max(1) as usize;
        let accuracy = self.settings.accuracy;
        let frame = self.frame;
        for u in &self.uses {
            u.store(0, Ordering::Relaxed);
        }
        // Per pixel: the surface, E from the records (None: no usable record), and the
        // specular part (None: a glossy pixel no radiance record reaches).
        type Shaded = Option<(Surface, Option<Rgb>, Option<Rgb>)>;
        let this = &*self;
        let mut shaded: Vec<Shaded> = gbuffer
            .pixels
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let px = p.as_ref()?;
                let (p, n) = shading_point(px)?;
                let surface = this.surface(&px.hit);
                let mut sum = WeightedSum::default();
                this.octree.for_each_containing(p, |id| {
                    if let Some(s) = &this.slots[id as usize] {
                        let error = s.record.ward_error(p, n);
                        if usable(error, accuracy) {
                            sum.add(1.0 / error, contribution(&s.record, p, n, frame));
                            this.uses[id as usize].fetch_add(1, Ordering::Relaxed);
                        }
                    }
                });
                let specular = match surface {
                    Surface::Diffuse(_) => Some(Rgb::ZERO),
                    Surface::Glossy {
                        brdf, traced: true, ..
                    } => Some(GlossyShading::traced(
                        world,
                        p,
                        n,
                        &brdf,
                        px.to_camera,
                        this.settings.traced_rays,
                        this.settings.seed,
                        i as u64,
                        &this.record_settings.path,
                    )),
                    Surface::Glossy {
                        brdf,
                        traced: false,
                        ..
                    } => this.specular_from_records(p, n, &brdf, px.to_camera, frame),
                };
                Some((surface, sum.result(), specular))
            })
            .collect();
        if self.counters.skipped > 0 {
            let max_step_m = FILL_PLANE_R_MIN * self.record_settings.r_min_m;
            let min_cos = 1.0 - accuracy * accuracy;
            let (mut e, mut specular): (Vec<_>, Vec<_>) = shaded
                .iter()
                .map(|s| s.map_or((None, None), |(_, e, sp)| (e, sp)))
                .unzip();
            let wants_e: Vec<bool> = shaded.iter().map(Option::is_some).collect();
            let wants_specular: Vec<bool> = shaded
                .iter()
                .map(|s| matches!(s, Some((Surface::Glossy { traced: false, .. }, _, _))))
                .collect();
            // Same surface first; then across creases and curvature (normals within 60°)
            // for what that left.
            let mut filled = 0;
            let mut unfilled = 0;
            for cos in [min_cos, FILL_CREASE_COS] {
                (filled, unfilled) = {
                    let (f, u) = fill_from_neighbours(gbuffer, &mut e, &wants_e, max_step_m, cos);
                    (filled + f, u)
                };
                fill_from_neighbours(gbuffer, &mut specular, &wants_specular, max_step_m, cos);
            }
            for ((s, e), sp) in shaded.iter_mut().zip(e).zip(specular) {
                if let Some((_, se, ssp)) = s {
                    (*se, *ssp) = (e, sp);
                }
            }
            self.counters.filled = filled;
            self.counters.unfilled = unfilled;
        }
        let mut img = RgbImage::filled(gbuffer.width, gbuffer.height, Rgb::ZERO);
        img.pixels_mut()
            .par_iter_mut()
            .zip(shaded.par_iter())
            .for_each(|(out, s)| {
                let Some((surface, e, specular)) = s else {
                    return;
                };
                let e = e.unwrap_or(Rgb::ZERO);
                *out = match surface {
                    Surface::Diffuse(rho) => *rho * INV_PI * e,
                    Surface::Glossy { diffuse, .. } => {
                        *diffuse * INV_PI * e + specular.unwrap_or(Rgb::ZERO)
                    }
                };
            });
        debug_assert_eq!(img.pixels().len(), w * gbuffer.height as usize);
        img
    }

    /// The specular part at `p` (normal `n`, view `wo`) from the usable radiance
    /// records: their coefficients moved to `p` (translation and temporal gradients),
    /// rotated into the point's frame, averaged with Ward's weights, shaded with f_s's
    /// BRDF×cos coefficients. `None` where no radiance record is usable.
    fn specular_from_records(
        &self,
        p: Vec3,
        n: Vec3,
        brdf: &MetalRough,
        wo: Vec3,
        frame: u32,
    ) -> Option<Rgb> {
        let to = Frame::from_normal(n);
        let len = self.glossy.basis().len();
        let mut acc = vec![Rgb::ZERO; len];
        let mut total = 0.0f32;
        let mut moved = vec![Rgb::ZERO; len];
        self.octree.for_each_containing(p, |id| {
            let Some(s) = &self.slots[id as usize] else {
                return;
            };
            let Some(data) = &s.radiance else { return };
            let error = s.record.ward_error(p, n);
            if !usable(error, self.settings.accuracy) {
                return;
            }
            let offset = p - s.record.position;
            let dt = frame as f32 - s.record.frame as f32;
            for (((m, c), g), t) in moved
                .iter_mut()
                .zip(&data.coefficients)
                .zip(&data.translation_gradient)
                .zip(&data.temporal_gradient)
            {
                *m = *c + g.dot(offset) + *t * dt;
            }
            let from = Frame::from_normal(s.record.normal);
            let rotated = self.glossy.rotate(&moved, &from, &to);
            let weight = 1.0 / error.max(1e-6);
            for (a, r) in acc.iter_mut().zip(&rotated) {
                *a += *r * weight;
            }
            total += weight;
        });
        if total <= 0.0 {
            return None;
        }
        let b = self
            .glossy
            .specular_coefficients_tabulated(brdf, to.to_local(wo));
        Some((crate::hsh::shade(&b, &acc) * (1.0 / total)).max(Rgb::ZERO))
    }

    /// One frame: expiry (or the plan's admissions), placement, shading.
    fn frame_step(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
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
        self.place(world, gbuffer);
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

    /// Marks each live record the camera sees on `img` (`show_records`, the paper's
    /// Fig. 1c): the pixel its position projects to, coloured from red (a lifespan of
    /// one frame) to green (`max_age_frames`), as in the paper, at 8 × the image's mean luminance. A
    /// record counts as seen when its pixel's surface is not nearer the camera than the
    /// record by more than 2 R_min.
    fn draw_records(&self, world: &World, gbuffer: &GBuffer, img: &mut RgbImage) {
        let camera = &world.scene.camera;
        let camera_from_world = camera.world_from_camera.inverse();
        let eye = Vec3::from(camera.world_from_camera.translation);
        let (w, h) = (gbuffer.width, gbuffer.height);
        let tan_half_y = (camera.yfov_rad * 0.5).tan();
        let aspect = w as f32 / h.max(1) as f32;
        let level = 8.0 * illume_core::luminance(img.mean()).max(1e-6);
        let max_age = self.settings.max_age_frames.max(2) as f32;
        let slack = 2.0 * self.record_settings.r_min_m;
        for slot in self.slots.iter().flatten() {
            let r = &slot.record;
            let q = camera_from_world.transform_point3(r.position);
            if q.z >= 0.0 {
                continue;
            }
            let ndc_x = q.x / (-q.z * tan_half_y * aspect);
            let ndc_y = q.y / (-q.z * tan_half_y);
            if !(ndc_x.abs() < 1.0 && ndc_y.abs() < 1.0) {
                continue;
            }
            let x = (((ndc_x + 1.0) * 0.5 * w as f32) as u32).min(w - 1);
            let y = (((1.0 - ndc_y) * 0.5 * h as f32) as u32).min(h - 1);
            let Some(px) = gbuffer.get(x, y) else {
                continue;
            };
            if (px.hit.position - eye).length() < (r.position - eye).length() - slack {
                continue;
            }
            let t = ((r.lifespan_frames as f32 - 1.0) / (max_age - 1.0)).clamp(0.0, 1.0);
            *img.get_mut(x, y) = Rgb::new(1.0 - t, t, 0.0) * level;
        }
    }

    /// The present in what records age by: the age clock in real time, frames otherwise.
    fn age_now(&self) -> u32 {
        if self.settings.paced_real_time {
            self.age_clock
        } else {
            self.frame
        }
    }

    /// True when the frame being made (`self.frame`) ticks the real-time age clock (at
    /// its start): it is the frame of the last change or one of the δt_max − 1 after it.
    fn age_clock_running(&self) -> bool {
        self.settings.paced_real_time
            && self
                .last_world_change
                .is_some_and(|c| self.frame < c.saturating_add(self.settings.max_age_frames))
    }

    /// The world changes after resting: records that stopped ageing resume with their
    /// remaining lives spread over 1 to their lifespan (by their key), as records made
    /// frame after frame have them, so that they expire over the next δt_max frames
    /// instead of all at once.
    fn stagger_ages(&mut self) {
        let clock = self.age_clock;
        for slot in self.slots.iter_mut().flatten() {
            let lifespan = slot.record.lifespan_frames.max(1);
            let age = (mix64(slot.key) % u64::from(lifespan)) as u32;
            slot.made_clock = slot.made_clock.min(clock.saturating_sub(age));
        }
    }

    /// Drops the cache (records, octree, frame count, pending expiries), keeping the
    /// plan and the history.
    fn clear_cache(&mut self) {
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

    /// Pass 1 of `interpolated` over the timeline on a private world (see the module
    /// docs), then the interpolated gradients (Eq. 21–23) and the plan.
    fn plan_timeline(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), RadianceCacheError> {
        let times = self.timeline.times().to_vec();
        let (w, h) = (self.timeline.width(), self.timeline.height());
        progress.begin(
            "radiance_cache pass 1 (records of the whole timeline)",
            times.len() as u64,
        );
        self.clear_cache();
        self.history.clear();
        self.recording = true;
        let mut private = world.at_time(times[0]);
        for (i, &t) in times.iter().enumerate() {
            if i > 0 {
                private.set_time(t);
            }
            let gbuffer = GBuffer::rasterize(&private, w, h);
            self.frame_step(&private, &gbuffer);
            progress.set(i as u64 + 1);
        }
        self.recording = false;
        progress.end();
        // Eq. 21–23: each replaced record moves towards its replacement.
        for k in 0..self.history.len() {
            if let Some(l) = self.history[k].successor {
                let (rk, rl) = (
                    &self.history[k].slot.record,
                    &self.history[l as usize].slot.record,
                );
                let span = rl.frame.saturating_sub(rk.frame);
                if let Ok(g) = interpolated_gradient(&rk.value, rk.frame, &rl.value, rl.frame) {
                    self.history[k].slot.record.temporal_gradient = g;
                }
                let next = self.history[l as usize]
                    .slot
                    .radiance
                    .as_ref()
                    .map(|d| d.coefficients.clone());
                if let (Some(next), Some(data), true) =
                    (next, self.history[k].slot.radiance.as_mut(), span > 0)
                {
                    data.temporal_gradient = next
                        .iter()
                        .zip(&data.coefficients)
                        .map(|(a, b)| (*a - *b) * (1.0 / span as f32))
                        .collect();
                }
            }
        }
        let mut plan = vec![Vec::new(); times.len()];
        for (i, p) in self.history.iter().enumerate() {
            if let Some(at) = plan.get_mut(p.slot.record.frame as usize) {
                at.push(i as u32);
            }
        }
        let planned = self.history.len();
        self.clear_cache();
        self.plan = Some(plan);
        progress.message(&format!(
            "radiance_cache: pass 1 made {planned} records over {} frames",
            times.len()
        ));
        Ok(())
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

    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        self.changed_since_frame = true;
        let world_changed = changes
            .iter()
            .any(|c| !matches!(c, SceneChange::CameraMoved { .. }));
        if world_changed {
            if self.settings.paced_real_time && !self.age_clock_running() {
                self.stagger_ages();
            }
            self.last_world_change = Some(self.frame);
        }
        // On the timeline: the frame about to be rendered is the timeline's, in time and
        // in everything records depend on. τ and the lifespans handle such changes.
        let on_timeline = self.temporal()
            && self
                .timeline
                .times()
                .get(self.frame as usize)
                .is_some_and(|&t| {
                    t == world.scene.time
                        && same_lighting(&self.timeline.scene_at_time(t), &world.scene)
                });
        if on_timeline {
            return ChangeResponse::Updated;
        }
        if world_changed {
            // Pass 2's plan assumed the timeline: online from here.
            self.plan = None;
            self.next_world = None;
        }
        if !self.settings.expire_on_surprise {
            return ChangeResponse::Updated;
        }
        for c in changes {
            match c {
                SceneChange::CameraMoved { .. } => {}
                SceneChange::InstanceMoved { instance, .. }
                | SceneChange::InstanceAdded { instance }
                | SceneChange::InstanceRemoved { instance, .. } => {
                    self.expire_instances.push(*instance)
                }
                _ => self.expire_all = true,
            }
        }
        ChangeResponse::Updated
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
