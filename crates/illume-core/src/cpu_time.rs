//! CPU time of the calling thread: what a piece of work cost, whatever share of the
//! cores other threads and processes took meanwhile (wall-clock time grows with them).

/// CPU time consumed so far by the calling thread \[ns\] (Unix:
/// `CLOCK_THREAD_CPUTIME_ID`; 0 if the clock is refused).
#[cfg(unix)]
pub fn thread_cpu_ns() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    #[expect(
        unsafe_code,
        reason = "clock_gettime through libc, no safe std equivalent"
    )]
    // SAFETY: `t` is a valid, writable timespec; CLOCK_THREAD_CPUTIME_ID exists on every
    // unix this builds for; the call has no other precondition.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    if status != 0 {
        return 0.0;
    }
    t.tv_sec as f64 * 1e9 + t.tv_nsec as f64
}

/// Elsewhere: wall-clock time since the first call, as if the thread were always busy.
#[cfg(not(unix))]
pub fn thread_cpu_ns() -> f64 {
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs_f64()
        * 1e9
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_cpu_time_grows_with_work_and_not_with_sleep() {
        // Spin until the clock has counted 30 ms (at most 10 s of wall time): on a loaded
        // machine 30 ms of wall time can hold far less CPU time, so the wall clock does
        // not bound the work; CPU time can never exceed the wall time it took.
        let t0 = thread_cpu_ns();
        let mut x = 0u64;
        let start = std::time::Instant::now();
        while thread_cpu_ns() - t0 < 30e6 && start.elapsed().as_secs() < 10 {
            for _ in 0..1000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
        }
        let wall_ns = start.elapsed().as_nanos() as f64;
        let t1 = thread_cpu_ns();
        std::thread::sleep(std::time::Duration::from_millis(50));
        let t2 = thread_cpu_ns();
        assert!(t1 - t0 >= 30e6, "10 s of spinning counted {} ns", t1 - t0);
        assert!(
            t1 - t0 <= wall_ns + 1e6,
            "{} ns of CPU in {wall_ns} ns of wall time",
            t1 - t0
        );
        #[cfg(unix)]
        assert!(t2 - t1 < 10e6, "50 ms of sleep counted {} ns", t2 - t1);
        let _ = t2;
    }
}
