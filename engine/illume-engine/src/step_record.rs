//! One frame's record — where it sits in the run, what each stage cost, the technique's
//! counters — taken from a [`StepOutput`], and `frames.csv`, the table of those records.
//!
//! Three writers share it: `illume animate` (`frames.csv`, and `frames_K_of_N.csv` per
//! shard), the window's clips (K) and `illume bench`. The first two write every column of
//! [`FRAMES_CSV_COLUMNS`]; bench's `results.csv` is its own table (series, metrics,
//! flicker) and carries of these only the engine's times, as the counters
//! [`StepRecord::set_engine_counters`] names.
//!
//! ```
//! use illume_engine::{Config, Engine, FramesCsv, StepRecord, TechniqueKind};
//! let scene = illume_scene::builtin::load("cornell-spot").unwrap();
//! let mut config = Config::default();
//! config.technique = TechniqueKind::Reference;
//! (config.render.width, config.render.height) = (8, 6);
//! let mut engine = Engine::new(scene, &config).unwrap();
//! let mut csv = FramesCsv::default();
//! let out = engine.step(0.0).unwrap();
//! csv.push(&StepRecord { frame: 0, wall_s: 0.1, ..StepRecord::from_step(0.0, &out, 0.0) });
//! let text = csv.text();
//! assert!(text.starts_with("frame,time_s,wall_s,precompute_ms,update_ms,"));
//! assert!(text.lines().nth(1).unwrap().starts_with("0,0.000000,0.100000,"));
//! ```

use crate::StepOutput;
use illume_core::Counters;

/// The fixed columns of `frames.csv`, in order; the technique's counters follow them.
/// Scripts (`scripts/plot_soak.py`) and tests read them by name: append, never reorder.
pub const FRAMES_CSV_COLUMNS: [&str; 10] = [
    "frame",
    "time_s",
    "wall_s",
    "precompute_ms",
    "update_ms",
    "advance_ms",
    "gbuffer_ms",
    "direct_ms",
    "indirect_ms",
    "render_ms",
];

/// One frame of a run: a row of `frames.csv`.
#[derive(Clone, Debug, Default)]
pub struct StepRecord {
    /// The frame's index in the run (its `frame_NNNNN` file).
    pub frame: u64,
    /// Scene time \[s\].
    pub time_s: f64,
    /// Wall-clock time since the run started, when the frame was done \[s\].
    pub wall_s: f64,
    /// Precompute charged to this frame \[ms\]: a rebuild its changes caused, and on a
    /// run's first frame the phase before it ([`crate::Engine::precompute`]).
    pub precompute_ms: f64,
    /// Updating the world and the technique \[ms\] ([`StepOutput::update_ms`]).
    pub update_ms: f64,
    /// The technique's `advance` \[ms\].
    pub advance_ms: f64,
    /// The renderer's G-buffer pass \[ms\].
    pub gbuffer_ms: f64,
    /// The renderer's direct light \[ms\].
    pub direct_ms: f64,
    /// The technique's indirect light \[ms\].
    pub indirect_ms: f64,
    /// The whole render, the three passes above included \[ms\].
    pub render_ms: f64,
    /// The step's counters, filed by technique ([`StepOutput::stats`]).
    pub counters: Counters,
}

impl StepRecord {
    /// The record of `out`, a step at scene time `time_s`, charged with
    /// `earlier_precompute_ms` of precompute done before it (the phase before a run's
    /// first frame; 0 for the others). `frame` and `wall_s` are the caller's to set.
    pub fn from_step(time_s: f64, out: &StepOutput, earlier_precompute_ms: f64) -> Self {
        let t = out.frame.timings;
        Self {
            frame: 0,
            time_s,
            wall_s: 0.0,
            precompute_ms: out.precompute_ms + earlier_precompute_ms,
            update_ms: out.update_ms,
            advance_ms: out.advance_ms,
            gbuffer_ms: t.gbuffer_ms,
            direct_ms: t.direct_ms,
            indirect_ms: t.indirect_ms,
            render_ms: t.total_ms,
            counters: out.stats.clone(),
        }
    }

