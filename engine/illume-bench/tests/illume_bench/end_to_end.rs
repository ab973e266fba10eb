//! A tiny scenario end to end: converged references (and their cache), the reference
//! technique with its equal-time path tracer, report files, and the CSV read back.

use crate::common::{options_in, temp_dir};
use illume_bench::{Scenario, Silent, run, write_report};
use illume_core::image::RgbImage;
use illume_metrics::report::{Cell, read_csv};
use illume_metrics::{Metric, compare_images};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// 16×12 pixels, 3 frames; the light moves (2 distinct states per animation step) and an
/// edit moves the sphere at 0.5 s.
const TINY: &str = r#"
name = "tiny"
scene = "builtin:cornell-spot"
animation = "move_light"
width = 16
height = 12
times_s = [0.0, 0.5, 1.0]
metrics = ["rmse", "relmse", "flip"]

[reference]
spp = 16

[[technique]]
name = "reference"
work = 1

[[edit]]
at_s = 0.5
instance = "sphere"
translation = [0.2, 0.3, 0.0]
"#;

fn mtimes(dir: &Path) -> Vec<(PathBuf, SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .map(|p| {
            let t = std::fs::metadata(&p).unwrap().modified().unwrap();
            (p, t)
        })
        .collect();
    v.sort();
    v
}

