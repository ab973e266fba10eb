//! The report writer and the FLIP error map produce the files they promise; the files are
//! parsed back and checked row by row.

use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_metrics::report::{Bar, BenchReport, Cell, Series, Table, read_csv, write_report};
use illume_metrics::temporal::error_curve;
use illume_metrics::{
    CompareSettings, Counters, FlipSettings, Metric, counters_table, flicker, ldr_flip,
};
use std::path::PathBuf;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("illume-metrics-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A small synthetic "benchmark": two techniques converging at different rates to a static
/// reference, measured with the library, then reported.
fn synthetic_report() -> BenchReport {
    let reference = RgbImage::filled(16, 16, Rgb::new(0.4, 0.5, 0.6));
    let times: Vec<f64> = (0..5).map(|i| i as f64 * 0.5).collect();
    let technique = |name: &str, decay: f32| {
        let frames: Vec<RgbImage> = (0..5)
            .map(|i| reference.map(|p| *p + Rgb::splat(0.2 * decay.powi(i))))
            .collect();
        let curve = error_curve(
            name,
            &frames,
            &vec![reference.clone(); 5],
            &times,
            Metric::Rmse,
            &CompareSettings::default(),
        )
        .unwrap();
        let flick = flicker(&frames, &vec![reference.clone(); 5]).unwrap();
        (curve, flick)
    };
    let (fast, fast_flicker) = technique("photon_stream", 0.25);
    let (slow, slow_flicker) = technique("radiance_cache", 0.75);

    let mut results = Table::new(&["technique", "final_rmse", "flicker", "latency_s"]);
    let mut bars = Vec::new();
    let mut counter_rows = Vec::new();
    for (curve, flick, ms) in [(&fast, &fast_flicker, 8.0), (&slow, &slow_flicker, 4.0)] {
        let latency = curve.latency(0, 0.07).unwrap().seconds.unwrap();
        results.push(vec![
            Cell::Text(curve.technique.clone()),
            Cell::Number(*curve.values.last().unwrap()),
            Cell::Number(flick.mean),
            Cell::Number(latency),
        ]);
        bars.push(Bar {
            label: curve.technique.clone(),
            value: latency,
        });
        let mut c = Counters::for_technique(&curve.technique);
        c.set("frame_ms", ms);
        counter_rows.push((curve.technique.clone(), c));
    }
    BenchReport {
        title: "Synthetic convergence".into(),
        notes: vec!["made by tests/report.rs".into()],
        results,
        tables: vec![(
            "Counters".into(),
            counters_table("technique", &counter_rows),
        )],
        error_label: "RMSE".into(),
        error_curves: vec![Series::from_curve(&fast), Series::from_curve(&slow)],
        fps: vec![
            Series::fps_from_frame_times_ms("photon_stream", &[8.0, 8.0, 10.0]),
            Series::fps_from_frame_times_ms("radiance_cache", &[4.0, 5.0, 4.0]),
        ],
        latencies_s: bars,
    }
}

#[test]
fn report_files_hold_the_expected_rows() {
    let dir = scratch("report");
    let report = synthetic_report();
    let files = write_report(&dir, &report).unwrap();

    // results.csv parses back to the same table.
    let csv = read_csv(&files.results_csv).unwrap();
    assert_eq!(csv, report.results);
    assert_eq!(
        csv.columns,
        vec!["technique", "final_rmse", "flicker", "latency_s"]
    );
    let names: Vec<&Cell> = csv.column("technique").unwrap();
    assert_eq!(
        names,
        vec![
            &Cell::Text("photon_stream".into()),
            &Cell::Text("radiance_cache".into())
        ]
    );
    // RMSE of frame i = 0.2·decayⁱ; final = 0.2·decay⁴. Latency = time from which the
    // RMSE stays below 0.07, frames 0.5 s apart:
    //   decay 0.25: 0.2, 0.05, … → frame 1 → 0.5 s;
    //   decay 0.75: 0.2, 0.15, 0.1125, 0.084, 0.063 → frame 4 → 2.0 s.
    let final_rmse = csv.column("final_rmse").unwrap()[0].as_number().unwrap();
    assert!(
        (final_rmse - 0.2 * 0.25f64.powi(4)).abs() < 1e-6,
        "{final_rmse}"
    );
    let latencies: Vec<Option<f64>> = csv
        .column("latency_s")
        .unwrap()
        .iter()
        .map(|c| c.as_number())
        .collect();
    assert_eq!(latencies, vec![Some(0.5), Some(2.0)]);

    // report.md: title, both tables with one line per row, and links to the plots.
    let md = std::fs::read_to_string(&files.report_md).unwrap();
    assert!(md.starts_with("# Synthetic convergence\n"), "{md}");
    assert!(
        md.contains("| technique | final_rmse | flicker | latency_s |"),
        "{md}"
    );
    assert_eq!(
        md.lines()
            .filter(|l| l.starts_with("| photon_stream |"))
            .count(),
        2,
        "{md}"
    );
    assert!(
        md.contains("| technique | photon_stream.frame_ms | radiance_cache.frame_ms |"),
        "{md}"
    );
    assert!(md.contains("| radiance_cache |  | 4.000 |"), "{md}");
    for plot in ["error_vs_time.svg", "fps.svg", "latency.svg"] {
        assert!(
            md.contains(&format!("]({plot})")),
            "{plot} not linked:\n{md}"
        );
    }

    // Plots: one SVG each, naming every technique (legend or bar labels).
    assert_eq!(files.plots.len(), 3);
    for plot in &files.plots {
        let svg = std::fs::read_to_string(plot).unwrap();
        assert!(svg.starts_with("<svg"), "{}", plot.display());
        assert!(
            svg.contains("photon_stream") && svg.contains("radiance_cache"),
            "{}",
            plot.display()
        );
    }
    let error_svg = std::fs::read_to_string(dir.join("error_vs_time.svg")).unwrap();
    assert!(
        error_svg.matches("<polyline").count() >= 2,
        "one line per technique"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn report_without_series_writes_no_plots() {
    let dir = scratch("report-empty");
    let report = BenchReport {
        title: "t".into(),
        results: Table::new(&["a"]),
        ..BenchReport::default()
    };
    let files = write_report(&dir, &report).unwrap();
    assert!(files.plots.is_empty());
    assert_eq!(read_csv(&files.results_csv).unwrap(), Table::new(&["a"]));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn flip_error_map_png_is_magma() {
    let dir = scratch("flipmap");
    std::fs::create_dir_all(&dir).unwrap();
    let reference = RgbImage::filled(24, 16, Rgb::splat(0.5));
    let mut test = reference.clone();
    // Left half white: large error; right half identical: zero error.
    for y in 0..16 {
        for x in 0..12 {
            *test.get_mut(x, y) = Rgb::ONE;
        }
    }
    let map = ldr_flip(&reference, &test, &FlipSettings::default()).unwrap();
    let path = dir.join("flip.png");
    map.write_png(&path).unwrap();
    let png = image::open(&path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (24, 16));
    // Far from the edge the right half has zero error: magma's first entry (0, 0, 4).
    assert_eq!(png.get_pixel(23, 8).0, [0, 0, 4]);
    // The left half is bright (high error) and matches the bytes of magma_rgb8.
    let bytes = map.magma_rgb8();
    assert_eq!(
        &png.get_pixel(0, 8).0[..],
        &bytes[(8 * 24) * 3..(8 * 24) * 3 + 3]
    );
    assert!(*map.errors.get(0, 8) > 0.5);
    std::fs::remove_dir_all(&dir).unwrap();
}
