//! The commands behind `docs/reproductions.md` and `docs/bench.md` cannot rot (issue 35):
//! every shipped scenario runs end to end as a miniature (`illume bench --miniature`),
//! and every scenario file the docs name exists.

use crate::common::{illume, ok, path, scratch};
use illume_bench::Scenario;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root (this crate is `apps/illume`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every `scenarios/*.toml`, sorted.
fn shipped_scenarios() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("scenarios"))
        .expect("the scenarios folder")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

/// Splits one line of the bench's `results.csv` (fields with a comma are quoted).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                fields.last_mut().unwrap().push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(String::new()),
            _ => fields.last_mut().unwrap().push(c),
        }
    }
    fields
}

#[test]
fn csv_fields_splits_quoted_labels() {
    assert_eq!(
        csv_fields(r#""a, b",x,,"say ""hi""""#),
        ["a, b", "x", "", r#"say "hi""#]
    );
}

/// `illume precompute` of the file `scenarios/day_sponza.toml` reads, at toy sizes (the
/// scenario's header gives the full command): two keys, one sample per texel.
fn precompute_day_sponza(work: &Path) {
    let sponza = illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    let out = illume(&[
        "precompute",
        path(&sponza),
        "--domain",
        "atlas",
        "--sky",
        "10,12,15",
        "--set",
        "precomputed.atlas_density=0.05",
        "--set",
        "precomputed.probe_spacing=4",
        "--set",
        "precomputed.exposure=0.02",
        "--schedule",
        "uniform",
        "--from",
        "7",
        "--to",
        "19",
        "--step-min",
        "720",
        "--spp",
        "1",
        "--output",
        path(&work.join("out/day_sponza.illumepc")),
    ]);
    ok(&out);
}

/// Every shipped scenario, run as `illume bench SCENARIO --miniature` from a folder of
/// its own (so `out/…` paths in scenarios resolve there): it succeeds, says it is a
/// miniature, and its `results.csv` holds every technique entry's series with one row
/// per frame and a finite, non-negative error on every measured frame. A scenario whose
/// scene, settings or edits no longer load fails here, not in a user's hands.
#[test]
fn every_shipped_scenario_runs_as_a_miniature() {
    let work = scratch("reproductions", "miniature");
    std::fs::create_dir_all(work.join("out")).unwrap();
    precompute_day_sponza(&work);
    let files = shipped_scenarios();
    assert!(
        files.len() >= 19,
        "{} scenarios found in scenarios/",
        files.len()
    );
    for file in &files {
        let name = file.file_stem().unwrap().to_str().unwrap();
        let scenario = Scenario::load(file)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .miniature();
        let report = work.join(name);
        let out = Command::new(env!("CARGO_BIN_EXE_illume"))
            .current_dir(&work)
            .args(["bench", path(file), "--miniature", "--output"])
            .arg(&report)
            .arg("--cache")
            .arg(work.join("cache"))
            .output()
            .expect("the illume binary runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{name}: {stderr}");
        assert!(stderr.contains("miniature"), "{name}: {stderr}");

        let csv = std::fs::read_to_string(report.join("results.csv"))
            .unwrap_or_else(|e| panic!("{name}: results.csv: {e}"));
        let mut lines = csv.lines();
        let header = csv_fields(lines.next().unwrap());
        let column = |title: &str| {
            header
                .iter()
                .position(|h| h == title)
                .unwrap_or_else(|| panic!("{name}: no `{title}` column in {header:?}"))
        };
        let (series, frame) = (column("series"), column("frame"));
        let error = column(&scenario.error_metric.to_string());
        let rows: Vec<Vec<String>> = lines.map(csv_fields).collect();
        let frames = scenario.frame_times().len();
        let measured = scenario.measured_frames(frames);
        for spec in &scenario.techniques {
            let label = spec.label();
            let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[series] == label).collect();
            assert_eq!(mine.len(), frames, "{name}: rows of series `{label}`");
            for r in mine {
                let f: usize = r[frame].parse().unwrap();
                if measured[f] {
                    let e: f64 = r[error]
                        .parse()
                        .unwrap_or_else(|_| panic!("{name}: `{label}` frame {f}: {:?}", r[error]));
                    assert!(
                        e.is_finite() && e >= 0.0,
                        "{name}: `{label}` frame {f}: {e}"
                    );
                }
            }
        }
    }
}

/// Every `scenarios/….toml` that the README and the docs name (brace lists such as
/// `scenarios/selective_{sphere,cube}.toml` expanded) is a shipped scenario.
#[test]
fn every_scenario_the_docs_name_exists() {
    let mut docs = vec![root().join("README.md")];
    for dir in ["docs", "docs/techniques", "docs/benchmarks"] {
        for e in std::fs::read_dir(root().join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "md") {
                docs.push(p);
            }
        }
    }
    let mut named = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for (at, _) in text.match_indices("scenarios/") {
            let rest = &text[at + "scenarios/".len()..];
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || "_{},.".contains(c)))
                .unwrap_or(rest.len());
            let Some(stem) = rest[..end].strip_suffix(".toml") else {
                continue; // the folder itself, or another file
            };
            for file in expand_braces(stem) {
                named += 1;
                let p = root().join("scenarios").join(format!("{file}.toml"));
                assert!(
                    p.is_file(),
                    "{} names scenarios/{file}.toml, which does not exist",
                    doc.display()
                );
            }
        }
    }
    assert!(named >= 10, "only {named} scenario names found in the docs");
}

/// `a_{b,c}` → `a_b`, `a_c` (one brace group, as the docs write them).
fn expand_braces(text: &str) -> Vec<String> {
    match (text.find('{'), text.find('}')) {
        (Some(open), Some(close)) if open < close => text[open + 1..close]
            .split(',')
            .map(|part| format!("{}{part}{}", &text[..open], &text[close + 1..]))
            .collect(),
        _ => vec![text.to_string()],
    }
}
