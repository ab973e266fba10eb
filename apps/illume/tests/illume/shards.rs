//! `--shard K/N` from the command line: sharded `animate` frames gathered by `--collect`
//! equal the unsharded run's bit for bit; techniques (or sequences) whose frames build
//! on the frames before are refused; the adaptive precompute run level by level in
//! shards equals the unsharded file; `bench --shard` fills the reference cache.

use crate::common::{self, illume};
use std::path::{Path, PathBuf};
use std::process::Output;

/// A fresh empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    common::scratch("shards", name)
}

fn ok(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "illume failed: {stderr}");
    stderr
}

fn fails(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "illume should have failed: {stderr}");
    stderr
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every `frame_*` file of `dir`, by name, with its bytes.
fn frames(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("frame_")
        })
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    v.sort();
    v
}

/// cornell-spot's `move`: the sphere and the spot light move in every frame.
fn animate_args<'a>(out: &'a Path, technique: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "animate",
        "builtin:cornell-spot",
        "--animation",
        "move",
        "--technique",
        technique,
        "--duration",
        "0.6",
        "--fps",
        "10",
        "--work-per-frame",
        "2",
        "--width",
        "24",
        "--height",
        "16",
        "--exr",
        "--output",
        path(out),
    ];
    v.extend_from_slice(extra);
    v
}

