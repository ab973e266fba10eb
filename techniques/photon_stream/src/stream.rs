//! Multi-thread processing (§0.7.2): one long-lived simulation thread shoots photons
//! forever while the frame loop renders.
//!
//! Each batch of [`PhotonStreamSettings::batch_photons`](crate::PhotonStreamSettings)
//! photons is traced in the thread's own snapshot of the world (an `Arc<World>` that the
//! frame loop publishes after each scene change, [`SharedPool::publish_world`]; a clone
//! shares the mesh BVHs and textures), then applied to the pool under the pool mutex —
//! the mutual exclusion of §0.7.2 that keeps every VSL's red, green and blue coherent.
//! The thread never holds the shared world's lock, so a scene update never waits for it:
//! with the thread at the lowest OS priority (the default), waiting for it to release a
//! read lock on a busy machine stalled the frame loop for seconds (priority inversion,
//! found by the soak test under load). The renderer copies all VSL powers under the same mutex
//! ([`SharedPool::snapshot`]): a consistent snapshot of the whole field, never a torn
//! RGB. A flush bumps an epoch so a batch traced before it is discarded, not applied.

use crate::emit::{Emitter, PhotonBatch};
use crate::placement::VslSet;
use crate::pool::PhotonPool;
use crate::settings::StreamPriority;
use illume_transport::World;
use illume_transport::photon::PhotonPathSettings;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

/// The pool and its rate measurements, behind one mutex.
#[derive(Debug)]
pub struct PoolState {
    /// The FIFO pool and VSL power sums.
    pub pool: PhotonPool,
    /// Incremented by every flush; batches traced under an older epoch are dropped.
    pub epoch: u64,
    /// Impacts per second over the last measurement window.
    pub impacts_per_s: f64,
    /// Photons per second over the last measurement window.
    pub photons_per_s: f64,
    /// Rays per second over the last measurement window.
    pub rays_per_s: f64,
    /// Rays traced in total.
    pub rays: u64,
    /// Photons pushed when the last scene change happened (for the stale fraction).
    pub photons_at_change: u64,
    window: Option<(Instant, u64, u64, u64)>,
}

impl PoolState {
    /// Pooled photons traced before the last lighting change (the oldest ones: the pool
    /// is a FIFO).
    pub fn stale_photons(&self) -> u64 {
        let evicted = self.pool.photons_pushed() - self.pool.photons();
        self.photons_at_change.saturating_sub(evicted)
    }

    /// Marks every photon pushed so far as stale (traced before the last lighting change).
    fn mark_stale(&mut self) {
        self.photons_at_change = self.pool.photons_pushed();
    }

    /// Sets the rates from the measurement window open since the last batch that opened
    /// one, and closes it. A window shorter than 10 ms is too noisy to replace a rate,
    /// but gives the first one (a thread that settles within its first window).
    fn close_window(&mut self, now: Instant) {
        if let Some((t0, p0, i0, r0)) = self.window.take() {
            let dt = (now - t0).as_secs_f64();
            if dt > 0.0 && (dt >= 0.01 || self.impacts_per_s == 0.0) {
                self.photons_per_s = (self.pool.photons_pushed() - p0) as f64 / dt;
                self.impacts_per_s = (self.pool.impacts_pushed() - i0) as f64 / dt;
                self.rays_per_s = (self.rays - r0) as f64 / dt;
            }
        }
    }
}

/// A consistent copy of the VSL field.
#[derive(Clone, Debug, PartialEq)]
pub struct PoolSnapshot {
    /// Power accumulators in quanta, index `2·vsl + side`.
    pub quanta: Vec<illume_transport::flux::Quanta>,
    /// K, the photons the powers are summed over.
    pub photons: u64,
    /// Watts per quantum.
    pub quantum_w: f64,
}

