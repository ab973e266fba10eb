//! Reports: plain data in, files out. `results.csv` (one row per measurement, named
//! columns), `report.md` (the same as Markdown tables, plus any other tables and the
//! plots), and SVG plots drawn with `plotters`: error versus time per technique, frames
//! per second per frame, and latency bars.
//!
//! ```
//! use illume_metrics::report::{BenchReport, Cell, Series, Table, write_report};
//! let dir = std::env::temp_dir().join(format!("illume-report-doc-{}", std::process::id()));
//! let report = BenchReport {
//!     title: "Cornell box, moving light".into(),
//!     results: Table {
//!         columns: vec!["technique".into(), "flip".into()],
//!         rows: vec![vec![Cell::Text("reference".into()), Cell::Number(0.0)]],
//!     },
//!     error_curves: vec![Series { name: "reference".into(), points: vec![(0.0, 0.0), (1.0, 0.0)] }],
//!     ..BenchReport::default()
//! };
//! let files = write_report(&dir, &report).unwrap();
//! assert!(files.report_md.exists() && files.results_csv.exists());
//! # std::fs::remove_dir_all(&dir).unwrap();
//! ```

use crate::error::MetricsError;
use crate::temporal::ErrorCurve;
use plotters::prelude::*;
use std::fmt;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One table cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// A number; written to CSV with full (round-trip) precision, `inf`/`NaN` as such.
    Number(f64),
    /// Text.
    Text(String),
    /// No value.
    Empty,
}

impl Cell {
    /// The number, if this is one.
    pub fn as_number(&self) -> Option<f64> {
        match self {
            Self::Number(v) => Some(*v),
            _ => None,
        }
    }

    /// A cell parsed from CSV text: a number if it parses as one, empty if empty.
    pub fn parse(text: &str) -> Self {
        if text.is_empty() {
            Self::Empty
        } else {
            text.parse::<f64>()
                .map_or_else(|_| Self::Text(text.to_owned()), Self::Number)
        }
    }

    /// The cell for Markdown: numbers to four significant digits.
    fn to_markdown(&self) -> String {
        match self {
            Self::Number(v) => format_significant(*v),
            Self::Text(t) => t.replace('|', "\\|"),
            Self::Empty => String::new(),
        }
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Number(v) => write!(f, "{v}"),
            Self::Text(t) => f.write_str(t),
            Self::Empty => Ok(()),
        }
    }
}

impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Self::Number(v)
    }
}

impl From<&str> for Cell {
    fn from(t: &str) -> Self {
        Self::Text(t.to_owned())
    }
}

impl From<String> for Cell {
    fn from(t: String) -> Self {
        Self::Text(t)
    }
}

/// Rows of named columns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows; each has one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(columns: &[&str]) -> Self {
        Self {
            columns: columns.iter().map(|c| (*c).to_owned()).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row; panics if its length differs from the column count (a programming
    /// error, not input).
    pub fn push(&mut self, row: Vec<Cell>) {
        assert_eq!(
            row.len(),
            self.columns.len(),
            "row length must match the columns {:?}",
            self.columns
        );
        self.rows.push(row);
    }

    /// Index of the named column.
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The named column's cells.
    pub fn column(&self, name: &str) -> Option<Vec<&Cell>> {
        let i = self.column_index(name)?;
        Some(self.rows.iter().map(|r| &r[i]).collect())
    }

    /// The table as CSV text: a header line, then one line per row.
    pub fn to_csv(&self) -> String {
        let mut s = csv_line(&self.columns);
        s.push('\n');
        for row in &self.rows {
            let cells: Vec<String> = row.iter().map(Cell::to_string).collect();
            s.push_str(&csv_line(&cells));
            s.push('\n');
        }
        s
    }

    /// The table as a GitHub-flavoured Markdown table.
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let header: Vec<String> = self.columns.iter().map(|c| c.replace('|', "\\|")).collect();
        let _ = writeln!(s, "| {} |", header.join(" | "));
        let _ = writeln!(s, "|{}", " --- |".repeat(self.columns.len()));
        for row in &self.rows {
            let cells: Vec<String> = row.iter().map(Cell::to_markdown).collect();
            let _ = writeln!(s, "| {} |", cells.join(" | "));
        }
        s
    }
}

