//! The paper's parallel thread (§6: the software part computing indirect light and the
//! display "run in parallel using multi-threading, and are synchronized by the
//! important events"): [`Streaming`] runs the [`Selective`] solution on one long-lived
//! thread while the frame loop renders.
//!
//! The thread repeats [`Selective::step`] — the most important stale group, else the
//! next chunk of the index-order fill — each under a read lock of the shared world and
//! the solution's mutex, so a group's negative and positive deposits are applied
//! together and a frame never sees half a group. The frame loop takes the same mutex for
//! scene changes and to copy the display values (shading runs outside it), so it waits
//! for at most the group in flight. A frame that is waiting for the mutex holds the
//! thread back from starting its next step (std's mutex is not fair). Likewise the frame
//! loop announces a world write ([`Technique::before_world_write`]) and the thread takes
//! no new read lock until the frame's [`Technique::scene_changed`] or
//! [`Technique::advance`] (or [`WORLD_WAIT`] at most): std's `RwLock` clears its
//! writer-waiting flag when it wakes the writer, so a reader that comes back at once gets
//! in first, and the writer waited for ~70 steps (100 ms) before this. A scene update
//! waits for one step at most. With nothing stale and the pool full the thread sleeps
//! until the next scene change.
//!
//! A step traces its group's photons in parallel on the thread's own rayon pool
//! (`stream_threads`, default 1), not on the global pool: the renderer's frames keep the
//! global pool busy, and work a foreign thread queues there waits until a frame's
//! parallel section has drained (issue 34, goal 6).

use crate::elements::Elements;
use crate::selection::Work;
use crate::state::Selective;
use crate::{SelectiveError, SelectiveSettings, shade};
use illume_core::image::RgbImage;
use illume_core::{Counters, Progress};
use illume_scene::SceneChange;
use illume_transport::{Budget, ChangeResponse, GBuffer, SharedWorld, Technique, World};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long the idle thread sleeps before looking for work again when no scene change
/// wakes it (a change always wakes it at once).
const IDLE_WAIT: Duration = Duration::from_millis(50);

/// Longest the thread stays off the world after the frame loop announced a write and
/// did not say it is done (an announcement no write followed).
pub const WORLD_WAIT: Duration = Duration::from_millis(50);

/// What the technique and its thread share.
struct Shared {
    solution: Mutex<Selective>,
    /// Frame-loop calls waiting for the mutex: the thread starts no step meanwhile.
    frame_waiting: AtomicU32,
    stop: AtomicBool,
    /// Steps the thread has taken (groups and fill chunks).
    steps: AtomicU64,
    /// When the frame loop announced a world write, in µs since `start` (+1; 0: none
    /// pending).
    world_wanted_us: AtomicU64,
    start: Instant,
}

impl Shared {
    /// Locks the solution for the thread (a poisoned lock is recovered: a group's
    /// deposits are applied in one loop that does not panic, so the accumulators hold a
    /// whole number of groups).
    fn lock(&self) -> MutexGuard<'_, Selective> {
        self.solution.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64 + 1
    }

    /// True while a world write the frame loop announced is pending (for [`WORLD_WAIT`]
    /// at most).
    fn world_wanted(&self) -> bool {
        let at = self.world_wanted_us.load(Ordering::Acquire);
        at != 0 && self.now_us().saturating_sub(at) < WORLD_WAIT.as_micros() as u64
    }

    /// Locks the solution for the frame loop, ahead of the thread's next step.
    fn lock_for_frame(&self) -> MutexGuard<'_, Selective> {
        self.frame_waiting.fetch_add(1, Ordering::AcqRel);
        let guard = self.lock();
        self.frame_waiting.fetch_sub(1, Ordering::AcqRel);
        guard
    }
}

/// Selective photon tracing with its solution on a background thread
/// ([`SelectiveMode::Streaming`](crate::SelectiveMode::Streaming)).
pub struct Streaming {
    shared: Arc<Shared>,
    elements: Arc<Elements>,
    thread: Option<JoinHandle<()>>,
    last_shade_ms: f64,
    /// How long the last [`Technique::indirect`] waited for the solution's lock (the
    /// thread finishing its step) \[ms\].
    last_lock_wait_ms: f64,
    /// The thread's steps when the last [`Technique::indirect`] copied the display values.
    steps_at_indirect: Option<u64>,
}