#[test]
fn tiny_scenario_runs_end_to_end_and_reuses_its_references() {
    let root = temp_dir("e2e");
    let scenario = Scenario::parse(TINY, &root.join("tiny.toml")).unwrap();
    let mut options = options_in(&root, true);
    options.notes = vec!["test run".into()];

    // First run: every distinct state is rendered (3 frames, 3 states: the light moves).
    let first = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!((first.cache_hits, first.cache_renders), (0, 3));
    let files = write_report(&scenario, &first, &options).unwrap();
    for f in [&files.report_md, &files.results_csv] {
        assert!(f.is_file(), "{} missing", f.display());
    }
    for name in [
        "error_vs_time.svg",
        "error_vs_time_rmse.svg",
        "fps.svg",
        "latency_0.svg",
        "latency_1.svg",
    ] {
        let p = options.output_dir.join(name);
        let svg = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(svg.contains("<svg"), "{name} is not an SVG");
    }
    assert_eq!(files.plots.len(), 6, "{:?}", files.plots);
    // The converged reference and the series labelled `reference` (1 spp) in folders of
    // their own: the series once wrote over the converged frames.
    let exr = |folder: &str, i: usize| {
        RgbImage::read(
            &options
                .output_dir
                .join(format!("frames/{folder}/{i:04}.exr")),
        )
        .unwrap_or_else(|e| panic!("frames/{folder}/{i:04}.exr: {e}"))
    };
    for i in [0, 2] {
        let (converged, series) = (exr("converged reference", i), exr("reference", i));
        assert!(
            illume_metrics::block_error(&converged, &series, 8).unwrap() > 0.0,
            "frame {i}: the 1-spp series equals the converged reference"
        );
    }

    // results.csv: one row per frame per series, finite metrics, and the technique
    // (1 spp of indirect light per frame) measurably away from the converged reference.
    let table = read_csv(&files.results_csv).unwrap();
    let series = table.column("series").unwrap();
    let equal = "reference (equal time to reference)";
    for name in ["reference", equal] {
        let n = series
            .iter()
            .filter(|c| **c == &Cell::Text(name.into()))
            .count();
        assert_eq!(n, 3, "{name}: one row per frame");
    }
    assert_eq!(table.rows.len(), 6);
    for m in ["rmse", "relmse", "flip", "frame_ms", "time_s"] {
        for (i, c) in table.column(m).unwrap().iter().enumerate() {
            let v = c
                .as_number()
                .unwrap_or_else(|| panic!("{m} row {i}: {c:?}"));
            assert!(v.is_finite(), "{m} row {i} = {v}");
        }
    }
    let rmse = table.column("rmse").unwrap();
    for (s, v) in series.iter().zip(&rmse) {
        if **s == Cell::Text("reference".into()) {
            assert!(
                v.as_number().unwrap() > 1e-4,
                "technique rmse {v:?} not above 0"
            );
        }
    }
    assert!(
        table.column("reference.spp").is_some(),
        "technique counters in the CSV"
    );
    // Equal time: the first frame always gets a pass; every frame shows at least 1 spp.
    let equal_rows: Vec<_> = first.records.iter().filter(|r| r.series == equal).collect();
    assert!(equal_rows[0].counters.get("equal_time.spp_added").unwrap() >= 1.0);
    for r in &equal_rows {
        assert!(r.counters.get("equal_time.spp").unwrap() >= 1.0, "{r:?}");
        let budget = r.counters.get("equal_time.budget_ms").unwrap();
        let technique = first
            .records
            .iter()
            .find(|t| t.series == "reference" && t.frame == r.frame);
        assert_eq!(
            budget,
            technique.unwrap().frame_ms,
            "budget = the technique's frame time"
        );
    }
    let times: Vec<f64> = table
        .column("time_s")
        .unwrap()
        .iter()
        .map(|c| c.as_number().unwrap())
        .collect();
    assert_eq!(&times[..3], &[0.0, 0.5, 1.0]);

    // The converged reference against itself scores exactly zero: the technique's error
    // above is the technique's, not the measurement's.
    let cached = first
        .reference_keys
        .iter()
        .map(|k| options.cache_dir.join(format!("{}.exr", k.hex())))
        .collect::<Vec<_>>();
    let r0 = RgbImage::read(&cached[0]).unwrap();
    let self_error = compare_images(&r0, &r0, &[Metric::Rmse, Metric::Flip]).unwrap();
    assert_eq!(self_error, vec![(Metric::Rmse, 0.0), (Metric::Flip, 0.0)]);
    let technique_rmse0 = first.records[0].metric(Metric::Rmse).unwrap();
    assert!(technique_rmse0 > self_error[0].1);

    // report.md holds the summary, latency and scenario sections.
    let md = std::fs::read_to_string(&files.report_md).unwrap();
    for needle in [
        "# tiny",
        "## Summary",
        "## Latency after events",
        "edit 0 (instance \"sphere\")",
        "start (animation starts)",
        "error_vs_time.svg",
        "```toml",
        "test run",
        "Machine:",
    ] {
        assert!(md.contains(needle), "report.md lacks `{needle}`:\n{md}");
    }
    assert_eq!(first.events.len(), 2, "{:?}", first.events);
    assert_eq!(
        first.events[1].frame, 1,
        "the edit at 0.5 s shows from frame 1"
    );

    // Second run: all three references come from the cache, the files (each image and
    // its first half) are untouched.
    let before = mtimes(&options.cache_dir);
    assert_eq!(before.len(), 6);
    let second = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!((second.cache_hits, second.cache_renders), (3, 0));
    assert_eq!(
        mtimes(&options.cache_dir),
        before,
        "cached EXRs were rewritten"
    );
    assert_eq!(second.reference_keys, first.reference_keys);

    // A changed reference setting changes every key: rendered anew, old files kept.
    let more = Scenario::parse(
        &TINY.replace("spp = 16", "spp = 17"),
        &root.join("tiny.toml"),
    )
    .unwrap();
    let third = run(&more, &options, &mut Silent).unwrap();
    assert_eq!((third.cache_hits, third.cache_renders), (0, 3));
    for (a, b) in third.reference_keys.iter().zip(&first.reference_keys) {
        assert_ne!(a.hash, b.hash);
    }
    assert_eq!(
        mtimes(&options.cache_dir).len(),
        12,
        "3 + 3 images, each with its half"
    );
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn static_scene_shares_one_reference_across_frames() {
    let root = temp_dir("static");
    let text = TINY
        .replace("animation = \"move_light\"\n", "")
        .replace(
            "[[edit]]\nat_s = 0.5\ninstance = \"sphere\"\ntranslation = [0.2, 0.3, 0.0]\n",
            "",
        )
        .replace(
            "[reference]\nspp = 16",
            "[reference]\nspp = 4\nequal_time = false",
        );
    let scenario = Scenario::parse(&text, &root.join("static.toml")).unwrap();
    let options = options_in(&root, false);
    let outcome = run(&scenario, &options, &mut Silent).unwrap();
    assert_eq!((outcome.cache_hits, outcome.cache_renders), (0, 1));
    assert_eq!(outcome.records.len(), 3, "no equal-time series");
    // The reference technique accumulates while nothing changes: its spp counter grows.
    let spp: Vec<f64> = outcome
        .records
        .iter()
        .map(|r| r.counters.get("reference.spp").unwrap())
        .collect();
    assert_eq!(spp, vec![1.0, 2.0, 3.0]);
    assert!(outcome.records.iter().skip(1).all(|r| r.flicker.is_some()));
    std::fs::remove_dir_all(&root).unwrap();
}

/// `reference_frames` measures only the listed frames (the others have no error, and no
/// reference is rendered for them); `own_converged_frames` measures each technique
/// against its own converged image, which for photon_stream (deterministic) is closer
/// than the path tracer's: its own steady state carries its bias. Latency against the
/// own images is judged with `own_latency_threshold`, against the path tracer with
/// `latency_threshold`.
#[test]
fn reference_frames_and_own_converged_images() {
    let text = r#"
name = "sparse"
scene = "builtin:cornell-spot"
animation = "move_light"
width = 24
height = 18
times_s = [0.0, 0.25, 0.5, 0.75, 1.0]
metrics = ["rmse", "flip"]
reference_frames = [0, 2, 4]
own_converged_frames = 6
latency_threshold = 0.5
own_latency_threshold = 0.001

[reference]
spp = 16
equal_time = false

[[technique]]
name = "photon_stream"
settings = { mode = "deterministic", vsl_count = 30, photons_per_frame = 3000 }

[[edit]]
at_s = 0.5
instance = "sphere"
translation = [0.2, 0.3, 0.0]
"#;
    let root = temp_dir("sparse");
    let scenario = Scenario::parse(text, &root.join("sparse.toml")).unwrap();
    let options = options_in(&root, false);
    let out = run(&scenario, &options, &mut Silent).unwrap();
    // Three references rendered, not five.
    assert_eq!(out.cache_renders, 3);
    let measured: Vec<bool> = out.records.iter().map(|r| !r.metrics.is_empty()).collect();
    assert_eq!(measured, [true, false, true, false, true]);
    let own: Vec<bool> = out
        .records
        .iter()
        .map(|r| !r.own_metrics.is_empty())
        .collect();
    assert_eq!(own, measured);
    // Its own converged image is nearer than the path tracer's on every measured frame.
    for r in out.records.iter().filter(|r| !r.metrics.is_empty()) {
        let (own, reference) = (
            r.own_metric(Metric::Rmse).unwrap(),
            r.metric(Metric::Rmse).unwrap(),
        );
        assert!(
            own < reference,
            "frame {}: own {own} vs reference {reference}",
            r.frame
        );
    }
    let s = &out.summaries[0];
    assert_eq!(s.own_latencies.len(), out.events.len());
    // Each threshold judges its own error: FLIP against the path tracer (about 0.2 at
    // this size) never rises above 0.5, so every latency is 0 frames; against its own
    // converged image (0.006 to 0.09 here) it does not stay below 0.001, so none settles. Judged
    // with the same threshold, both rows would agree.
    for (e, (l, own)) in out
        .events
        .iter()
        .zip(s.latencies.iter().zip(&s.own_latencies))
    {
        assert_eq!(l.frames, Some(0), "{}: {l:?}", e.name);
        assert_eq!(own.frames, None, "{}: {own:?}", e.name);
    }
    // Wall-clock latency is the frame times after the event's frame, up to the settled one.
    for (e, l) in out.events.iter().zip(&s.latencies) {
        if let (Some(k), Some(wall)) = (l.frames, l.wall_seconds) {
            let expected: f64 = out.records[e.frame + 1..=e.frame + k]
                .iter()
                .map(|r| r.frame_ms)
                .sum::<f64>()
                / 1e3;
            assert!((wall - expected).abs() < 1e-12, "{wall} vs {expected}");
        }
    }
    let files = write_report(&scenario, &out, &options).unwrap();
    let md = std::fs::read_to_string(&files.report_md).unwrap();
    assert!(
        md.contains("latency wall [s]") && md.contains("to own steady state"),
        "{md}"
    );
    // The latency section states both thresholds.
    assert!(
        md.contains("stays below 0.5 up to the next event")
            && md.contains("(a fresh start, 6 frames at fixed work)")
            && md.contains("stays below 0.001."),
        "{md}"
    );
    let csv = std::fs::read_to_string(&files.results_csv).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.contains("own_rmse"), "{header}");
    // Unmeasured frames have empty cells, not zeros.
    let row1 = csv.lines().nth(2).unwrap();
    assert!(row1.contains(",,"), "{row1}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn reference_frames_out_of_range_name_the_key() {
    let text = "scene = \"builtin:cornell-spot\"\ntimes_s = [0.0, 0.5]\nreference_frames = [0, 2]\n[[technique]]\nname = \"reference\"\n";
    let e = Scenario::parse(text, Path::new("scenarios/x.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("x.toml") && e.contains("reference_frames") && e.contains("frame 2"),
        "{e}"
    );
    let text = text.replace("[0, 2]", "[1, 0]");
    let e = Scenario::parse(&text, Path::new("scenarios/x.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("increasing"), "{e}");
}

/// The own converged image is the technique started fresh on the edited state, its last
/// frame rendered with the measured frame's random numbers: for selective photon tracing
/// (deterministic), whose finished update equals a fresh trace of the pool bit for bit,
/// the error against it is exactly zero before the edit and again once every group is up
/// to date after it — and not zero while it catches up. The scene has an area light,
/// whose direct light is sampled anew each frame.
#[test]
fn own_converged_image_is_a_fresh_start_on_the_edited_state() {
    let scene = illume_scene::shared_scenes_dir().join("gltf/cornell_area.gltf");
    let text = r#"
name = "own_selective"
scene = "SCENE"
width = 24
height = 18
times_s = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.25]
metrics = ["rmse"]
error_metric = "rmse"
own_converged_frames = 1
own_latency_threshold = 1e-12

[reference]
spp = 1
equal_time = false

[[technique]]
name = "selective"
settings = { mode = "deterministic", pilots_per_group = 8, ratio = 4, element_count = 400, min_photons_per_element = 0, min_impacts_per_element = 0, photons_per_frame = 600 }

[[edit]]
at_s = 0.5
instance = "sphere"
translation = [0.3, 0.3, 0.3]
"#
    .replace("SCENE", &scene.to_string_lossy());
    let root = temp_dir("own-selective");
    let scenario = Scenario::parse(&text, &root.join("own_selective.toml")).unwrap();
    let options = options_in(&root, false);
    let out = run(&scenario, &options, &mut Silent).unwrap();
    let own: Vec<f64> = out
        .records
        .iter()
        .map(|r| r.own_metric(Metric::Rmse).unwrap())
        .collect();
    let stale: Vec<f64> = out
        .records
        .iter()
        .map(|r| r.counters.get("selective.stale_groups").unwrap())
        .collect();
    assert_eq!(&own[..2], &[0.0, 0.0], "before the edit: {own:?}");
    assert!(
        own[2] > 0.0,
        "at the edit's frame the update has only begun: {own:?}"
    );
    // The first frame after the edit with every group up to date.
    let current = (2..stale.len())
        .find(|&f| stale[f] == 0.0)
        .unwrap_or_else(|| panic!("groups still stale at the last frame: {stale:?}"));
    assert!(current > 2, "the update takes a few frames: {stale:?}");
    assert!(
        own[current..].iter().all(|&e| e == 0.0),
        "exact once no group is stale (frame {current}): {own:?}, stale {stale:?}"
    );
    // Judged against the own images with a threshold this strict, the edit's latency is
    // the frame the update finished.
    let edit = &out.events[1];
    assert_eq!(
        out.summaries[0].own_latencies[1].frames,
        Some(current - edit.frame),
        "{own:?}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// `supersample = K`: an entry's frames are rendered at K × K times the pixels and
/// averaged back, so a 1-sample-a-pixel path tracer becomes K² samples a pixel and its
/// error against the converged reference falls by about K (≈ 1/√samples).
#[test]
fn a_supersampled_entry_is_measured_on_frames_averaged_back_to_the_scenarios_size() {
    let root = temp_dir("supersample");
    let text = r#"
name = "supersample"
scene = "builtin:cornell-spot"
width = 16
height = 12
times_s = [0.0, 0.5]
metrics = ["rmse"]

[reference]
spp = 256

[[technique]]
name = "reference"
label = "one sample"
work = 1

[[technique]]
name = "reference"
label = "four by four"
work = 1
supersample = 4
"#;
    let scenario = Scenario::parse(text, &root.join("supersample.toml")).unwrap();
    let options = options_in(&root, true);
    let result = run(&scenario, &options, &mut Silent).unwrap();
    let rmse = |series: &str| -> f64 {
        let v: Vec<f64> = result
            .records
            .iter()
            .filter(|r| r.series == series)
            .map(|r| {
                r.metrics
                    .iter()
                    .find(|(m, _)| *m == Metric::Rmse)
                    .unwrap()
                    .1
            })
            .collect();
        assert_eq!(v.len(), 2, "{series}: one record a frame");
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (one, sixteen) = (rmse("one sample"), rmse("four by four"));
    // 16 samples a pixel: ≈ 1/4 of the error; at most 1/2 allowed for the noise of
    // 192 pixels, at least 1/8 (a frame not averaged back would fail to compare at all).
    assert!(
        sixteen < 0.5 * one && sixteen > one / 8.0,
        "RMSE {sixteen} supersampled against {one}"
    );
    // The saved frames are the scenario's size.
    let saved = options.output_dir.join("frames/four_by_four/0000.exr");
    let image = RgbImage::read(&saved).unwrap_or_else(|e| panic!("{}: {e}", saved.display()));
    assert_eq!((image.width(), image.height()), (16, 12));
    // The report says which series were supersampled, and only those.
    let files = write_report(&scenario, &result, &options).unwrap();
    let report = std::fs::read_to_string(&files.report_md).unwrap();
    let line = report
        .lines()
        .find(|l| l.starts_with("Supersampled series"))
        .unwrap_or_else(|| panic!("no supersampled line in\n{report}"));
    assert!(
        line.contains("four by four 4 × 4 (64×48 rendered)") && !line.contains("one sample"),
        "{line}"
    );
    let _ = std::fs::remove_dir_all(&root);
}