/// `v` with four significant digits (scientific outside [1e-3, 1e6)); `inf`, `NaN` as such.
fn format_significant(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_owned();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&magnitude) {
        format!("{v:.3e}")
    } else {
        format!("{v:.*}", (3 - magnitude).max(0) as usize)
    }
}

/// One CSV line (no newline): fields joined by commas, quoted when they hold a comma,
/// quote or line break (RFC 4180).
pub fn csv_line<S: AsRef<str>>(fields: &[S]) -> String {
    fields
        .iter()
        .map(|f| {
            let f = f.as_ref();
            if f.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// Writes `table` as CSV to `path`.
pub fn write_csv(path: &Path, table: &Table) -> Result<(), MetricsError> {
    illume_core::atomic::write_file(path, table.to_csv()).map_err(|e| MetricsError::io(path, e))
}

/// Reads a CSV file written by [`write_csv`] (RFC 4180 quoting; first line is the
/// header). Cells that parse as numbers become [`Cell::Number`].
pub fn read_csv(path: &Path) -> Result<Table, MetricsError> {
    let text = std::fs::read_to_string(path).map_err(|e| MetricsError::io(path, e))?;
    let records = parse_csv(&text).map_err(|(line, message)| MetricsError::Csv {
        path: path.to_owned(),
        line,
        message,
    })?;
    let mut records = records.into_iter();
    let Some((_, columns)) = records.next() else {
        return Err(MetricsError::Csv {
            path: path.to_owned(),
            line: 1,
            message: "no header line".into(),
        });
    };
    let mut table = Table {
        columns,
        rows: Vec::new(),
    };
    for (line, record) in records {
        if record.len() != table.columns.len() {
            return Err(MetricsError::Csv {
                path: path.to_owned(),
                line,
                message: format!("{} fields, expected {}", record.len(), table.columns.len()),
            });
        }
        table
            .rows
            .push(record.iter().map(|f| Cell::parse(f)).collect());
    }
    Ok(table)
}

/// A CSV record: its 1-based starting line and its fields.
type Record = (usize, Vec<String>);

/// Splits CSV text into records; a syntax error gives its line and a message.
fn parse_csv(text: &str) -> Result<Vec<Record>, (usize, String)> {
    let mut records = Vec::new();
    let mut chars = text.chars().peekable();
    let mut line = 1;
    while chars.peek().is_some() {
        let start_line = line;
        let mut record = Vec::new();
        let mut field = String::new();
        let mut quoted = false;
        loop {
            match chars.next() {
                None if quoted => return Err((start_line, "unterminated quoted field".into())),
                None => {
                    record.push(std::mem::take(&mut field));
                    break;
                }
                Some('"') if quoted => {
                    if chars.peek() == Some(&'"') {
                        chars.next();
                        field.push('"');
                    } else {
                        quoted = false;
                    }
                }
                Some('"') if field.is_empty() => quoted = true,
                Some(',') if !quoted => record.push(std::mem::take(&mut field)),
                Some('\r') if !quoted && chars.peek() == Some(&'\n') => {}
                Some('\n') if !quoted => {
                    line += 1;
                    record.push(std::mem::take(&mut field));
                    break;
                }
                Some(c) => {
                    if c == '\n' {
                        line += 1;
                    }
                    field.push(c);
                }
            }
        }
        records.push((start_line, record));
    }
    Ok(records)
}

/// A named sequence of `(x, y)` points: one line of a plot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// The legend name (usually the technique).
    pub name: String,
    /// The points, in x order.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// The error-versus-time series of a curve (x = seconds).
    pub fn from_curve(curve: &ErrorCurve) -> Self {
        Self {
            name: curve.technique.clone(),
            points: curve.points(),
        }
    }

    /// Frames per second per frame (x = frame index, y = 1000 / frame time in ms).
    pub fn fps_from_frame_times_ms(name: &str, frame_times_ms: &[f64]) -> Self {
        let points = frame_times_ms
            .iter()
            .enumerate()
            .map(|(i, &ms)| (i as f64, 1000.0 / ms))
            .collect();
        Self {
            name: name.to_owned(),
            points,
        }
    }
}

/// One bar of a bar chart.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bar {
    /// Label under the bar (usually the technique).
    pub label: String,
    /// Height.
    pub value: f64,
}

/// A line drawn over a bar chart on its own y axis (right), one value per bar at the
/// bar's centre: e.g. the sun's elevation beside keys per clock hour.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BarLine {
    /// Legend entry.
    pub name: String,
    /// The right axis' description.
    pub y_label: String,
    /// One value per bar (non-finite values are left out).
    pub values: Vec<f64>,
}