impl Streaming {
    /// Lays out the solution for `world`'s scene (as [`Selective::new`]) and starts its
    /// thread. With `warm_up` the pool is filled by [`Technique::precompute`] or the first
    /// [`Technique::advance`]; without it the thread fills it in index order.
    pub fn new(world: &SharedWorld, settings: SelectiveSettings) -> Result<Self, SelectiveError> {
        let threads = settings.stream_threads();
        let solution = Selective::new(world, settings)?;
        let elements = solution.shared_elements();
        let shared = Arc::new(Shared {
            solution: Mutex::new(solution),
            frame_waiting: AtomicU32::new(0),
            stop: AtomicBool::new(false),
            steps: AtomicU64::new(0),
            world_wanted_us: AtomicU64::new(0),
            start: Instant::now(),
        });
        let thread = spawn(Arc::clone(world), Arc::clone(&shared), threads)
            .map_err(SelectiveError::Thread)?;
        Ok(Self {
            shared,
            elements,
            thread: Some(thread),
            last_shade_ms: 0.0,
            last_lock_wait_ms: 0.0,
            steps_at_indirect: None,
        })
    }

    /// Runs `f` on the solution under its lock (tests and tools: counters, stale groups,
    /// accumulators as the thread left them).
    pub fn with_solution<T>(&self, f: impl FnOnce(&mut Selective) -> T) -> T {
        f(&mut self.shared.lock_for_frame())
    }

    /// Steps the thread has taken since it started (groups re-traced and fill chunks).
    pub fn thread_steps(&self) -> u64 {
        self.shared.steps.load(Ordering::Acquire)
    }

    /// The frame loop is done writing the world: the thread may read it again.
    fn world_written(&self) {
        self.shared.world_wanted_us.store(0, Ordering::Release);
        self.wake();
    }

    fn wake(&self) {
        if let Some(t) = &self.thread {
            t.thread().unpark();
        }
    }
}

/// The thread's loop: one step at a time until asked to stop.
fn spawn(world: SharedWorld, shared: Arc<Shared>, threads: u32) -> std::io::Result<JoinHandle<()>> {
    let pool = (threads > 0)
        .then(|| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads as usize)
                .thread_name(|i| format!("selective-{i}"))
                .build()
                .ok()
        })
        .flatten();
    std::thread::Builder::new()
        .name("selective".into())
        .spawn(move || {
            while !shared.stop.load(Ordering::Acquire) {
                if shared.frame_waiting.load(Ordering::Acquire) > 0 {
                    std::thread::yield_now();
                    continue;
                }
                if shared.world_wanted() {
                    std::thread::park_timeout(Duration::from_millis(1));
                    continue;
                }
                let worked = {
                    let w = world.read().unwrap_or_else(|e| e.into_inner());
                    let w: &World = &w;
                    // On the thread's own pool when it has one: the renderer's frames keep
                    // the global pool busy, and work queued there waits for them.
                    let run = |f: &mut (dyn FnMut() + Send)| match &pool {
                        Some(pool) => pool.install(f),
                        None => f(),
                    };
                    // Steps are counted under the lock: whoever sees a step's effect sees
                    // it counted.
                    let counted = |done: bool| {
                        if done {
                            shared.steps.fetch_add(1, Ordering::AcqRel);
                        }
                        done
                    };
                    // A stale group is traced outside the solution's lock, so that a frame
                    // copying the display values does not wait for a whole re-trace
                    // (crate::selection::RetraceJob); other work is done under it.
                    let mut work = None;
                    run(&mut || {
                        let mut guard = shared.lock();
                        work = Some(match guard.take_work(w) {
                            Work::Stepped(done) => Err(counted(done.is_some())),
                            Work::Retrace(job) => Ok(job),
                        });
                    });
                    match work.expect("set above") {
                        Err(worked) => worked,
                        Ok(job) => {
                            let mut out = None;
                            run(&mut || out = Some(job.trace()));
                            let out = out.expect("set above");
                            let mut guard = shared.lock();
                            guard.finish_retrace(*job, out);
                            counted(true)
                        }
                    }
                };
                if !worked {
                    std::thread::park_timeout(IDLE_WAIT);
                }
            }
        })
}