/// State shared by the technique and its simulation thread.
#[derive(Debug)]
pub struct SharedPool {
    state: Mutex<PoolState>,
    paused: Mutex<bool>,
    wake: Condvar,
    stop: AtomicBool,
    /// The world the thread traces in, replaced by [`SharedPool::publish_world`].
    world: Mutex<Arc<World>>,
    /// Counts published worlds: a batch during which a new one arrives ends after the
    /// current photon.
    world_generation: AtomicU64,
    next_seq: AtomicU64,
    start: Instant,
    /// False while the thread rests with a settled pool ([`SharedPool::settled`]); set
    /// under the pool lock, with the settling test or with the change that unsettles it.
    wanted: AtomicBool,
    /// True while the thread blocks in [`SharedPool::wait_running`] (paused or resting):
    /// no batch is in flight.
    waiting: AtomicBool,
}

impl SharedPool {
    /// A shared pool around `pool`; the thread traces in `world` until another is
    /// published.
    pub fn new(pool: PhotonPool, paused: bool, world: Arc<World>) -> Self {
        Self {
            state: Mutex::new(PoolState {
                pool,
                epoch: 0,
                impacts_per_s: 0.0,
                photons_per_s: 0.0,
                rays_per_s: 0.0,
                rays: 0,
                photons_at_change: 0,
                window: None,
            }),
            paused: Mutex::new(paused),
            wake: Condvar::new(),
            stop: AtomicBool::new(false),
            world: Mutex::new(world),
            world_generation: AtomicU64::new(0),
            next_seq: AtomicU64::new(0),
            waiting: AtomicBool::new(false),
            start: Instant::now(),
            wanted: AtomicBool::new(true),
        }
    }

    /// Locks the pool state (a poisoned lock is recovered: the pool's invariants hold
    /// after every completed operation).
    pub fn lock(&self) -> MutexGuard<'_, PoolState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Seconds since construction (the clock of pool stamps).
    pub fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// Reserves `count` photon indices.
    pub fn reserve(&self, count: u64) -> u64 {
        self.next_seq.fetch_add(count, Ordering::Relaxed)
    }

    /// Applies a traced batch unless a flush happened since `epoch`. Returns whether it
    /// was applied.
    pub fn apply(&self, batch: &PhotonBatch, epoch: u64) -> bool {
        self.apply_then(batch, epoch, || true, |_| {})
    }

    /// [`SharedPool::apply`] when `current()` also holds under the pool's lock, then
    /// `after` on the pool state under the same lock (the streaming thread's rest
    /// bookkeeping: one lock per batch).
    fn apply_then(
        &self,
        batch: &PhotonBatch,
        epoch: u64,
        current: impl FnOnce() -> bool,
        after: impl FnOnce(&mut PoolState),
    ) -> bool {
        let now = Instant::now();
        let t = self.now_s();
        let mut s = self.lock();
        if s.epoch == epoch && current() {
            s.pool.stamp(t);
            for path in batch.paths() {
                s.pool.push_photon(path);
            }
            s.rays += batch.rays;
            let (photons, impacts, rays) =
                (s.pool.photons_pushed(), s.pool.impacts_pushed(), s.rays);
            match s.window {
                None => s.window = Some((now, photons, impacts, rays)),
                Some((t0, ..)) => {
                    if (now - t0).as_secs_f64() >= 0.25 {
                        s.close_window(now);
                        s.window = Some((now, photons, impacts, rays));
                    }
                }
            }
        }
        after(&mut s);
        s.epoch == epoch
    }

    /// Copies every VSL power and K under the mutex.
    pub fn snapshot(&self) -> PoolSnapshot {
        let s = self.lock();
        PoolSnapshot {
            quanta: s.pool.power_quanta().to_vec(),
            photons: s.pool.photons(),
            quantum_w: s.pool.quantum_w(),
        }
    }

    /// Empties the pool and invalidates batches in flight.
    pub fn flush(&self) {
        {
            let mut s = self.lock();
            s.epoch += 1;
            s.pool.flush();
            s.window = None;
            // An emptied pool is not settled: without this, its photons pushed before
            // counted as turned over, and a resting thread stayed at rest on it.
            s.mark_stale();
            self.wanted.store(true, Ordering::Release);
        }
        let _paused = self.paused.lock().unwrap_or_else(|e| e.into_inner());
        self.wake.notify_all();
    }