/// Everything a benchmark or comparison run reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BenchReport {
    /// Heading of `report.md`.
    pub title: String,
    /// Lines printed under the heading (command line, scene, machine).
    pub notes: Vec<String>,
    /// The main results: written to `results.csv` and as the first table of `report.md`.
    pub results: Table,
    /// Further `(heading, table)` sections of `report.md` (counters, flicker, …).
    pub tables: Vec<(String, Table)>,
    /// Error-versus-time curves, one per technique → `error_vs_time.svg`.
    pub error_curves: Vec<Series>,
    /// Y-axis label of the error plot (e.g. `"FLIP"`); `"error"` if empty.
    pub error_label: String,
    /// Frames per second per frame, one series per technique → `fps.svg`.
    pub fps: Vec<Series>,
    /// Latency after the event per technique, in seconds → `latency.svg`.
    pub latencies_s: Vec<Bar>,
}

/// The files [`write_report`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportFiles {
    /// `results.csv`.
    pub results_csv: PathBuf,
    /// `report.md`.
    pub report_md: PathBuf,
    /// The SVG plots, in the order they appear in `report.md`.
    pub plots: Vec<PathBuf>,
}

/// Plot file names inside the report folder.
pub const ERROR_PLOT: &str = "error_vs_time.svg";
/// See [`ERROR_PLOT`].
pub const FPS_PLOT: &str = "fps.svg";
/// See [`ERROR_PLOT`].
pub const LATENCY_PLOT: &str = "latency.svg";

/// Writes `results.csv`, `report.md` and the plots that have data into `dir` (created if
/// missing).
pub fn write_report(dir: &Path, report: &BenchReport) -> Result<ReportFiles, MetricsError> {
    std::fs::create_dir_all(dir).map_err(|e| MetricsError::io(dir, e))?;
    let results_csv = dir.join("results.csv");
    write_csv(&results_csv, &report.results)?;

    let mut plots = Vec::new();
    let mut md = format!("# {}\n\n", report.title);
    for note in &report.notes {
        let _ = writeln!(md, "{note}  ");
    }
    if !report.notes.is_empty() {
        md.push('\n');
    }
    let _ = write!(md, "## Results\n\n{}\n", report.results.to_markdown());
    for (heading, table) in &report.tables {
        let _ = write!(md, "## {heading}\n\n{}\n", table.to_markdown());
    }
    if !report.error_curves.is_empty() {
        let path = dir.join(ERROR_PLOT);
        let label = if report.error_label.is_empty() {
            "error"
        } else {
            &report.error_label
        };
        plot_lines(
            &path,
            &format!("{label} vs time"),
            "time [s]",
            label,
            &report.error_curves,
        )?;
        let _ = write!(
            md,
            "## Error vs time\n\n![{label} vs time]({ERROR_PLOT})\n\n"
        );
        plots.push(path);
    }
    if !report.fps.is_empty() {
        let path = dir.join(FPS_PLOT);
        plot_lines(&path, "frames per second", "frame", "fps", &report.fps)?;
        let _ = write!(
            md,
            "## Frames per second\n\n![fps per frame]({FPS_PLOT})\n\n"
        );
        plots.push(path);
    }
    if !report.latencies_s.is_empty() {
        let path = dir.join(LATENCY_PLOT);
        plot_bars(
            &path,
            "latency after the event",
            "latency [s]",
            &report.latencies_s,
        )?;
        let _ = write!(
            md,
            "## Latency\n\n![latency after the event]({LATENCY_PLOT})\n\n"
        );
        plots.push(path);
    }
    let report_md = dir.join("report.md");
    illume_core::atomic::write_file(&report_md, md).map_err(|e| MetricsError::io(&report_md, e))?;
    Ok(ReportFiles {
        results_csv,
        report_md,
        plots,
    })
}

