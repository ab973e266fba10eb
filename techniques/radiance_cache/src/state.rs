//! The technique: [`RadianceCache`], the frame loop of the `per_frame` and `reuse`
//! modes over the G-buffer.
//!
//! Each frame ([`Technique::indirect`]):
//! 1. Records leave the cache: all of them in `per_frame` (the paper's baseline, a new
//!    cache every frame); in `reuse`, those older than δt_max (`max_age_frames`, Eq. 12;
//!    without the §4.3 reprojection there is no τ, so Eq. 10 cannot shorten a lifespan)
//!    and those a scene change expired ([`RadianceCache::scene_changed`]).
//! 2. New records are placed coarse to fine over the G-buffer (the classic multi-pass
//!    scheme): pixels on grids of spacing 32, 16, 8, 4, 2 and 1 px; a pixel of a pass
//!    gets a new record only if no record is usable there (w ≥ 1/a, Eq. 2–3). Which
//!    pixels get one is decided from the cache as it was before the pass, then the
//!    records are computed in parallel and inserted in pixel order: records are pure
//!    functions of (seed, record key, cell), the key is (frame, pixel), so the cache and
//!    the image do not depend on the thread count. Two pixels of the same pass may both
//!    get a record although one would have covered the other: the price of that
//!    determinism, paid mostly at the fine passes where gaps are small.
//! 3. Each pixel is shaded from the usable records (Eq. 1 with Eq. 4, the octree giving
//!    the candidates): indirect radiance = ρ/π·E, ρ the pixel's albedo.
//!
//! **Glossy surfaces are shaded Lambertian for now** (ρ = base colour, irradiance
//! records only): radiance records (hemispherical harmonics, [`crate::hsh`]) are to come.
//!
//! **Scene changes** (`reuse`): records are world-space and keep their positions, so a
//! camera move keeps them all. An instance that moved, was added or removed expires the
//! records made on it (they would float in the air or lie inside it). A light, sky or
//! material change expires every record (their irradiance is wrong everywhere). Records
//! near a moving object but not on it keep the light of the object's old position until
//! δt_max ends their life: the ghosting of Fig. 5c, which τ and the temporal gradients
//! (to come) are there to cut. This holds for timeline steps and surprises alike;
//! `expire_on_surprise = false` turns it off (changes then expire nothing).
//!
//! **Budget.** All records a frame needs are computed in [`Technique::indirect`] (the
//! G-buffer says where); [`Budget`] is not honoured yet and `advance` does nothing.

use crate::octree::Octree;
use crate::record::{IrradianceRecord, RecordSettings, WeightedSum, usable};
use crate::settings::{RadianceCacheSettings, TemporalMode};
use crate::{NAME, RadianceCacheError};
use illume_core::image::RgbImage;
use illume_core::{Counters, INV_PI, Rgb, Vec3};
use illume_scene::{InstanceId, SceneChange, Timeline};
use illume_transport::{Budget, ChangeResponse, GBuffer, GBufferPixel, Technique, World};
use rayon::prelude::*;
use std::time::Instant;

/// Grid spacings of the placement passes, coarse to fine \[px\].
pub const PLACEMENT_SPACINGS_PX: [u32; 6] = [32, 16, 8, 4, 2, 1];

/// Counters of the last frame and since construction.
#[derive(Clone, Copy, Debug, Default)]
struct FrameCounters {
    created: u64,
    reused: u64,
    expired: u64,
    failed: u64,
    created_total: u64,
    place_ms: f64,
    shade_ms: f64,
}