    /// `frames.csv`'s header for records whose counters are `counter_names`:
    /// [`FRAMES_CSV_COLUMNS`], then the names.
    pub fn csv_header<'a>(counter_names: impl IntoIterator<Item = &'a str>) -> String {
        let mut header = FRAMES_CSV_COLUMNS.join(",");
        for name in counter_names {
            header.push(',');
            header.push_str(name);
        }
        header
    }

    /// The record as a row under [`StepRecord::csv_header`] of its counters' names:
    /// times in seconds to 6 decimals, in milliseconds to 3, counters as they are.
    pub fn csv_row(&self) -> String {
        use std::fmt::Write as _;
        let mut row = format!(
            "{},{:.6},{:.6},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3}",
            self.frame,
            self.time_s,
            self.wall_s,
            self.precompute_ms,
            self.update_ms,
            self.advance_ms,
            self.gbuffer_ms,
            self.direct_ms,
            self.indirect_ms,
            self.render_ms
        );
        for (_, v) in self.counters.iter() {
            let _ = write!(row, ",{v}");
        }
        row
    }

    /// Files the engine's times among `counters` as `illume bench` reports them:
    /// `engine.precompute_ms`, `engine.update_ms`, `engine.advance_ms` and
    /// `engine.render_ms` (the renderer's passes and scene times are not among them).
    pub fn set_engine_counters(&self, counters: &mut Counters) {
        counters.set("engine.precompute_ms", self.precompute_ms);
        counters.set("engine.update_ms", self.update_ms);
        counters.set("engine.advance_ms", self.advance_ms);
        counters.set("engine.render_ms", self.render_ms);
    }
}

/// A `frames.csv` being written: the header takes the first record's counter names,
/// then one row per record.
#[derive(Clone, Debug, Default)]
pub struct FramesCsv {
    header: Option<String>,
    rows: String,
}

impl FramesCsv {
    /// Appends `record`'s row (the first record also sets the header).
    pub fn push(&mut self, record: &StepRecord) {
        self.header
            .get_or_insert_with(|| StepRecord::csv_header(record.counters.names()));
        self.rows.push_str(&record.csv_row());
        self.rows.push('\n');
    }

    /// The table: the header (the fixed columns alone before any record), then the
    /// rows, each line ending in a newline.
    pub fn text(&self) -> String {
        let header = self
            .header
            .clone()
            .unwrap_or_else(|| StepRecord::csv_header([]));
        format!("{header}\n{}", self.rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The columns `animate`'s tests and `scripts/plot_soak.py` read, in their order;
    /// counters after them; a table without records is its header.
    #[test]
    fn frames_csv_keeps_its_columns() {
        assert_eq!(
            StepRecord::csv_header(["a.x", "b.y"]),
            "frame,time_s,wall_s,precompute_ms,update_ms,advance_ms,gbuffer_ms,direct_ms,\
             indirect_ms,render_ms,a.x,b.y"
        );
        let mut counters = Counters::new();
        counters.set("a.x", 3.0);
        counters.set("b.y", 0.25);
        let record = StepRecord {
            frame: 7,
            time_s: 0.5,
            wall_s: 1.25,
            precompute_ms: 2.0,
            render_ms: 10.0,
            counters,
            ..Default::default()
        };
        assert_eq!(
            record.csv_row(),
            "7,0.500000,1.250000,2.000,0.000,0.000,0.000,0.000,0.000,10.000,3,0.25"
        );
        let mut csv = FramesCsv::default();
        assert_eq!(csv.text(), format!("{}\n", StepRecord::csv_header([])));
        csv.push(&record);
        csv.push(&record);
        let text = csv.text();
        assert_eq!(text.lines().count(), 3);
        assert!(text.ends_with("0.25\n"));
        let mut engine = Counters::new();
        record.set_engine_counters(&mut engine);
        assert_eq!(engine.get("engine.precompute_ms"), Some(2.0));
        assert_eq!(engine.get("engine.render_ms"), Some(10.0));
    }
}