/// Distinct line colours (Tableau 10).
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The legend box's fill: white, slightly see-through.
const LEGEND_BACKGROUND: RGBAColor = RGBAColor(255, 255, 255, 0.85);

/// Draws the legend box of `chart`'s labelled series: [`LEGEND_BACKGROUND`], a black
/// border (line charts and the bar chart's line alike; a dual-axis chart passes its
/// primary context, which holds both axes' labels).
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .background_style(LEGEND_BACKGROUND)
        .border_style(BLACK)
        .draw()
}

/// A line series' legend mark: a 20-pixel stroke in its colour.
fn legend_mark(colour: RGBColor) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
}

/// `[lo, hi]` padded so that a flat or empty range still plots.
fn padded_range(values: impl Iterator<Item = f64>, include_zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if include_zero {
        lo = lo.min(0.0);
        hi = hi.max(0.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        0.5 * hi.abs().max(1.0)
    };
    (
        if include_zero && lo == 0.0 {
            0.0
        } else {
            lo - pad
        },
        hi + pad,
    )
}

/// Draws `series` as lines with a legend into an SVG file.
pub fn plot_lines(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), MetricsError> {
    let plot_error = |e: &dyn fmt::Display| MetricsError::Plot {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let (x0, x1) = padded_range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        false,
    );
    let (y0, y1) = padded_range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        true,
    );
    let root = SVGBackend::new(path, (900, 540)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_error(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| plot_error(&e))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()
        .map_err(|e| plot_error(&e))?;
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let finite = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite());
        chart
            .draw_series(LineSeries::new(finite, colour.stroke_width(2)))
            .map_err(|e| plot_error(&e))?
            .label(s.name.as_str())
            .legend(legend_mark(colour));
    }
    draw_legend(&mut chart).map_err(|e| plot_error(&e))?;
    root.present().map_err(|e| plot_error(&e))
}

/// Draws one labelled bar per entry into an SVG file.
pub fn plot_bars(
    path: &Path,
    title: &str,
    y_label: &str,
    bars: &[Bar],
) -> Result<(), MetricsError> {
    draw_bars(path, title, y_label, bars, None)
}

/// [`plot_bars`] with `line` over the bars on a second y axis (right).
pub fn plot_bars_and_line(
    path: &Path,
    title: &str,
    y_label: &str,
    bars: &[Bar],
    line: &BarLine,
) -> Result<(), MetricsError> {
    draw_bars(path, title, y_label, bars, Some(line))
}

