//! `illume.bench`: a benchmark scenario run into plain dicts and arrays.

use crate::engine::PyProgress;
use crate::{detached, value_error};
use illume_bench::{RunOptions, Scenario, run, write_report};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// `(mean, max)` pairs of metrics as a dict from the metric's name.
fn metric_pairs<'py>(
    py: Python<'py>,
    pairs: &[(illume_metrics::Metric, f64, f64)],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (m, mean, max) in pairs {
        d.set_item(m.name(), (mean, max))?;
    }
    Ok(d)
}

/// Runs the benchmark scenario `scenario` (a `.toml` file, docs/bench.md) as `illume
/// bench` does: converged references from (and into) `cache`, each technique's series.
/// With `output` the report (report.md, results.csv, plots) is written there too.
/// Returns a dict: `times_s` (array), `events` (list of dicts), `cache_hits`,
/// `cache_renders`, `reference_noise` {metric: (mean, max)} (each metric between the two
/// halves of the converged references' samples: their own noise, empty when the cache
/// holds no halves), and `series`, a dict from series name to its summary
/// (`technique`, `median_frame_ms`, `precompute_ms`, `metrics` {name: (mean, max)},
/// `latencies` [(frames, seconds, wall_seconds)]) and per-frame arrays under `frames`
/// (`frame`, `time_s`, `frame_ms`, and one per metric, NaN where not measured).
#[pyfunction]
#[pyo3(signature = (scenario, *, cache="out/cache".into(), output=None, progress=None))]
pub fn bench<'py>(
    py: Python<'py>,
    scenario: PathBuf,
    cache: PathBuf,
    output: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (scenario, outcome) = detached(py, move || {
        let scenario = Scenario::load(&scenario).map_err(value_error)?;
        let mut options = RunOptions::for_scenario(&scenario);
        options.cache_dir = cache;
        let mut progress = PyProgress::new(progress);
        let outcome = run(&scenario, &options, &mut progress).map_err(value_error)?;
        if let Some(dir) = output {
            options.output_dir = dir;
            write_report(&scenario, &outcome, &options).map_err(value_error)?;
        }
        Ok((scenario, outcome))
    })?;
    let d = PyDict::new(py);
    d.set_item("name", &scenario.name)?;
    d.set_item("times_s", outcome.times_s.clone().into_pyarray(py))?;
    let events = PyList::empty(py);
    for e in &outcome.events {
        let ed = PyDict::new(py);
        ed.set_item("name", &e.name)?;
        ed.set_item("at_s", e.at_s)?;
        ed.set_item("frame", e.frame)?;
        events.append(ed)?;
    }
    d.set_item("events", events)?;
    d.set_item("cache_hits", outcome.cache_hits)?;
    d.set_item("cache_renders", outcome.cache_renders)?;
    let noise = PyDict::new(py);
    for (m, mean, max, _) in outcome.reference_noise_summary() {
        noise.set_item(m.to_string(), (mean, max))?;
    }
    d.set_item("reference_noise", noise)?;
    let series = PyDict::new(py);
    for s in &outcome.summaries {
        let sd = PyDict::new(py);
        sd.set_item("technique", &s.technique)?;
        sd.set_item("median_frame_ms", s.median_frame_ms)?;
        sd.set_item("precompute_ms", s.precompute_ms)?;
        sd.set_item("metrics", metric_pairs(py, &s.metrics)?)?;
        sd.set_item("own_metrics", metric_pairs(py, &s.own_metrics)?)?;
        let latencies: Vec<_> = s
            .latencies
            .iter()
            .map(|l| (l.frames, l.seconds, l.wall_seconds))
            .collect();
        sd.set_item("latencies", latencies)?;
        let records: Vec<_> = outcome
            .records
            .iter()
            .filter(|r| r.series == s.series)
            .collect();
        let frames = PyDict::new(py);
        let column = |f: &dyn Fn(&illume_bench::FrameRecord) -> f64| {
            records.iter().map(|r| f(r)).collect::<Vec<f64>>()
        };
        frames.set_item("frame", column(&|r| r.frame as f64).into_pyarray(py))?;
        frames.set_item("time_s", column(&|r| r.time_s).into_pyarray(py))?;
        frames.set_item("frame_ms", column(&|r| r.frame_ms).into_pyarray(py))?;
        for m in &scenario.metrics {
            let values = column(&|r| r.metric(*m).unwrap_or(f64::NAN));
            frames.set_item(m.name(), values.into_pyarray(py))?;
        }
        sd.set_item("frames", frames)?;
        series.set_item(&s.series, sd)?;
    }
    d.set_item("series", series)?;
    Ok(d)
}