/// Temporal radiance caching, `per_frame` and `reuse` modes (see the module docs).
pub struct RadianceCache {
    settings: RadianceCacheSettings,
    record_settings: RecordSettings,
    /// Records by id (the octree's ids); `None` for free slots.
    records: Vec<Option<IrradianceRecord>>,
    free: Vec<u32>,
    octree: Octree,
    /// Frames shaded so far: the next frame's index.
    frame: u32,
    /// A scene change expired every record; done at the next frame.
    expire_all: bool,
    /// Instances whose records a scene change expired; done at the next frame.
    expire_instances: Vec<InstanceId>,
    counters: FrameCounters,
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

impl RadianceCache {
    /// The technique for `world` with `settings`; `timeline` gives the image size for
    /// now (the reprojection and the two-pass mode will use its frames). Errors on
    /// invalid settings (`radiance_cache.FIELD: …`), and for the temporal modes not
    /// built yet (`extrapolated`, `interpolated`).
    pub fn new(
        world: &World,
        timeline: &Timeline,
        settings: RadianceCacheSettings,
    ) -> Result<Self, RadianceCacheError> {
        let _ = timeline;
        settings.validate()?;
        if let mode @ (TemporalMode::Extrapolated | TemporalMode::Interpolated) = settings.temporal
        {
            let name = if mode == TemporalMode::Extrapolated {
                "extrapolated"
            } else {
                "interpolated"
            };
            return Err(RadianceCacheError::InvalidSetting {
                field: "temporal",
                reason: format!(
                    "`{name}` is not built yet (it needs the §4.3 next-frame reprojection, \
                     to come); use `per_frame` or `reuse`"
                ),
            });
        }
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
            records: Vec::new(),
            free: Vec::new(),
            octree: Octree::new(),
            frame: 0,
            expire_all: false,
            expire_instances: Vec::new(),
            counters: FrameCounters::default(),
        })
    }

    /// Records alive.
    pub fn records_alive(&self) -> usize {
        self.octree.len()
    }

    /// Records created since construction (or the last reset).
    pub fn records_created(&self) -> u64 {
        self.counters.created_total
    }

    /// The live records, in id order.
    pub fn records(&self) -> impl Iterator<Item = &IrradianceRecord> {
        self.records.iter().flatten()
    }

    fn remove(&mut self, id: u32) {
        if self.records[id as usize].take().is_some() {
            self.octree.remove(id);
            self.free.push(id);
        }
    }

    fn insert(&mut self, record: IrradianceRecord) -> Result<(), RadianceCacheError> {
        let id = match self.free.pop() {
            Some(id) => id,
            None => {
                self.records.push(None);
                (self.records.len() - 1) as u32
            }
        };
        let radius = record.influence_radius_m(self.settings.accuracy);
        if let Err(e) = self.octree.insert(id, record.position, radius) {
            self.free.push(id);
            return Err(e);
        }
        self.records[id as usize] = Some(record);
        Ok(())
    }

    /// Step 1: the records that leave the cache before frame `self.frame`.
    fn expire(&mut self) {
        let frame = self.frame;
        let max_age = self.settings.max_age_frames;
        let all = self.expire_all || self.settings.temporal == TemporalMode::PerFrame;
        let doomed: Vec<u32> = self
            .records
            .iter()
            .enumerate()
            .filter_map(|(id, r)| {
                let r = r.as_ref()?;
                let gone = all
                    || frame.saturating_sub(r.frame) >= max_age
                    || r.instance
                        .is_some_and(|i| self.expire_instances.contains(&i));
                gone.then_some(id as u32)
            })
            .collect();
        self.counters.expired = doomed.len() as u64;
        for id in doomed {
            self.remove(id);
        }
        self.expire_all = false;
        self.expire_instances.clear();
    }

    /// True when a record of the cache is usable at `p` with normal `n` (Eq. 3).
    fn covered(&self, p: Vec3, n: Vec3) -> bool {
        let mut found = false;
        self.octree.for_each_containing(p, |id| {
            if !found
                && let Some(r) = &self.records[id as usize]
                && usable(r.ward_error(p, n), self.settings.accuracy)
            {
                found = true;
            }
        });
        found
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
            let new: Vec<Result<IrradianceRecord, RadianceCacheError>> = pixels
                .par_iter()
                .filter_map(|&(x, y)| {
                    let (p, n) = shading_point(gbuffer.get(x, y)?)?;
                    if this.covered(p, n) {
                        return None;
                    }
                    let instance = gbuffer.get(x, y).map(|px| px.hit.instance);
                    let key = ((frame as u64) << 32) | (y as u64 * w as u64 + x as u64);
                    Some(IrradianceRecord::compute(
                        world,
                        p,
                        n,
                        frame,
                        instance,
                        key,
                        &this.record_settings,
                    ))
                })
                .collect();
            for r in new {
                match r.and_then(|r| self.insert(r)) {
                    Ok(()) => self.counters.created += 1,
                    Err(_) => self.counters.failed += 1,
                }
            }
        }
    }

    /// Step 3: Eq. 1 with Eq. 4 at every pixel, times ρ/π.
    fn shade(&self, gbuffer: &GBuffer) -> RgbImage {
        let w = gbuffer.width.max(1) as usize;
        let mut img = RgbImage::filled(gbuffer.width, gbuffer.height, Rgb::ZERO);
        let accuracy = self.settings.accuracy;
        img.pixels_mut()
            .par_chunks_mut(w)
            .zip(gbuffer.pixels.par_chunks(w))
            .for_each(|(row, px)| {
                for (out, p) in row.iter_mut().zip(px) {
                    let Some(px) = p else { continue };
                    let Some((p, n)) = shading_point(px) else {
                        continue;
                    };
                    let mut sum = WeightedSum::default();
                    self.octree.for_each_containing(p, |id| {
                        if let Some(r) = &self.records[id as usize] {
                            let error = r.ward_error(p, n);
                            if usable(error, accuracy) {
                                sum.add(1.0 / error, r.contribution(p, n));
                            }
                        }
                    });
                    if let Some(e) = sum.result() {
                        *out = px.hit.albedo * INV_PI * e;
                    }
                }
            });
        img
    }
}

impl Technique for RadianceCache {
    fn name(&self) -> &'static str {
        NAME
    }

    fn scene_changed(&mut self, _world: &World, changes: &[SceneChange]) -> ChangeResponse {
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

    fn advance(&mut self, _world: &World, _budget: &Budget) {}

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let t0 = Instant::now();
        let before = self.octree.len() as u64;
        self.counters.created = 0;
        self.counters.failed = 0;
        self.expire();
        self.counters.reused = before - self.counters.expired;
        self.place(world, gbuffer);
        self.counters.created_total += self.counters.created;
        let t1 = Instant::now();
        let img = self.shade(gbuffer);
        self.counters.place_ms = (t1 - t0).as_secs_f64() * 1e3;
        self.counters.shade_ms = t1.elapsed().as_secs_f64() * 1e3;
        self.frame += 1;
        img
    }

    fn stats(&self) -> Counters {
        let c = &self.counters;
        let mut out = Counters::new();
        let memory = self.records.capacity() * std::mem::size_of::<Option<IrradianceRecord>>()
            + self.octree.node_count() * 128
            + self.octree.len() * 16;
        for (name, x) in [
            ("records_alive", self.octree.len() as f64),
            ("records_created", c.created as f64),
            ("records_reused", c.reused as f64),
            ("records_expired", c.expired as f64),
            ("records_failed", c.failed as f64),
            ("records_created_total", c.created_total as f64),
            ("memory_bytes", memory as f64),
            ("place_ms", c.place_ms),
            ("shade_ms", c.shade_ms),
        ] {
            out.set(name, x);
        }
        out
    }

    fn reset(&mut self) {
        self.records.clear();
        self.free.clear();
        self.octree = Octree::new();
        self.frame = 0;
        self.expire_all = false;
        self.expire_instances.clear();
        self.counters = FrameCounters::default();
    }
}