#[test]
fn sharded_animate_frames_equal_the_unsharded_ones() {
    let root = scratch("animate");
    let whole = root.join("whole");
    ok(&illume(&animate_args(&whole, "reference", &[])));
    let sharded = root.join("sharded");
    for k in 0..3 {
        let shard = format!("{k}/3");
        let err = ok(&illume(&animate_args(
            &sharded,
            "reference",
            &["--shard", &shard],
        )));
        assert!(err.contains(&format!("shard {k}/3")), "{err}");
    }
    // Before the collect: only linear frames and the shards' tables.
    assert!(!sharded.join("frame_00000.png").exists());
    assert!(sharded.join("frames_1_of_3.csv").is_file());
    // A collect that expects more shards names the missing table.
    let err = fails(&illume(&animate_args(
        &sharded,
        "reference",
        &["--collect", "4"],
    )));
    assert!(err.contains("frames_0_of_4.csv"), "{err}");
    ok(&illume(&animate_args(
        &sharded,
        "reference",
        &["--collect", "3"],
    )));

    let (a, b) = (frames(&whole), frames(&sharded));
    assert_eq!(a.len(), 14, "7 frames (0.6 s at 10 fps), PNG and EXR");
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            x == y,
            "{name} differs between the sharded and unsharded runs"
        );
    }
    let csv = std::fs::read_to_string(sharded.join("frames.csv")).unwrap();
    let first: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(first, ["0", "1", "2", "3", "4", "5", "6"], "{csv}");
    assert!(
        !sharded.join("frames_0_of_3.csv").exists(),
        "shard tables removed"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn animate_shards_are_refused_where_frames_build_on_earlier_ones() {
    let root = scratch("animate-refused");
    // Photon streaming keeps its photons from frame to frame.
    let err = fails(&illume(&animate_args(
        &root,
        "photon_stream",
        &["--shard", "0/2"],
    )));
    assert!(
        err.contains("photon_stream") && err.contains("carries state"),
        "{err}"
    );
    // The reference averages over still frames: the furnace has no animation, so
    // frame 1 builds on frame 0.
    let out = root.join("still");
    let err = fails(&illume(&[
        "animate",
        "builtin:furnace",
        "--technique",
        "reference",
        "--duration",
        "0.2",
        "--fps",
        "10",
        "--width",
        "8",
        "--height",
        "8",
        "--shard",
        "1/2",
        "-o",
        path(&out),
    ]));
    assert!(
        err.contains("frame 1") && err.contains("no change"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn adaptive_precompute_in_level_shards_equals_the_unsharded_file() {
    let root = scratch("precompute");
    let p = |name: &str| root.join(name).to_str().unwrap().to_owned();
    // verify_midpoint splits this day at this size (Yee at exposure 64, 32 spp).
    let common = [
        "builtin:sun-room",
        "--from",
        "7",
        "--to",
        "19",
        "--step-min",
        "90",
        "--spp",
        "32",
        "--components",
        "3",
        "--width",
        "64",
        "--height",
        "48",
        "--set",
        "precomputed.exposure=64",
        "--set",
        "precomputed.verify_midpoint=true",
    ];
    let precompute = |extra: &[&str]| {
        let mut args = vec!["precompute"];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        illume(&args)
    };
    ok(&precompute(&[
        "--schedule",
        "adaptive",
        "-o",
        &p("whole.illumepc"),
    ]));

    // Clear errors: a level with the uniform schedule, a shard of the adaptive one
    // without its level, a level ≥ 1 without the levels before.
    let err = fails(&precompute(&[
        "--schedule",
        "uniform",
        "--level",
        "0",
        "-o",
        &p("x"),
    ]));
    assert!(
        err.contains("--level is for the adaptive schedule"),
        "{err}"
    );
    let err = fails(&precompute(&[
        "--schedule",
        "adaptive",
        "--shard",
        "0/2",
        "-o",
        &p("x"),
    ]));
    assert!(err.contains("needs --level"), "{err}");
    let err = fails(&precompute(&[
        "--schedule",
        "adaptive",
        "--level",
        "1",
        "-o",
        &p("x"),
    ]));
    assert!(
        err.contains("levels 0–0") && err.contains("--previous"),
        "{err}"
    );

    let mut previous: Option<String> = None;
    let mut finished = false;
    for level in 0..8 {
        let mut parts = Vec::new();
        for k in 0..2 {
            let part = p(&format!("l{level}_{k}.illumepc"));
            let (lv, sh) = (level.to_string(), format!("{k}/2"));
            let mut extra = vec!["--level", &lv, "--shard", &sh, "-o", &part];
            extra.extend(["--schedule", "adaptive"]);
            if let Some(prev) = &previous {
                extra.extend(["--previous", prev.as_str()]);
            }
            ok(&precompute(&extra));
            parts.push(part);
        }
        let merged = p(&format!("levels{level}.illumepc"));
        let mut args = vec!["precompute", "merge"];
        args.extend(parts.iter().map(String::as_str));
        if let Some(prev) = &previous {
            args.extend(["--previous", prev.as_str()]);
        }
        args.extend(["-o", &merged]);
        let err = ok(&illume(&args));
        let info = illume(&["precompute", "info", &merged]);
        let info = String::from_utf8_lossy(&info.stdout).into_owned();
        if info.contains("kind        pca") {
            finished = true;
            previous = Some(merged);
            break;
        }
        assert!(
            err.contains(&format!("next: --level {}", level + 1)),
            "{err}"
        );
        assert!(info.contains("kind        levels"), "{info}");
        previous = Some(merged);
    }
    assert!(finished, "the schedule did not end");
    let merged = std::fs::read(previous.unwrap()).unwrap();
    let whole = std::fs::read(root.join("whole.illumepc")).unwrap();
    assert!(
        merged == whole,
        "the level-by-level shards differ from the unsharded file"
    );
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn bench_shards_fill_the_reference_cache() {
    let root = scratch("bench");
    let scenario = root.join("tiny.toml");
    std::fs::write(
        &scenario,
        r#"
name = "tiny"
scene = "builtin:cornell-spot"
animation = "move_light"
width = 8
height = 6
times_s = [0.0, 0.5, 1.0]
metrics = ["rmse"]

[reference]
spp = 4

[[technique]]
name = "reference"
work = 1
"#,
    )
    .unwrap();
    let cache = root.join("cache");
    for k in 0..2 {
        let shard = format!("{k}/2");
        let err = ok(&illume(&[
            "bench",
            path(&scenario),
            "--cache",
            path(&cache),
            "--shard",
            &shard,
        ]));
        let expected = if k == 0 { "2 of 3" } else { "1 of 3" };
        assert!(err.contains(expected), "{err}");
    }
    let names: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".exr"))
        .collect();
    let halves = names.iter().filter(|n| n.ends_with(".half.exr")).count();
    assert_eq!(
        (names.len() - halves, halves),
        (3, 3),
        "images and their halves"
    );
    let out = root.join("report");
    let err = ok(&illume(&[
        "bench",
        path(&scenario),
        "--cache",
        path(&cache),
        "-o",
        path(&out),
    ]));
    assert!(err.contains("3 from the cache, 0 rendered"), "{err}");
    let _ = std::fs::remove_dir_all(&root);
}