    /// The current epoch.
    pub fn epoch(&self) -> u64 {
        self.lock().epoch
    }

    /// Pauses or resumes the simulation thread.
    pub fn set_paused(&self, paused: bool) {
        *self.paused.lock().unwrap_or_else(|e| e.into_inner()) = paused;
        if !paused {
            self.lock().window = None;
        }
        self.wake.notify_all();
    }

    /// True while paused.
    pub fn is_paused(&self) -> bool {
        *self.paused.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Gives the thread `world` (the world after a scene change) for its next batches;
    /// the batch in flight ends after its current photon. Call before a flush, so that a
    /// batch that reads the flushed epoch also reads this world.
    pub fn publish_world(&self, world: Arc<World>) {
        *self.world.lock().unwrap_or_else(|e| e.into_inner()) = world;
        self.world_generation.fetch_add(1, Ordering::AcqRel);
    }

    /// The world the thread traces in now.
    pub fn world(&self) -> Arc<World> {
        Arc::clone(&self.world.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// Records a change that affects lighting: photons pushed until now are stale, and a
    /// resting thread is woken to replace them.
    pub fn lighting_changed(&self) {
        {
            // One lock for both: the thread decides to rest under it too.
            let mut s = self.lock();
            s.mark_stale();
            self.wanted.store(true, Ordering::Release);
        }
        // Under the mutex the thread waits with, so the wake cannot fall between its test
        // and its wait.
        let _paused = self.paused.lock().unwrap_or_else(|e| e.into_inner());
        self.wake.notify_all();
    }

    /// True when every photon in the pool was traced after the last change that affects
    /// lighting and the pool is full: it has evicted a photon traced since that change
    /// (so a flushed or new pool is never settled).
    pub fn settled(s: &PoolState) -> bool {
        s.pool.photons_pushed() - s.pool.photons() > s.photons_at_change
    }

    /// True while the thread rests on a settled pool.
    pub fn is_resting(&self) -> bool {
        !self.wanted.load(Ordering::Acquire)
    }

    /// Rests the thread if the pool `s` (locked) is settled: later `wait_running` calls
    /// block until [`SharedPool::lighting_changed`] (or a stop).
    fn rest_if_settled(&self, s: &mut PoolState) {
        if Self::settled(s) {
            // The rate while streaming, for `latency_s` while the thread rests.
            s.close_window(Instant::now());
            self.wanted.store(false, Ordering::Release);
        }
    }

    /// Asks the simulation thread to end.
    pub fn request_stop(&self) {
        self.stop.store(true, Ordering::Release);
        self.wake.notify_all();
    }

    /// Blocks while paused or resting; returns false when asked to stop.
    fn wait_running(&self) -> bool {
        let mut paused = self.paused.lock().unwrap_or_else(|e| e.into_inner());
        while (*paused || !self.wanted.load(Ordering::Acquire))
            && !self.stop.load(Ordering::Acquire)
        {
            self.waiting.store(true, Ordering::Release);
            paused = self.wake.wait(paused).unwrap_or_else(|e| e.into_inner());
        }
        self.waiting.store(false, Ordering::Release);
        !self.stop.load(Ordering::Acquire)
    }

    /// True while the simulation thread blocks, paused or resting: no batch is in flight,
    /// so the pool changes no more until it is woken.
    pub fn is_thread_waiting(&self) -> bool {
        self.waiting.load(Ordering::Acquire)
    }
}

/// What the simulation thread needs.
pub struct StreamConfig {
    /// Photons per batch (one pool update).
    pub batch_photons: u64,
    /// OS priority of the thread.
    pub priority: StreamPriority,
    /// Photon path settings.
    pub path: PhotonPathSettings,
    /// Seed.
    pub seed: u64,
    /// The first impact that deposits
    /// ([`PhotonStreamSettings::first_deposit`](crate::PhotonStreamSettings::first_deposit)).
    pub first_deposit: u32,
    /// 1 / (watts per quantum).
    pub inv_quantum: f64,
    /// With [`StreamPriority::Low`]: the share of one core the thread may take from
    /// render threads that want it ([`PhotonStreamSettings::stream_share`]).
    ///
    /// [`PhotonStreamSettings::stream_share`]: crate::PhotonStreamSettings::stream_share
    pub share: f32,
    /// Rest once the pool is settled ([`PhotonStreamSettings::rest_when_settled`]).
    ///
    /// [`PhotonStreamSettings::rest_when_settled`]: crate::PhotonStreamSettings::rest_when_settled
    pub rest_when_settled: bool,
}

/// Starts the simulation thread; it runs until [`SharedPool::request_stop`].
pub fn spawn(
    vsls: Arc<VslSet>,
    shared: Arc<SharedPool>,
    config: StreamConfig,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("photon_stream".into())
        .spawn(move || {
            if config.priority == StreamPriority::Low {
                lower_own_priority();
            }
            // A share of 1 is no limit: no checks at all.
            let mut governor = (config.priority == StreamPriority::Low && config.share < 1.0)
                .then(|| ShareGovernor::new(config.share));
            while shared.wait_running() {
                // The epoch before the world: a flush publishes its world first, so a
                // batch that reads the new epoch traces in the new world.
                let epoch = shared.epoch();
                let generation = shared.world_generation.load(Ordering::Acquire);
                let w = shared.world();
                let emitter = Emitter::new(&w, &vsls, config.inv_quantum, config.path, config.seed)
                    .with_first_deposit(config.first_deposit);
                let first = shared.reserve(config.batch_photons);
                let mut traced = 0u32;
                let wanted = || {
                    traced = traced.wrapping_add(1);
                    if traced.is_multiple_of(ShareGovernor::EVERY_PHOTONS)
                        && let Some(g) = governor.as_mut()
                    {
                        g.check();
                    }
                    shared.world_generation.load(Ordering::Acquire) != generation
                };
                let batch = emitter.trace_until(&w, first, config.batch_photons, wanted);
                drop(w);
                // Photon indices reserved but not traced are simply skipped. A batch cut
                // short by a lighting change was traced in the world before it: it is
                // dropped, checked under the pool's lock (a change records its stale
                // photons under that lock, after publishing its world). It used to be
                // pooled and everything pooled so far marked stale, which also marked the
                // frame loop's top-ups traced after the change: under load such a late
                // batch undid them (`turnover_frames` missed, 0.13–0.79 of the pool
                // still stale after 5 frames).
                shared.apply_then(
                    &batch,
                    epoch,
                    || shared.world_generation.load(Ordering::Acquire) == generation,
                    |s| {
                        if config.rest_when_settled {
                            shared.rest_if_settled(s);
                        }
                    },
                );
            }
        })
}

/// Puts the calling thread at the lowest nice level (19 on Linux). Lowering one's own
/// priority needs no privilege on Linux; where it is refused, streaming at normal
/// priority is still correct, and the refusal is said once on stderr.
///
/// Not `SCHED_IDLE`: tried (issue 15), it made frames rendered back to back 1.06–1.21×
/// faster but starved the thread there, and `illume bench scenarios/moving_light.toml`
/// (balanced preset) went from FLIP 0.069–0.075, settled within 5 frames, to 0.14–0.15,
/// never settled (BENCHMARKS.md, photon_stream).
fn lower_own_priority() {
    if let Err(e) =
        thread_priority::set_current_thread_priority(thread_priority::ThreadPriority::Min)
    {
        log::warn!("photon_stream: cannot lower the streaming thread's priority: {e:?}");
    }
}

/// Keeps a low-priority streaming thread to about its share of a core while render
/// threads want the cores, and lets it have all of a core nobody wants.
///
/// Why it is wanted: at nice 19 the thread still took ≈ 45 % of a core from frames
/// rendered back to back, and frames ran 1.3–1.5× slower than with it paused. Rayon's
/// workers, out of work for a moment, spin and call `sched_yield`; the scheduler then
/// runs the streaming thread, and the worker, runnable rather than waking, gets its core
/// back only at the next scheduler tick, its next job long waiting. Measured in
/// BENCHMARKS.md, photon_stream, "the streaming thread beside the frame".
///
/// How: every [`Self::EVERY_PHOTONS`] photons the thread checks the wall clock; every
/// [`Self::READ_EVERY_S`] it reads its CPU clock and updates the share of a core it had,
/// averaged over ≈ [`Self::AVERAGE_S`]. At or above `share` it yields at every check,
/// which hands the core back to a waiting render thread within microseconds (with
/// nothing waiting, the yield returns at once: an idle machine still streams at full
/// rate); below, it keeps the core while it has it. The CPU clock is read rarely: read
/// at every check (a system call every few microseconds) it cost the frames most of
/// what the yields win.
struct ShareGovernor {
    /// The share of a core kept while render threads want the cores.
    share: f64,
    /// The thread's share of a core, averaged over ≈ [`Self::AVERAGE_S`].
    average: f64,
    /// When the CPU clock was last read, and what it said [s].
    wall: std::time::Instant,
    cpu_s: f64,
    /// Yielding at every check (the average is at or above the share).
    yielding: bool,
}

impl ShareGovernor {
    /// Photons between checks: 5–30 µs of tracing.
    const EVERY_PHOTONS: u32 = 8;
    /// Wall time between readings of the thread's CPU clock [s].
    const READ_EVERY_S: f64 = 0.001;
    /// Time constant of the average share [s].
    const AVERAGE_S: f64 = 0.05;

    fn new(share: f32) -> Self {
        Self {
            share: f64::from(share),
            average: 0.0,
            wall: std::time::Instant::now(),
            cpu_s: thread_cpu_s(),
            yielding: false,
        }
    }

    /// Updates the average now and then; yields the core while at or above the share.
    fn check(&mut self) {
        let now = std::time::Instant::now();
        let dt = (now - self.wall).as_secs_f64();
        if dt >= Self::READ_EVERY_S {
            let cpu_s = thread_cpu_s();
            self.book(dt, cpu_s - self.cpu_s);
            (self.wall, self.cpu_s) = (now, cpu_s);
        }
        if self.yielding {
            std::thread::yield_now();
        }
    }

    /// Books `ran_s` seconds of CPU in the last `dt_s` seconds of wall time.
    fn book(&mut self, dt_s: f64, ran_s: f64) {
        let a = (dt_s / Self::AVERAGE_S).min(1.0);
        self.average += a * (ran_s / dt_s - self.average);
        self.yielding = self.average >= self.share;
    }
}

/// CPU time of the calling thread [s].
fn thread_cpu_s() -> f64 {
    illume_core::cpu_time::thread_cpu_ns() * 1e-9
}

#[cfg(test)]
mod tests {
    use super::ShareGovernor;

    /// The fraction of 1 ms steps in which a thread that runs whenever it does not
    /// yield (and is off the core when it yields) is let run, over 10 s.
    fn running_fraction(share: f32) -> f64 {
        let mut g = ShareGovernor::new(share);
        let steps = 10_000;
        let ran = (0..steps)
            .filter(|_| {
                let runs = !g.yielding;
                g.book(1e-3, if runs { 1e-3 } else { 0.0 });
                runs
            })
            .count();
        ran as f64 / steps as f64
    }

    #[test]
    fn a_thread_held_to_its_share_runs_that_share_of_the_time() {
        for share in [0.1f32, 0.25, 0.5, 0.9] {
            let f = running_fraction(share);
            assert!(
                (f - f64::from(share)).abs() < 0.02,
                "share {share}: ran {f:.3} of the time"
            );
        }
        // Share 0 yields from the first reading on. A thread that runs all the time
        // (alone on an idle core, where its yields return at once) averages a whole
        // core and yields at every check.
        assert!(running_fraction(0.0) < 0.001);
        let mut g = ShareGovernor::new(0.25);
        for _ in 0..1000 {
            g.book(1e-3, 1e-3);
        }
        assert!(g.yielding && (g.average - 1.0).abs() < 1e-6);
    }
}