fn draw_bars(
    path: &Path,
    title: &str,
    y_label: &str,
    bars: &[Bar],
    line: Option<&BarLine>,
) -> Result<(), MetricsError> {
    let plot_error = |e: &dyn fmt::Display| MetricsError::Plot {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let (_, y1) = padded_range(bars.iter().map(|b| b.value), true);
    let root = SVGBackend::new(path, (900, 540)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_error(&e))?;
    let n = bars.len().max(1);
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70);
    if line.is_some() {
        builder.right_y_label_area_size(70);
    }
    // Integer ranges are inclusive in plotters: 0..n−1 gives n segments.
    let chart = builder
        .build_cartesian_2d((0..n - 1).into_segmented(), 0.0..y1)
        .map_err(|e| plot_error(&e))?;
    let (l0, l1) = padded_range(
        line.into_iter().flat_map(|l| l.values.iter().copied()),
        true,
    );
    let mut chart = chart.set_secondary_coord((0..n - 1).into_segmented(), l0..l1);
    let labels: Vec<String> = bars.iter().map(|b| b.label.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .y_desc(y_label)
        .x_labels(n)
        .x_label_formatter(&|v| match v {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                labels.get(*i).cloned().unwrap_or_default()
            }
            SegmentValue::Last => String::new(),
        })
        .draw()
        .map_err(|e| plot_error(&e))?;
    let histogram = Histogram::vertical(&*chart)
        .style(COLOURS[0].filled())
        .margin(20)
        .data(
            bars.iter()
                .enumerate()
                .filter(|(_, b)| b.value.is_finite())
                .map(|(i, b)| (i, b.value)),
        );
    chart.draw_series(histogram).map_err(|e| plot_error(&e))?;
    if let Some(line) = line {
        chart
            .configure_secondary_axes()
            .y_desc(line.y_label.as_str())
            .draw()
            .map_err(|e| plot_error(&e))?;
        let colour = COLOURS[1];
        chart
            .draw_secondary_series(LineSeries::new(
                line.values
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| v.is_finite())
                    .map(|(i, &v)| (SegmentValue::CenterOf(i), v)),
                colour.stroke_width(2),
            ))
            .map_err(|e| plot_error(&e))?
            .label(line.name.as_str())
            .legend(legend_mark(colour));
        draw_legend(&mut chart).map_err(|e| plot_error(&e))?;
    }
    root.present().map_err(|e| plot_error(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_quotes_and_numbers() {
        let mut t = Table::new(&["name, with comma", "value"]);
        t.push(vec![
            Cell::Text("say \"hi\"\nthere".into()),
            Cell::Number(0.1),
        ]);
        t.push(vec![Cell::Text("inf".into()), Cell::Number(f64::INFINITY)]);
        t.push(vec![Cell::Empty, Cell::Number(-3.0)]);
        let dir = std::env::temp_dir().join(format!("illume-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.csv");
        write_csv(&p, &t).unwrap();
        let back = read_csv(&p).unwrap();
        assert_eq!(back.columns, t.columns);
        assert_eq!(back.rows[0], t.rows[0]);
        // "inf" text reads back as a number: CSV has no types.
        assert_eq!(
            back.rows[1],
            vec![Cell::Number(f64::INFINITY), Cell::Number(f64::INFINITY)]
        );
        assert_eq!(back.rows[2], t.rows[2]);
        std::fs::write(&p, "a,b\n1\n").unwrap();
        let e = read_csv(&p).unwrap_err();
        assert!(e.to_string().contains("t.csv:2"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn plots_accept_single_and_degenerate_data() {
        let dir = std::env::temp_dir().join(format!("illume-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let one = [Bar {
            label: "only".into(),
            value: 0.0,
        }];
        plot_bars(&dir.join("one.svg"), "t", "s", &one).unwrap();
        assert!(
            std::fs::read_to_string(dir.join("one.svg"))
                .unwrap()
                .contains("only")
        );
        let flat = [Series {
            name: "flat".into(),
            points: vec![(1.0, 2.0), (1.0, f64::NAN)],
        }];
        plot_lines(&dir.join("flat.svg"), "t", "x", "y", &flat).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_line_over_bars_gets_its_own_axis_and_legend() {
        let dir = std::env::temp_dir().join(format!("illume-barline-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bars: Vec<Bar> = (0..4)
            .map(|i| Bar {
                label: format!("{i:02}"),
                value: i as f64,
            })
            .collect();
        let line = BarLine {
            name: "sun elevation".into(),
            y_label: "elevation [degrees]".into(),
            values: vec![-10.0, 20.0, f64::NAN, 40.0],
        };
        plot_bars_and_line(&dir.join("both.svg"), "t", "keys", &bars, &line).unwrap();
        plot_bars(&dir.join("bars.svg"), "t", "keys", &bars).unwrap();
        let both = std::fs::read_to_string(dir.join("both.svg")).unwrap();
        let plain = std::fs::read_to_string(dir.join("bars.svg")).unwrap();
        // The line in its colour (Tableau orange), its legend and the right axis.
        for text in ["sun elevation", "elevation [degrees]", "#FF7F0E"] {
            assert!(both.contains(text), "{text} missing");
            assert!(!plain.contains(text), "{text} in the plain bar chart");
        }
        // The right axis spans the line's values (−10 … 40, padded), the left the bars'
        // (0 … 3).
        for tick in ["-10.0", "40.0"] {
            assert!(both.contains(tick), "tick {tick} missing");
            assert!(!plain.contains(tick), "tick {tick} in the plain bar chart");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn markdown_rounds_numbers() {
        let mut t = Table::new(&["a", "b"]);
        t.push(vec![Cell::Number(0.123456), Cell::Number(1234.5678)]);
        t.push(vec![Cell::Number(1.5e-7), Cell::Number(f64::INFINITY)]);
        let md = t.to_markdown();
        assert!(md.contains("| 0.1235 | 1235 |"), "{md}");
        assert!(md.contains("| 1.500e-7 | inf |"), "{md}");
    }
}
