//! Progress bars for work longer than a second. When stderr is not a terminal (a batch
//! job's log, a pipe) the bars are hidden and [`Bars`] writes a plain line per phase
//! instead: at its start, every 10 s with the count, rate and ETA, and at its end.

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A bar over `len` units of `what`.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {per_sec} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb.enable_steady_tick(Duration::from_millis(200));
    pb
}

/// A spinner with the elapsed time, for one long step whose progress is not known.
pub fn spinner(what: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_message(what.to_string());
    pb.enable_steady_tick(Duration::from_millis(200));
    pb
}

/// indicatif bars for progress reports of long work (a technique's precompute, the
/// bench's converged references): one bar per phase, with rate and ETA; between phases,
/// an optional spinner with the elapsed time (work whose progress is not known).
#[derive(Default)]
pub struct Bars {
    bar: Option<ProgressBar>,
    idle: Option<String>,
    /// Plain log lines (stderr is not a terminal): the phase, its total, its start and
    /// the last line's time.
    log: Option<LogPhase>,
}

/// A phase reported by plain lines.
struct LogPhase {
    what: String,
    total: u64,
    start: std::time::Instant,
    last: std::time::Instant,
}

/// Whether progress goes to plain lines rather than bars.
fn plain() -> bool {
    use std::io::IsTerminal;
    !std::io::stderr().is_terminal()
}

impl Bars {
    /// Bars that show a spinner labelled `what` while no phase runs.
    pub fn with_spinner(what: &str) -> Self {
        Self {
            bar: Some(spinner(what)),
            idle: Some(what.to_owned()),
            log: None,
        }
    }

    /// Clears whatever is shown.
    pub fn finish(&mut self) {
        self.idle = None;
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}

impl illume_core::Progress for Bars {
    fn begin(&mut self, what: &str, total: u64) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        self.bar = Some(bar(total, what));
        if plain() {
            // A phase that grows (the adaptive schedule re-begins with a larger total)
            // keeps its start time.
            let now = std::time::Instant::now();
            match &mut self.log {
                Some(p) if p.what == what => p.total = total,
                _ => {
                    eprintln!("{what}: started, {total} to do");
                    self.log = Some(LogPhase {
                        what: what.to_owned(),
                        total,
                        start: now,
                        last: now,
                    });
                }
            }
        }
    }

    fn set(&mut self, done: u64) {
        if let Some(b) = &self.bar {
            b.set_position(done);
        }
        if let Some(p) = &mut self.log
            && p.last.elapsed().as_secs_f64() >= 10.0
        {
            p.last = std::time::Instant::now();
            let elapsed = p.start.elapsed().as_secs_f64();
            let eta = if done > 0 {
                format!(
                    ", eta {:.0} s",
                    elapsed / done as f64 * p.total.saturating_sub(done) as f64
                )
            } else {
                String::new()
            };
            eprintln!("{}: {done}/{} after {elapsed:.0} s{eta}", p.what, p.total);
        }
    }

    fn end(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        if let Some(p) = self.log.take() {
            eprintln!(
                "{}: done in {:.1} s",
                p.what,
                p.start.elapsed().as_secs_f64()
            );
        }
        self.bar = self.idle.as_deref().map(spinner);
    }

    fn message(&mut self, text: &str) {
        match &self.bar {
            Some(b) => b.println(text),
            None => eprintln!("{text}"),
        }
    }
}

/// Installs the logger through which the libraries' warnings (`log::warn!`: a stale
/// precomputed file, a thread that kept its priority, …) and the window's messages
/// (`log::info!`) reach the user on stderr: `warning: …` and `error: …` prefixed, info
/// as it is; debug and trace are dropped. Called once, first thing in `main`.
pub fn install_logger() {
    /// Writes records at info and above to stderr.
    struct Stderr;
    impl log::Log for Stderr {
        fn enabled(&self, metadata: &log::Metadata) -> bool {
            metadata.level() <= log::Level::Info
        }
        fn log(&self, record: &log::Record) {
            if !self.enabled(record.metadata()) {
                return;
            }
            match record.level() {
                log::Level::Error => eprintln!("error: {}", record.args()),
                log::Level::Warn => eprintln!("warning: {}", record.args()),
                _ => eprintln!("{}", record.args()),
            }
        }
        fn flush(&self) {}
    }
    static LOGGER: Stderr = Stderr;
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(log::LevelFilter::Info);
    }
}
