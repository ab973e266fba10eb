//! The report of a run: `results.csv` (one row per series per frame), `report.md`
//! (summary tables, the plots, the scenario and the machine) and SVG plots drawn with
//! illume-metrics' plotting functions.

use crate::error::BenchError;
use crate::run::{BenchOutcome, FrameRecord, RunOptions};
use crate::scenario::Scenario;
use illume_core::outputs::OutputDir;
use illume_metrics::report::{Bar, Cell, Series, Table, plot_bars, plot_lines, write_csv};
use illume_metrics::{Counters, Metric, counters_table};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The files [`write_report`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportFiles {
    /// `report.md`.
    pub report_md: PathBuf,
    /// `results.csv`.
    pub results_csv: PathBuf,
    /// The SVG plots.
    pub plots: Vec<PathBuf>,
}

/// The per-frame table of `results.csv`: `series, technique, frame, time_s, frame_ms,
/// fps`, one column per metric, `flicker`, then every counter (union over the series;
/// empty where a series has no such counter).
pub fn results_table(scenario: &Scenario, records: &[FrameRecord]) -> Table {
    let counter_rows: Vec<(String, Counters)> = records
        .iter()
        .map(|r| (String::new(), r.counters.clone()))
        .collect();
    let counters = counters_table("", &counter_rows);
    let mut columns: Vec<String> = ["series", "technique", "frame", "time_s", "frame_ms", "fps"]
        .map(String::from)
        .to_vec();
    columns.extend(scenario.metrics.iter().map(|m| m.name().to_owned()));
    let own = scenario.own_converged_frames > 0;
    if own {
        columns.extend(scenario.metrics.iter().map(|m| format!("own_{}", m.name())));
    }
    columns.push("flicker".into());
    columns.extend(counters.columns.iter().skip(1).cloned());
    let rows = records
        .iter()
        .zip(&counters.rows)
        .map(|(r, c)| {
            let mut row = vec![
                Cell::Text(r.series.clone()),
                Cell::Text(r.technique.clone()),
                Cell::Number(r.frame as f64),
                Cell::Number(r.time_s),
                Cell::Number(r.frame_ms),
                Cell::Number(1000.0 / r.frame_ms),
            ];
            row.extend(
                scenario
                    .metrics
                    .iter()
                    .map(|&m| r.metric(m).map_or(Cell::Empty, Cell::Number)),
            );
            if own {
                row.extend(
                    scenario
                        .metrics
                        .iter()
                        .map(|&m| r.own_metric(m).map_or(Cell::Empty, Cell::Number)),
                );
            }
            row.push(r.flicker.map_or(Cell::Empty, Cell::Number));
            row.extend(c.iter().skip(1).cloned());
            row
        })
        .collect();
    Table { columns, rows }
}

/// One row per series: frames, precompute time, median frame time and fps, mean and max
/// of each metric, mean and max flicker.
pub fn summary_table(scenario: &Scenario, outcome: &BenchOutcome) -> Table {
    let mut columns: Vec<String> = [
        "series",
        "frames",
        "precompute [ms]",
        "median frame [ms]",
        "median fps",
    ]
    .map(String::from)
    .to_vec();
    for m in &scenario.metrics {
        columns.push(format!("{m} mean"));
        columns.push(format!("{m} max"));
    }
    let own = scenario.own_converged_frames > 0;
    if own {
        columns.push(format!("{} vs own converged mean", scenario.error_metric));
    }
    columns.push("flicker mean".into());
    columns.push("flicker max".into());
    let rows = outcome
        .summaries
        .iter()
        .map(|s| {
            let frames = outcome
                .records
                .iter()
                .filter(|r| r.series == s.series)
                .count();
            let mut row = vec![
                Cell::Text(s.series.clone()),
                Cell::Text(frames.to_string()),
                Cell::Number(s.precompute_ms),
                Cell::Number(s.median_frame_ms),
                Cell::Number(1000.0 / s.median_frame_ms),
            ];
            for &(_, mean, max) in &s.metrics {
                row.push(Cell::Number(mean));
                row.push(Cell::Number(max));
            }
            if own {
                let mean = s
                    .own_metrics
                    .iter()
                    .find(|(m, _, _)| *m == scenario.error_metric)
                    .map(|&(_, mean, _)| mean);
                row.push(mean.map_or(Cell::Empty, Cell::Number));
            }
            match s.flicker {
                Some((mean, max)) => row.extend([Cell::Number(mean), Cell::Number(max)]),
                None => row.extend([Cell::Empty, Cell::Empty]),
            }
            row
        })
        .collect();
    Table { columns, rows }
}

/// One row per series per event: when it happened and how long the error took to stay
/// below `latency_threshold`, in frames, scene seconds and wall-clock seconds (`never` if
/// it did not by the next event or the last frame); with `own_converged_frames`, the same
/// in frames and wall-clock seconds against the technique's own converged images, below
/// `own_latency_threshold`.
pub fn latency_table(outcome: &BenchOutcome) -> Table {
    let own = outcome
        .summaries
        .iter()
        .any(|s| !s.own_latencies.is_empty());
    let mut columns = vec![
        "series",
        "event",
        "at [s]",
        "frame",
        "latency [frames]",
        "latency [s]",
        "latency wall [s]",
    ];
    if own {
        columns.extend([
            "to own steady state [frames]",
            "to own steady state wall [s]",
        ]);
    }
    let mut t = Table::new(&columns);
    for s in &outcome.summaries {
        for (k, (e, l)) in outcome.events.iter().zip(&s.latencies).enumerate() {
            let never = || Cell::Text("never".into());
            let mut row = vec![
                Cell::Text(s.series.clone()),
                Cell::Text(e.name.clone()),
                Cell::Number(e.at_s),
                Cell::Text(e.frame.to_string()),
                l.frames.map_or_else(never, |f| Cell::Text(f.to_string())),
                l.seconds.map_or_else(never, Cell::Number),
                l.wall_seconds.map_or_else(never, Cell::Number),
            ];
            if own {
                match s.own_latencies.get(k) {
                    Some(o) => row.extend([
                        o.frames.map_or_else(never, |f| Cell::Text(f.to_string())),
                        o.wall_seconds.map_or_else(never, Cell::Number),
                    ]),
                    None => row.extend([Cell::Empty, Cell::Empty]),
                }
            }
            t.push(row);
        }
    }
    t
}

/// The CPU model (from `lscpu`, else `/proc/cpuinfo`) and the thread count.
pub fn machine_info() -> String {
    let from_lscpu = std::process::Command::new("lscpu")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|text| {
            text.lines()
                .find_map(|l| l.strip_prefix("Model name:").map(|m| m.trim().to_owned()))
        });
    let model = from_lscpu
        .or_else(|| {
            std::fs::read_to_string("/proc/cpuinfo")
                .ok()
                .and_then(|text| {
                    text.lines().find_map(|l| {
                        l.strip_prefix("model name")
                            .and_then(|r| r.split_once(':'))
                            .map(|(_, m)| m.trim().to_owned())
                    })
                })
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{model}, {threads} threads available")
}

/// The series' values of `metric` against time.
fn metric_series(outcome: &BenchOutcome, metric: Metric) -> Vec<Series> {
    outcome
        .summaries
        .iter()
        .map(|s| Series {
            name: s.series.clone(),
            points: outcome
                .records
                .iter()
                .filter(|r| r.series == s.series)
                // Frames outside `reference_frames` have no error: no point.
                .filter_map(|r| r.metric(metric).map(|v| (r.time_s, v)))
                .collect(),
        })
        .collect()
}

/// Writes `results.csv`, `report.md` and the plots into `options.output_dir`:
/// `error_vs_time.svg` (the error metric), `error_vs_time_METRIC.svg` (each other
/// metric), `fps.svg` (the techniques' frames per second per frame; the equal-time
/// series match them by construction and are left out) and `latency_K.svg` for event
/// `K` (one bar per series; a series that never settles has no bar).
pub fn write_report(
    scenario: &Scenario,
    outcome: &BenchOutcome,
    options: &RunOptions,
) -> Result<ReportFiles, BenchError> {
    let dir = &options.output_dir;
    let out = OutputDir::create(dir)?;
    // Each file is recorded in the folder's manifest; one that is there already and is
    // not illume's is refused, untouched.
    let recorded = |name: &str, write: &mut dyn FnMut(&Path) -> Result<(), BenchError>| {
        out.intend(name)?;
        write(&dir.join(name))?;
        out.written(name)?;
        Ok::<(), BenchError>(())
    };
    let results_csv = dir.join("results.csv");
    recorded("results.csv", &mut |p| {
        Ok(write_csv(p, &results_table(scenario, &outcome.records))?)
    })?;

    let mut plots = Vec::new();
    let mut plot_md = String::new();
    let error = scenario.error_metric;
    let path = dir.join("error_vs_time.svg");
    recorded("error_vs_time.svg", &mut |p| {
        Ok(plot_lines(
            p,
            &format!("{error} vs time (against the converged reference)"),
            "time [s]",
            error.name(),
            &metric_series(outcome, error),
        )?)
    })?;
    let _ = write!(
        plot_md,
        "### {error} vs time\n\n![{error} vs time](error_vs_time.svg)\n\n"
    );
    plots.push(path);
    for &m in scenario.metrics.iter().filter(|&&m| m != error) {
        let name = format!("error_vs_time_{}.svg", m.name());
        let path = dir.join(&name);
        recorded(&name, &mut |p| {
            Ok(plot_lines(
                p,
                &format!("{m} vs time"),
                "time [s]",
                m.name(),
                &metric_series(outcome, m),
            )?)
        })?;
        let _ = write!(plot_md, "### {m} vs time\n\n![{m} vs time]({name})\n\n");
        plots.push(path);
    }
    let fps: Vec<Series> = scenario
        .techniques
        .iter()
        .map(|t| {
            let ms: Vec<f64> = outcome
                .records
                .iter()
                .filter(|r| r.series == t.label())
                .map(|r| r.frame_ms)
                .collect();
            Series::fps_from_frame_times_ms(t.label(), &ms)
        })
        .collect();
    let path = dir.join("fps.svg");
    recorded("fps.svg", &mut |p| {
        Ok(plot_lines(p, "frames per second", "frame", "fps", &fps)?)
    })?;
    let _ = write!(
        plot_md,
        "### Frames per second\n\n![fps per frame](fps.svg)\n\n"
    );
    plots.push(path);
    let _ = write!(plot_md, "### Latency after each event\n\n");
    for (k, event) in outcome.events.iter().enumerate() {
        let bars: Vec<Bar> = outcome
            .summaries
            .iter()
            .map(|s| Bar {
                label: s.series.clone(),
                value: s.latencies[k].seconds.unwrap_or(f64::NAN),
            })
            .collect();
        let name = format!("latency_{k}.svg");
        let path = dir.join(&name);
        let title = format!("latency after \"{}\" (frame {})", event.name, event.frame);
        recorded(&name, &mut |p| {
            Ok(plot_bars(p, &title, "latency [s]", &bars)?)
        })?;
        let _ = write!(plot_md, "![{title}]({name})\n\n");
        plots.push(path);
    }

    let report_md = dir.join("report.md");
    let md = markdown(scenario, outcome, options, &plot_md);
    out.write_file("report.md", md)?;
    Ok(ReportFiles {
        report_md,
        results_csv,
        plots,
    })
}

/// The report's section on the converged reference's own noise: each metric between the
/// two independent halves of its samples, over the measured frames.
fn reference_noise_section(scenario: &Scenario, outcome: &BenchOutcome) -> String {
    let half = scenario.reference.spp / 2;
    let mut md = String::from("## The converged reference's own noise\n\n");
    let summary = outcome.reference_noise_summary();
    if summary.is_empty() {
        let _ = write!(
            md,
            "Not measured: {}.\n\n",
            if half == 0 {
                "the reference has one sample a pixel, so no halves".to_owned()
            } else {
                "its cached images were stored before the cache kept their first halves \
                 (remove them from the cache to render them again with halves)"
                    .to_owned()
            }
        );
        return md;
    }
    let table = Table {
        columns: ["metric", "between halves, mean", "max", "frames"]
            .map(String::from)
            .to_vec(),
        rows: summary
            .iter()
            .map(|&(m, mean, max, n)| {
                vec![
                    Cell::Text(m.to_string()),
                    Cell::Number(mean),
                    Cell::Number(max),
                    Cell::Text(n.to_string()),
                ]
            })
            .collect(),
    };
    let _ = write!(
        md,
        "Each converged reference is the mean of two independent halves of its samples \
         ({half} spp each). The metrics between them measure its noise: the full \
         reference's own error is smaller (for RMSE, half of the halves'), but a series \
         whose error approaches these values is measuring the reference's noise as much \
         as its own; raise `[reference].spp` (error falls as 1/√spp) before reading \
         differences there.\n\n{}\n",
        table.to_markdown()
    );
    md
}

fn markdown(
    scenario: &Scenario,
    outcome: &BenchOutcome,
    options: &RunOptions,
    plots: &str,
) -> String {
    let mut md = format!("# {}\n\n", scenario.name);
    if !scenario.description.is_empty() {
        let _ = writeln!(md, "{}\n", scenario.description);
    }
    for note in &options.notes {
        let _ = writeln!(md, "{note}  ");
    }
    let times = &outcome.times_s;
    let span = match (times.first(), times.last()) {
        (Some(a), Some(b)) => format!("{} frames, {a} s to {b} s", times.len()),
        _ => "no frames".into(),
    };
    let _ = writeln!(
        md,
        "Scene `{}`{}, {}×{} pixels, {span}.  ",
        scenario.scene,
        scenario
            .animation
            .as_ref()
            .map_or(String::new(), |a| format!(", animation `{a}`")),
        scenario.width,
        scenario.height
    );
    let _ = writeln!(
        md,
        "Converged reference: path tracer, {} spp, seed {}; {} distinct, {} from the cache, \
         {} rendered (cache `{}`).  ",
        scenario.reference.spp,
        scenario.reference.seed,
        outcome.cache_hits + outcome.cache_renders,
        outcome.cache_hits,
        outcome.cache_renders,
        options.cache_dir.display()
    );
    // Supersampled entries say so: their frames (and frame times) are of a larger image.
    let supersampled: Vec<String> = scenario
        .techniques
        .iter()
        .filter(|t| t.supersample() > 1)
        .map(|t| {
            let k = t.supersample();
            format!(
                "{} {k} × {k} ({}×{} rendered)",
                t.label(),
                scenario.width * k,
                scenario.height * k
            )
        })
        .collect();
    if !supersampled.is_empty() {
        let _ = writeln!(
            md,
            "Supersampled series (frames averaged over K × K samples a pixel before they \
             are measured; frame times are those of the larger image): {}.  ",
            supersampled.join(", ")
        );
    }
    let _ = writeln!(md, "Machine: {}.\n", machine_info());
    let _ = write!(
        md,
        "## Summary\n\nEvery metric is measured per frame against the converged reference \
         (lower is better except PSNR and SSIM). Frame time is wall clock for the whole \
         frame. Flicker: frame-to-frame luminance change beyond the reference's own change. \
         {}\n\n{}\n",
        if scenario.reference.equal_time {
            "`reference (equal time to X)` is the progressive reference path tracer given the \
             same cumulative wall-clock time as technique X, frame by frame (whole samples per \
             pixel; between passes it shows its last image), accumulating while the scene \
             does not change."
        } else {
            ""
        },
        summary_table(scenario, outcome).to_markdown()
    );
    let _ = write!(md, "{}", reference_noise_section(scenario, outcome));
    let _ = write!(
        md,
        "## Latency after events\n\nFrames, scene seconds and wall-clock seconds (the frame \
         times of the frames rendered after the event's frame, up to the settled one) from \
         the event until {} against the converged reference stays below {} up to the next \
         event (or the last frame), judged on the measured frames; `never` if it does \
         not.{}\n\n{}\n",
        scenario.error_metric,
        scenario.latency_threshold,
        if scenario.own_converged_frames > 0 {
            format!(
                " \"To own steady state\": the same until {} against the technique's own \
                 converged image of the frame's state (a fresh start, {} frames at fixed \
                 work) stays below {}.",
                scenario.error_metric,
                scenario.own_converged_frames,
                scenario.own_latency_threshold()
            )
        } else {
            String::new()
        },
        latency_table(outcome).to_markdown()
    );
    let _ = write!(md, "## Plots\n\n{plots}");
    let _ = write!(
        md,
        "## Per-frame results\n\n`results.csv`: one row per series per frame ({} rows): \
         time, frame time, each metric, flicker against the previous frame, and every \
         counter the technique reports.\n\n",
        outcome.records.len()
    );
    let _ = write!(
        md,
        "## Scenario\n\n`{}`\n\n```toml\n{}\n```\n",
        scenario.file.display(),
        scenario.text.trim_end()
    );
    md
}
