//! Step 2 of a frame, **placement, coarse to fine**, and the making of a record.
//!
//! Grids of spacing 32, 16, 8, 4, 2 and 1 px; a pixel of a pass gets a new record only
//! if no record is usable there (w ≥ 1/a, Eq. 2–3). Which pixels get one is decided
//! from the cache before the pass, then the records are computed in parallel and
//! inserted in pixel order: records are pure functions of (seed, key, cell), the key is
//! (frame, pixel), so the cache and the image do not depend on the thread count.
//!
//! **A new record's future** (§4.3): in the temporal modes its gather is reprojected into
//! the next timeline frame's world ([`crate::reproject`]), giving E(t + 1), hence τ and
//! the lifespan, and the extrapolated temporal gradient (Eq. 18–20). Where the next frame
//! is unknown (the last frame, a frame off the timeline) or the scene does not change
//! between the two, τ = 1 and the record lives δt_max frames.

use crate::record::{IrradianceRecord, usable};
use crate::reproject::reproject;
use crate::settings::TemporalMode;
use crate::shading::shading_point;
use crate::state::{RadianceCache, Slot};
use crate::temporal::{change_rate, lifespan_frames};
use crate::update::same_lighting;
use crate::{HemisphereGather, RadianceCacheError};
use illume_core::{Progress, Vec3};
use illume_scene::InstanceId;
use illume_transport::{GBuffer, World};
use rayon::prelude::*;
use std::time::Instant;

/// Grid spacings of the placement passes, coarse to fine \[px\].
pub const PLACEMENT_SPACINGS_PX: [u32; 6] = [32, 16, 8, 4, 2, 1];

/// Records a thread makes between two progress reports of a still's placement pass:
/// ≈ 0.3 s at the default 64×64 rays a record, and the threads' wait at each report
/// (half a record each, on average) under 1 % of the pass.
const REPORTED_RECORDS_PER_THREAD: usize = 64;

/// A pixel of a placement pass that needs a new record.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub(crate) p: Vec3,
    pub(crate) n: Vec3,
    pub(crate) instance: InstanceId,
    pub(crate) key: u64,
    pub(crate) glossy: bool,
}

/// A new record and what its making found.
pub(crate) struct Made {
    pub(crate) slot: Slot,
    pub(crate) holes: u32,
}

impl RadianceCache {
    /// The world of timeline frame `frame + 1`, for reprojecting records made at
    /// `frame`, and whether the scene changes between the two; `None` past the
    /// timeline's end.
    pub(crate) fn prepare_next(&mut self, world: &World) {
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
    pub(crate) fn make(
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
        record.harmonic_distance_m = record
            .harmonic_distance_m
            .max(self.screen_floor_m(world, p))
            .min(rs.r_max_m);
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

    /// The smallest R_k `min_sphere_fraction` allows at `p` \[m\]: the sphere of use
    /// a·R_k spans that fraction of the image height at p's distance from the camera
    /// (the image is 2·d·tan(fov/2) high there); 0 when off.
    fn screen_floor_m(&self, world: &World, p: Vec3) -> f32 {
        let s = &self.settings;
        if s.min_sphere_fraction <= 0.0 {
            return 0.0;
        }
        let camera = &world.scene.camera;
        let eye = Vec3::from(camera.world_from_camera.translation);
        let height_m = 2.0 * (0.5 * camera.yfov_rad).tan() * p.distance(eye);
        let floor = s.min_sphere_fraction * height_m / s.accuracy;
        if floor.is_finite() { floor } else { 0.0 }
    }

    /// True when a record of the cache is usable at `p` with normal `n` (Eq. 3), and,
    /// with `radiance`, a radiance record too.
    pub(crate) fn covered(&self, p: Vec3, n: Vec3, radiance: bool) -> bool {
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

    /// Step 2: coarse-to-fine placement over `gbuffer`. With `progress` (a still's
    /// frame), each pass that makes records is a phase counted in records, its gathers
    /// computed in parallel chunks of [`REPORTED_RECORDS_PER_THREAD`] a thread between
    /// reports (the same records, in the same order).
    pub(crate) fn place(
        &mut self,
        world: &World,
        gbuffer: &GBuffer,
        mut progress: Option<&mut dyn Progress>,
    ) {
        let (w, h) = (gbuffer.width, gbuffer.height);
        let frame = self.frame;
        let coarsest = PLACEMENT_SPACINGS_PX[0];
        for (pass, spacing) in PLACEMENT_SPACINGS_PX.into_iter().enumerate() {
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
            let make =
                |c: &Candidate| this.make(world, c.p, c.n, Some(c.instance), c.key, c.glossy);
            let new: Vec<Result<Made, RadianceCacheError>> = match progress.as_deref_mut() {
                Some(progress) if !chosen.is_empty() => {
                    progress.begin(
                        &format!(
                            "radiance_cache records, pass {} of {} ({spacing}-px grid)",
                            pass + 1,
                            PLACEMENT_SPACINGS_PX.len()
                        ),
                        chosen.len() as u64,
                    );
                    let mut new = Vec::with_capacity(chosen.len());
                    let chunk = REPORTED_RECORDS_PER_THREAD * rayon::current_num_threads();
                    for part in chosen.chunks(chunk) {
                        new.par_extend(part.par_iter().map(make));
                        progress.set(new.len() as u64);
                    }
                    progress.end();
                    new
                }
                _ => chosen.par_iter().map(make).collect(),
            };
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
}