impl Drop for Streaming {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Release);
        self.wake();
        if let Some(t) = self.thread.take() {
            // A panicked thread has nothing left to clean up.
            let _ = t.join();
        }
    }
}

impl Technique for Streaming {
    fn name(&self) -> &'static str {
        crate::NAME
    }

    fn precompute(
        &mut self,
        world: &World,
        progress: &mut dyn Progress,
    ) -> Result<(), illume_transport::TechniqueError> {
        self.shared.lock_for_frame().precompute(world, progress)
    }

    fn scene_changed(&mut self, world: &World, changes: &[SceneChange]) -> ChangeResponse {
        let response = self.shared.lock_for_frame().scene_changed(world, changes);
        self.world_written();
        response
    }

    /// With `warm_up`, the first call fills the pool (unless precompute did). The
    /// thread does the rest; `budget` is ignored.
    fn advance(&mut self, world: &World, _budget: &Budget) {
        self.world_written();
        self.shared
            .lock_for_frame()
            .warm_up(world, &mut illume_core::progress::Silent);
    }

    /// The thread takes no new read lock of the world until the write is done (see the
    /// module doc).
    fn before_world_write(&self) {
        let now = self.shared.now_us();
        self.shared.world_wanted_us.store(now, Ordering::Release);
    }

    /// The display values are copied under the solution's lock; shading runs outside it.
    fn indirect(&mut self, world: &World, gbuffer: &GBuffer) -> RgbImage {
        let t0 = Instant::now();
        let (display, directional) = {
            let mut solution = self.shared.lock_for_frame();
            self.last_lock_wait_ms = t0.elapsed().as_secs_f64() * 1e3;
            solution.set_aspect(gbuffer.width, gbuffer.height);
            // Steps are counted under this lock: the count matches the values copied.
            self.steps_at_indirect = Some(self.shared.steps.load(Ordering::Acquire));
            (
                solution.frame_display(world),
                solution.settings.directional_albedo,
            )
        };
        let img = shade::shade(world, gbuffer, &self.elements, &display, directional);
        self.last_shade_ms = t0.elapsed().as_secs_f64() * 1e3;
        img
    }

    fn stats(&self) -> Counters {
        let mut c = self.shared.lock_for_frame().stats();
        c.set("shading_ms", self.last_shade_ms);
        c.set("lock_wait_ms", self.last_lock_wait_ms);
        c.set("thread_steps", self.thread_steps() as f64);
        c
    }

    /// True once the thread has nothing left to do (nothing stale, the pool full and
    /// grown to `max_photons`) and the last frame copied its final values. A scene change
    /// makes groups stale under the same lock, so it is never settled with a change
    /// waiting for the thread.
    fn settled(&self) -> bool {
        let solution = self.shared.lock_for_frame();
        !solution.has_work()
            && self.steps_at_indirect == Some(self.shared.steps.load(Ordering::Acquire))
    }

    fn reset(&mut self) {
        self.shared.lock_for_frame().reset();
        self.wake();
    }

    /// Direct light with shadows is the renderer's (the paper's hardware pass, §6.1).
    fn interactive(&self) -> bool {
        true
    }
}

/// Builds the technique the settings ask for: [`Streaming`] (a background thread) in
/// [`SelectiveMode::Streaming`](crate::SelectiveMode::Streaming), else [`Selective`]
/// working on the frame thread.
pub fn build(
    world: &SharedWorld,
    settings: SelectiveSettings,
) -> Result<Box<dyn Technique>, SelectiveError> {
    Ok(match settings.mode {
        crate::SelectiveMode::Streaming => Box::new(Streaming::new(world, settings)?),
        crate::SelectiveMode::Timed | crate::SelectiveMode::Deterministic => {
            Box::new(Selective::new(world, settings)?)
        }
    })
}
