//! [`PhotonStream`]: VSLs, the shared photon pool, the simulation thread, and the
//! [`Technique`] implementation the renderer drives.

use crate::emit::Emitter;
use crate::placement::{PlacementSettings, VslSet};
use crate::pool::PhotonPool;
use crate::settings::{PhotonStreamSettings, StreamMode};
use crate::shade::{ShadeStats, VslField, shade};
use crate::stream::{PoolSnapshot, SharedPool, StreamConfig, spawn};
use crate::{PhotonStreamError, update};
use illume_core::image::RgbImage;
use illume_core::{Counters, Rgb};
use illume_scene::SceneChange;
use illume_transport::{Budget, ChangeResponse, GBuffer, SharedWorld, Technique, World};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

/// Photon streaming with virtual surface lights (technique name `photon_stream`).
pub struct PhotonStream {
    settings: PhotonStreamSettings,
    vsls: Arc<VslSet>,
    shared: Arc<SharedPool>,
    thread: Option<JoinHandle<()>>,
    inv_quantum: f64,
    frames: u64,
    last_shade: ShadeStats,
    shading_ms: f64,
    warmed_up: bool,
    /// Photons pushed to the pool when the last [`Technique::indirect`] read it.
    pushed_at_indirect: Option<u64>,
    /// Impacts pushed to the pool at the end of the last [`Technique::advance`]
    /// ([`PhotonStreamSettings::turnover_frames`]).
    impacts_at_advance: Option<u64>,
    /// Photons the last [`Technique::advance`] traced to keep the turnover.
    topped_up: u64,
    /// The VSL powers the last frame showed ([`PhotonStreamSettings::smooth_frames`]).
    shown: Option<Shown>,
}

/// What [`PhotonStream::smooth`] carries from one frame to the next.
#[derive(Debug)]
struct Shown {
    front_w: Vec<Rgb>,
    back_w: Vec<Rgb>,
    /// The relative change still owed after this frame.
    lag: f64,
}

/// How far `field`'s powers are from `shown`'s: Σ|ΔΦ| over every VSL side and channel
/// over the larger of the two totals (0 for equal powers, at most 2, 1 from darkness).
fn relative_change(shown: &Shown, field: &VslField) -> f64 {
    let (mut diff, mut a, mut b) = (0.0f64, 0.0f64, 0.0f64);
    let sides = [
        (&shown.front_w, &field.front_w),
        (&shown.back_w, &field.back_w),
    ];
    for (was, now) in sides {
        for (w, x) in was.iter().zip(now.iter()) {
            diff += f64::from((*x - *w).abs().element_sum());
            a += f64::from(w.element_sum());
            b += f64::from(x.element_sum());
        }
    }
    let total = a.max(b);
    if total > 0.0 { diff / total } else { 0.0 }
}

/// VSL fluxes \[W\] from a pool snapshot: front and back side of each VSL.
pub fn fluxes(snapshot: &PoolSnapshot) -> (Vec<Rgb>, Vec<Rgb>) {
    let scale = if snapshot.photons == 0 {
        0.0
    } else {
        snapshot.quantum_w / snapshot.photons as f64
    };
    let to_w = |q: &illume_transport::flux::Quanta| q.to_flux(scale);
    snapshot
        .quanta
        .chunks_exact(2)
        .map(|c| (to_w(&c[0]), to_w(&c[1])))
        .unzip()
}

