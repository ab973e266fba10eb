//! Progress bars for work longer than a second (hidden when stderr is not a terminal).

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
}

impl Bars {
    /// Bars that show a spinner labelled `what` while no phase runs.
    pub fn with_spinner(what: &str) -> Self {
        Self {
            bar: Some(spinner(what)),
            idle: Some(what.to_owned()),
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
    }

    fn set(&mut self, done: u64) {
        if let Some(b) = &self.bar {
            b.set_position(done);
        }
    }

    fn end(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
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
