//! Progress of long work (a precompute phase, converged references): the worker reports,
//! the caller shows (the CLI draws bars with an ETA; tests stay [`Silent`]).

/// Receives progress reports of long work. Calls come from one thread, in the order
/// `begin`, any number of `set`/`message`, `end`; a worker may run several such phases.
pub trait Progress {
    /// Work of `total` units called `what` starts.
    fn begin(&mut self, what: &str, total: u64);
    /// `done` of the units are finished (monotonic within a phase).
    fn set(&mut self, done: u64);
    /// The phase is over.
    fn end(&mut self);
    /// A line of information (cache use, warnings).
    fn message(&mut self, text: &str);
}

/// Shows no progress.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn begin(&mut self, _what: &str, _total: u64) {}
    fn set(&mut self, _done: u64) {}
    fn end(&mut self) {}
    fn message(&mut self, _text: &str) {}
}