impl PhotonStream {
    /// Places the VSLs on `world`'s scene and, in [`StreamMode::Streaming`], starts the
    /// simulation thread (which traces in its own snapshot of `world`, renewed at each
    /// scene change that affects light: [`Technique::scene_changed`]).
    pub fn new(
        world: &SharedWorld,
        settings: PhotonStreamSettings,
    ) -> Result<Self, PhotonStreamError> {
        settings.validate()?;
        let (vsls, quantum_w) = {
            let w = world.read().map_err(|_| PhotonStreamError::PoisonedWorld)?;
            let vsls = VslSet::place(
                &w.scene,
                &PlacementSettings {
                    vsl_count: settings.vsl_count,
                    oversampling: settings.oversampling,
                    triangle_scale: settings.triangle_scale,
                    seed: settings.seed,
                    oriented_cells: settings.cells == crate::settings::VslCells::Oriented,
                },
            );
            if vsls.is_empty() {
                return Err(PhotonStreamError::NoSurfaces {
                    scene: w.scene.source.clone(),
                });
            }
            // 2^24 quanta per photon of the scene's total power: 6e-8 relative precision.
            let power = w.lights.total_power().max_element() as f64;
            (
                vsls,
                if power > 0.0 {
                    power / (1u64 << 24) as f64
                } else {
                    1e-12
                },
            )
        };
        let vsls = Arc::new(vsls);
        let pool = PhotonPool::new(settings.pool_size as usize, vsls.len(), quantum_w);
        let snapshot = Arc::new(
            world
                .read()
                .map_err(|_| PhotonStreamError::PoisonedWorld)?
                .clone(),
        );
        let shared = Arc::new(SharedPool::new(pool, settings.start_paused, snapshot));
        let inv_quantum = 1.0 / quantum_w;
        let thread = match settings.mode {
            StreamMode::Streaming => Some(
                spawn(
                    Arc::clone(&vsls),
                    Arc::clone(&shared),
                    StreamConfig {
                        batch_photons: settings.batch_photons as u64,
                        priority: settings.stream_priority,
                        path: settings.photon_path(),
                        seed: settings.seed,
                        first_deposit: settings.first_deposit(),
                        inv_quantum,
                        share: settings.stream_share,
                        rest_when_settled: settings.rest_when_settled,
                    },
                )
                .map_err(PhotonStreamError::Thread)?,
            ),
            StreamMode::Deterministic => None,
        };
        Ok(Self {
            settings,
            vsls,
            shared,
            thread,
            inv_quantum,
            frames: 0,
            last_shade: ShadeStats::default(),
            shading_ms: 0.0,
            warmed_up: false,
            pushed_at_indirect: None,
            impacts_at_advance: None,
            topped_up: 0,
            shown: None,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &PhotonStreamSettings {
        &self.settings
    }

    /// The placed VSLs.
    pub fn vsls(&self) -> &VslSet {
        &self.vsls
    }

    /// Shoots `count` photons now, on the calling thread and rayon (the deterministic
    /// mode's step; usable in streaming mode too, e.g. to warm the pool up).
    pub fn shoot(&mut self, world: &World, count: u64) {
        let emitter = Emitter::new(
            world,
            &self.vsls,
            self.inv_quantum,
            self.settings.photon_path(),
            self.settings.seed,
        )
        .with_first_deposit(self.settings.first_deposit());
        let epoch = self.shared.epoch();
        let first = self.shared.reserve(count);
        let batch = emitter.trace_parallel(world, first, count);
        self.shared.apply(&batch, epoch);
    }

    /// Shoots photons until the pool is full (or 4 × pool size photons were shot, for
    /// scenes where most photons escape). Returns the photons shot.
    pub fn warm_up(&mut self, world: &World) -> u64 {
        let capacity = self.settings.pool_size as u64;
        let mut shot = 0;
        while (self.shared.lock().pool.len() as u64) < capacity && shot < 4 * capacity {
            let n = (capacity / 4).clamp(1000, 50_000);
            self.shoot(world, n);
            shot += n;
        }
        self.warmed_up = true;
        shot
    }

    /// Streaming mode, [`PhotonStreamSettings::turnover_frames`]: photons to trace now so
    /// that the impacts pooled since the last frame reach `pool_size / turnover_frames`,
    /// while photons from before the last lighting change remain (0 when the thread
    /// keeps up, is paused or rests, and at the first frame).
    fn turnover_deficit(&self) -> u64 {
        let frames = u64::from(self.settings.turnover_frames);
        let Some(before) = self.impacts_at_advance else {
            return 0;
        };
        if frames == 0 || self.shared.is_paused() {
            return 0;
        }
        let s = self.shared.lock();
        if s.stale_photons() == 0 {
            return 0; // every pooled photon was traced after the last change
        }
        let pool = &s.pool;
        let floor = (pool.capacity() as u64).div_ceil(frames);
        let deficit = floor.saturating_sub(pool.impacts_pushed() - before);
        // Impacts per photon so far (≥ 1 in a closed scene; escaping photons lower it).
        let per_photon = pool.impacts_pushed() as f64 / pool.photons_pushed().max(1) as f64;
        (deficit as f64 / per_photon.max(0.25)).ceil() as u64
    }

    /// A consistent copy of the VSL powers.
    pub fn snapshot(&self) -> PoolSnapshot {
        self.shared.snapshot()
    }

    /// The VSL field in world space for `world`'s current transforms.
    pub fn field(&self, world: &World) -> VslField {
        let (front_w, back_w) = fluxes(&self.snapshot());
        let (positions, normals) = self.vsls.world_frames(&world.scene);
        let area_m2 = self.vsls.vsls().iter().map(|v| v.area_m2).collect();
        VslField {
            positions,
            normals,
            front_w,
            back_w,
            area_m2,
            inverse_square: self.settings.falloff == crate::settings::VslFalloff::InverseSquare,
        }
    }

    /// The powers to show this frame ([`PhotonStreamSettings::smooth_frames`]): the pool's
    /// `field`, or, when it differs from the last frame's powers by more than
    /// 1/`smooth_frames` (relative L1 over every VSL side), the last frame's powers moved
    /// that far towards it. Streaming mode only.
    fn smooth(&mut self, mut field: VslField) -> VslField {
        let n = self.settings.smooth_frames;
        if n == 0 || self.thread.is_none() {
            return field;
        }
        let mut lag = 0.0;
        if let Some(prev) = self
            .shown
            .take()
            .filter(|p| p.front_w.len() == field.front_w.len())
        {
            let gap = relative_change(&prev, &field);
            let step = 1.0 / f64::from(n);
            if gap > step {
                let a = (step / gap) as f32;
                let ramp = |shown: &mut [Rgb], was: &[Rgb]| {
                    for (x, w) in shown.iter_mut().zip(was) {
                        *x = *w + (*x - *w) * a;
                    }
                };
                ramp(&mut field.front_w, &prev.front_w);
                ramp(&mut field.back_w, &prev.back_w);
                lag = gap - step;
            }
        }
        self.shown = Some(Shown {
            front_w: field.front_w.clone(),
            back_w: field.back_w.clone(),
            lag,
        });
        field
    }

    /// The change the displayed powers still owe (relative L1; 0 when they show the
    /// pool).
    fn display_lag(&self) -> f64 {
        self.shown.as_ref().map_or(0.0, |s| s.lag)
    }

    /// The VSL powers \[W\] (front, back) the last frame showed: the pool's, or on their
    /// way to them ([`PhotonStreamSettings::smooth_frames`]). `None` before the first
    /// frame, in deterministic mode and with smoothing off.
    pub fn shown_powers(&self) -> Option<(&[Rgb], &[Rgb])> {
        self.shown
            .as_ref()
            .map(|s| (s.front_w.as_slice(), s.back_w.as_slice()))
    }

    /// Pauses the simulation thread (no effect in deterministic mode).
    pub fn pause(&self) {
        self.shared.set_paused(true);
    }

    /// Resumes the simulation thread.
    pub fn resume(&self) {
        self.shared.set_paused(false);
    }

    /// True while paused.
    pub fn is_paused(&self) -> bool {
        self.shared.is_paused()
    }

    /// True while the simulation thread blocks (paused or resting): the batch it was
    /// tracing when paused has landed, and no other starts until it is woken.
    pub fn is_thread_waiting(&self) -> bool {
        self.shared.is_thread_waiting()
    }

    /// Checks the pool's invariants (power conservation, K); see
    /// [`PhotonPool::validate`].
    pub fn validate(&self) -> Result<(), String> {
        self.shared.lock().pool.validate()
    }

    /// Impacts per second the stream measured while it last streamed (0 until measured;
    /// kept while the thread rests, where the `impacts_per_s` counter says 0).
    pub fn impacts_per_s(&self) -> f64 {
        self.shared.lock().impacts_per_s
    }

    /// Stats of the last shading pass.
    pub fn last_shade(&self) -> ShadeStats {
        self.last_shade
    }
}

impl Drop for PhotonStream {
    fn drop(&mut self) {
        self.shared.request_stop();
        if let Some(t) = self.thread.take() {
            // A panicked simulation thread has nothing left to clean up.
            let _ = t.join();
        }
    }
}

impl Technique for PhotonStream {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        // The thread's next batches trace in the changed world (published before the
        // policy's flush; see `SharedPool::publish_world`). A camera move changes no photon.
        if self.thread.is_some() && changes.iter().any(update::affects_lighting) {
            self.shared.publish_world(Arc::new(world.clone()));
        }
        update::on_changes(&self.shared, self.settings.on_change, changes)
    }

    /// First call with [`PhotonStreamSettings::warm_up`]: fills the pool. Then, in
    /// deterministic mode: shoots `budget.work` photons (default
    /// [`PhotonStreamSettings::photons_per_frame`]). Streaming mode: the thread runs by
    /// itself (`budget` is ignored); when it has fallen behind a change, the frame loop
    /// traces what [`PhotonStreamSettings::turnover_frames`] asks.
    fn advance(&mut self, world: &World, budget: &Budget) {
        if self.settings.warm_up && !self.warmed_up {
            self.warm_up(world);
        }
        match self.settings.mode {
            StreamMode::Deterministic => {
                let n = budget.work.unwrap_or(self.settings.photons_per_frame);
                self.shoot(world, n);
            }
            StreamMode::Streaming => {
                // The count per photon is an average: a second round (rarely a third)
                // makes up a shortfall.
                self.topped_up = 0;
                for _ in 0..4 {
                    let n = self.turnover_deficit();
                    if n == 0 {
                        break;
                    }
                    self.shoot(world, n);
                    self.topped_up += n;
                }
                self.impacts_at_advance = Some(self.shared.lock().pool.impacts_pushed());
            }
        }
    }

    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let t0 = Instant::now();
        // Read before the pool's snapshot: a batch pushed in between makes `settled`
        // false for one more frame, never true too early.
        self.pushed_at_indirect = Some(self.shared.lock().pool.photons_pushed());
        let field = self.field(world);
        let field = self.smooth(field);
        let (img, stats) = shade(
            world,
            gbuffer,
            &field,
            &self.vsls,
            &self.settings,
            self.frames,
        );
        self.frames += 1;
        self.last_shade = stats;
        self.shading_ms = t0.elapsed().as_secs_f64() * 1e3;
        img
    }

    fn stats(&self) -> Counters {
        let now = self.shared.now_s();
        let s = self.shared.lock();
        let pool = &s.pool;
        let age = pool.oldest_time_s().map_or(0.0, |t| now - t);
        let stale = if pool.photons() == 0 {
            0.0
        } else {
            s.stale_photons() as f64 / pool.photons() as f64
        };
        let latency = if s.impacts_per_s > 0.0 {
            pool.capacity() as f64 / s.impacts_per_s
        } else {
            f64::INFINITY
        };
        let resting = self.shared.is_resting();
        let now_rate = |r: f64| if resting { 0.0 } else { r };
        let mut c = Counters::new();
        for (name, x) in [
            ("photons_shot", pool.photons_pushed() as f64),
            ("impacts_shot", pool.impacts_pushed() as f64),
            // Rates now: 0 while the thread rests (`latency_s` keeps the last streaming
            // rate: the time a change would take to turn the pool over).
            ("photons_per_s", now_rate(s.photons_per_s)),
            ("impacts_per_s", now_rate(s.impacts_per_s)),
            ("rays_per_s", now_rate(s.rays_per_s)),
            ("pool_impacts", pool.len() as f64),
            ("pool_fill", pool.len() as f64 / pool.capacity() as f64),
            ("pool_photons", pool.photons() as f64),
            ("pool_age_s", age),
            ("latency_s", latency),
            ("stale_fraction", stale),
            ("stream_resting", if resting { 1.0 } else { 0.0 }),
            ("vsl_count", self.vsls.len() as f64),
            ("vsls_per_tile", self.last_shade.vsls_per_tile()),
            ("shading_ms", self.shading_ms),
            ("shadow_rays", self.last_shade.shadow_rays as f64),
            ("near_field_rays", self.last_shade.near_rays as f64),
            ("interpolated_pixels", self.last_shade.interpolated as f64),
            ("fallback_pixels", self.last_shade.fallbacks as f64),
            ("paused", if self.shared.is_paused() { 1.0 } else { 0.0 }),
            ("topped_up_photons", self.topped_up as f64),
            ("display_lag", self.display_lag()),
        ] {
            c.set(name, x);
        }
        c
    }

    /// True once the streaming thread rests on a settled pool
    /// ([`PhotonStreamSettings::rest_when_settled`]) and the last frame's indirect light
    /// read that pool: until a change that affects lighting, every frame would shade the
    /// same VSL powers. False in deterministic mode (every frame shoots photons).
    fn settled(&self) -> bool {
        self.thread.is_some()
            && self.display_lag() == 0.0
            && self.shared.is_resting()
            && self.pushed_at_indirect == Some(self.shared.lock().pool.photons_pushed())
    }

    /// Photon streaming is the interactive technique (the paper renders with shadow maps).
    fn interactive(&self) -> bool {
        true
    }

    fn reset(&mut self) {
        self.shared.flush();
        self.warmed_up = false;
        self.pushed_at_indirect = None;
        self.impacts_at_advance = None;
        self.topped_up = 0;
        self.shown = None;
        self.frames = 0;
        self.last_shade = ShadeStats::default();
    }
}
