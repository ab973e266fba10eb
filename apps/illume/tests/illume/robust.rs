//! Issue 38 end to end: no user file lost (`animate`, `--collect`, `precompute -o`),
//! `--work-per-frame` checked as its setting is, `--sky` on a precomputed round trip,
//! `convert` with render's tone curve, `--help` and `info` on first use.

use crate::common::{self, illume, ok, path};
use illume_core::image::RgbImage;
use std::path::{Path, PathBuf};
use std::process::Output;

fn scratch(name: &str) -> PathBuf {
    common::scratch("robust", name)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `illume animate builtin:cornell-spot` (0.1 s at 10 fps, 8×8) into `dir` with `extra`.
fn animate(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "animate",
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--duration",
        "0.1",
        "--fps",
        "10",
        "--width",
        "8",
        "--height",
        "8",
        "--output",
        path(dir),
    ];
    args.extend_from_slice(extra);
    illume(&args)
}

/// The must-show of issue 38: a user's `preview.mp4`, `frames.csv` and
/// `frame_00000.png` in the output folder — names `animate` itself writes — make it
/// refuse, naming them, and all three stay byte-identical. (Before: deleted.)
#[test]
fn animate_into_a_folder_of_user_files_refuses_and_keeps_them_byte_identical() {
    let dir = scratch("user-files");
    let png = {
        let p = dir.join("made.png");
        RgbImage::black(4, 4)
            .write(&p, &Default::default())
            .unwrap();
        let bytes = std::fs::read(&p).unwrap();
        std::fs::remove_file(&p).unwrap();
        bytes
    };
    let files: [(&str, Vec<u8>); 3] = [
        (
            "preview.mp4",
            b"\x00\x00\x00\x18ftypmp42 a user's film".to_vec(),
        ),
        ("frames.csv", b"frame,note\n0,my own table\n".to_vec()),
        ("frame_00000.png", png),
    ];
    for (name, bytes) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    for extra in [&[][..], &["--shard", "0/2"][..], &["--collect", "2"][..]] {
        let out = animate(&dir, extra);
        let err = stderr(&out);
        assert!(!out.status.success(), "{extra:?}: succeeded: {err}");
        for (name, bytes) in &files {
            assert_eq!(
                &std::fs::read(dir.join(name)).unwrap(),
                bytes,
                "{extra:?}: {name} changed"
            );
        }
        if extra.is_empty() {
            for (name, _) in &files {
                assert!(err.contains(name), "{extra:?}: {name} not named: {err}");
            }
        }
        let count = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(count, 3, "{extra:?}: files were added or removed");
    }
}

/// What `animate` wrote it may clear on the next run; a file of its own that the user
/// changed since (same name, other bytes) is refused and kept.
#[test]
fn animate_clears_what_it_wrote_and_keeps_what_the_user_changed() {
    let dir = scratch("own-files");
    ok(&animate(&dir, &[]));
    ok(&animate(&dir, &[]));
    let csv = dir.join("frames.csv");
    std::thread::sleep(std::time::Duration::from_millis(20));
    std::fs::write(&csv, "frame,edited by hand\n").unwrap();
    let out = animate(&dir, &[]);
    assert!(!out.status.success() && stderr(&out).contains("frames.csv"));
    assert_eq!(
        std::fs::read_to_string(&csv).unwrap(),
        "frame,edited by hand\n"
    );
}

/// `precompute -o` overwrites an earlier `.illumepc`, never anything else.
#[test]
fn precompute_output_over_a_user_file_is_refused_before_rendering() {
    let dir = scratch("precompute-o");
    let target = dir.join("day.illumepc");
    std::fs::write(&target, "not a precompute").unwrap();
    let out = illume(&[
        "precompute",
        "builtin:sun-room",
        "--schedule",
        "uniform",
        "--step-min",
        "360",
        "--spp",
        "1",
        "--width",
        "8",
        "--height",
        "8",
        "--output",
        path(&target),
    ]);
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("day.illumepc") && err.contains("not an .illumepc"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(&target).unwrap(),
        "not a precompute"
    );
}

/// `--work-per-frame` goes through the technique setting's own check: 0 is refused as
/// `reference.spp_per_frame = 0` is (before: one sample per pixel, silently), and an
/// amount the setting cannot hold as `--set` refuses it (before: a run that never ends).
#[test]
fn work_per_frame_is_checked_as_its_setting_is() {
    let dir = scratch("work");
    let out = animate(&dir, &["--work-per-frame", "0"]);
    let err = stderr(&out);
    assert!(
        !out.status.success()
            && err.contains("--work-per-frame 0")
            && err.contains("spp_per_frame"),
        "{err}"
    );
    let out = animate(&dir, &["--work-per-frame", "18446744073709551615"]);
    let err = stderr(&out);
    assert!(!out.status.success() && err.contains("4294967295"), "{err}");
    let out = animate(&dir, &["--set", "reference.spp_per_frame=0"]);
    assert!(!out.status.success(), "the setting itself accepts 0");
    ok(&animate(&dir, &["--work-per-frame", "2"]));
}

/// "Precompute and render with the same --sky" (docs): on builtin:sun-room the render
/// used to ignore --sky (the sun path rescaled the scene's own sky) and call the file
/// "another scene". Now `--sky` replaces the sky the sun scales: a file made with a sky
/// renders with it, without it is another scene, and the reference sees the sky.
#[test]
fn sky_flag_round_trips_through_a_precomputed_file() {
    let dir = scratch("sky-round-trip");
    let day = dir.join("day.illumepc");
    let size = ["--width", "16", "--height", "12"];
    let sky = ["--sky", "0.2,0.4,0.9"];
    let mut args = vec!["precompute", "builtin:sun-room", "--schedule", "uniform"];
    args.extend([
        "--from",
        "3",
        "--to",
        "15",
        "--step-min",
        "240",
        "--spp",
        "1",
    ]);
    args.extend(["--components", "2"]);
    args.extend(size);
    args.extend(sky);
    args.extend(["--output", path(&day)]);
    ok(&illume(&args));
    let render = |technique: &[&str], extra: &[&str], out: &Path| {
        let mut a = vec![
            "render",
            "builtin:sun-room",
            "--time",
            "30000",
            "--spp",
            "1",
        ];
        a.extend(technique);
        a.extend(size);
        a.extend(extra);
        a.extend(["-o", path(out)]);
        illume(&a)
    };
    let precomputed = ["--technique", "precomputed", "--data", path(&day)];
    let with = dir.join("with.exr");
    ok(&render(&precomputed, &sky, &with));
    assert!(RgbImage::read(&with).unwrap().mean().max_element() > 0.0);
    let out = render(&precomputed, &[], &dir.join("without.exr"));
    assert!(
        !out.status.success() && stderr(&out).contains("another scene"),
        "{}",
        stderr(&out)
    );
    // The sky reaches the renderer on a scene with a sun path.
    let reference = ["--technique", "reference"];
    let (a, b) = (dir.join("ref-sky.exr"), dir.join("ref.exr"));
    ok(&render(&reference, &["--sky", "5,5,5", "--seed", "1"], &a));
    ok(&render(&reference, &["--seed", "1"], &b));
    let (a, b) = (RgbImage::read(&a).unwrap(), RgbImage::read(&b).unwrap());
    assert!(
        a.mean().max_element() > 1.01 * b.mean().max_element(),
        "--sky is ignored on a scene with a sun: {} vs {}",
        a.mean(),
        b.mean()
    );
}

/// `--sky-from` on the command line: another range of hours with the file's sky writes
/// the file a fresh precompute writes, byte for byte; a file rendered with other samples
/// is refused by name and setting, before any key, and nothing is written.
#[test]
fn sky_from_reuses_a_files_sky_and_refuses_one_that_differs() {
    let dir = scratch("sky-from");
    let run = |from: &str, to: &str, spp: &str, extra: &[&str], out: &Path| {
        let mut args = vec!["precompute", "builtin:sun-room", "--schedule", "uniform"];
        args.extend(["--from", from, "--to", to, "--step-min", "120"]);
        args.extend([
            "--spp",
            spp,
            "--components",
            "2",
            "--width",
            "16",
            "--height",
            "12",
        ]);
        args.extend(extra);
        args.extend(["--output", path(out)]);
        illume(&args)
    };
    let morning = dir.join("morning.illumepc");
    ok(&run("6", "10", "2", &[], &morning));
    let (fresh, reused) = (dir.join("fresh.illumepc"), dir.join("reused.illumepc"));
    ok(&run("12", "16", "2", &[], &fresh));
    let out = run("12", "16", "2", &["--sky-from", path(&morning)], &reused);
    ok(&out);
    assert!(stderr(&out).contains("sky: from"), "{}", stderr(&out));
    assert!(
        std::fs::read(&fresh).unwrap() == std::fs::read(&reused).unwrap(),
        "the file made with --sky-from differs from the fresh one"
    );
    let refused = dir.join("refused.illumepc");
    let out = run("12", "16", "4", &["--sky-from", path(&morning)], &refused);
    let err = stderr(&out);
    assert!(
        !out.status.success()
            && err.contains("morning.illumepc")
            && err.contains("spp (4 here, 2 in the file)"),
        "{err}"
    );
    assert!(!refused.exists(), "a refused precompute wrote its output");
    let out = run(
        "12",
        "16",
        "2",
        &["--sky-from", path(&morning), "--shard", "0/2"],
        &refused,
    );
    assert!(
        !out.status.success() && stderr(&out).contains("--shard"),
        "{}",
        stderr(&out)
    );
}

/// `convert` gives the PNG `render` writes for the same image (the same automatic
/// exposure, curve and encoding), with `--exposure` on top.
#[test]
fn convert_gives_the_png_render_writes() {
    let dir = scratch("convert");
    let base = [
        "render",
        "builtin:cornell-spot",
        "--technique",
        "reference",
        "--spp",
        "2",
        "--width",
        "16",
        "--height",
        "12",
    ];
    let exr = dir.join("a.exr");
    let png = dir.join("a.png");
    for (out, extra) in [(&exr, "0"), (&png, "0")] {
        let mut a = base.to_vec();
        a.extend(["--exposure", extra, "-o", path(out)]);
        ok(&illume(&a));
    }
    let converted = dir.join("c.png");
    ok(&illume(&["convert", path(&exr), path(&converted)]));
    let pixels = |p: &Path| image::open(p).unwrap().to_rgb8().into_raw();
    assert_eq!(
        pixels(&converted),
        pixels(&png),
        "convert differs from render's PNG"
    );
    let brighter = dir.join("b.png");
    ok(&illume(&[
        "convert",
        path(&exr),
        path(&brighter),
        "--exposure",
        "1",
    ]));
    let sum = |p: &Path| pixels(p).iter().map(|&v| v as u64).sum::<u64>();
    assert!(
        sum(&brighter) > sum(&converted),
        "--exposure 1 is not brighter"
    );
}

/// `--help` names every subcommand in its first line, `view` and `precompute` included
/// (before: "render, animate, info, compare, bench, demo").
#[test]
fn help_names_every_subcommand() {
    let out = illume(&["--help"]);
    ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    let first = text.lines().next().unwrap_or_default();
    let commands: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|&c| c != "help")
        .collect();
    assert!(
        commands.contains(&"precompute") && commands.contains(&"convert"),
        "{text}"
    );
    for c in &commands {
        assert!(first.contains(c), "--help's first line lacks {c}: {first}");
    }
}

/// `info` speaks of the file's own format: no "glTF" for OBJ or PLY.
#[test]
fn info_names_the_files_own_format() {
    let dir = scratch("info");
    let obj = dir.join("q.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let ply = dir.join("q.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    for (file, word) in [(&obj, "OBJ"), (&ply, "PLY")] {
        let out = illume(&["info", path(file)]);
        ok(&out);
        let text = String::from_utf8_lossy(&out.stdout);
        let units = text.lines().find(|l| l.starts_with("units")).unwrap_or("");
        assert!(
            units.contains(word) && !units.contains("glTF light"),
            "{file:?}: {units}"
        );
    }
}

/// Small OpenEXR files found by fuzzing (`read_exr`, 2026-11-28) whose headers claim
/// images of about 1 GB: the decoder allocated that much before finding their blocks
/// wrong, so under a memory limit (`ulimit -v`, as batch jobs have) `convert` aborted
/// (exit 134, "memory allocation failed"). Now each is refused before the allocation,
/// exit 1 with the file named, under a 512 MiB address-space limit.
#[cfg(target_os = "linux")]
#[test]
fn exr_files_claiming_a_gigabyte_are_refused_under_a_memory_limit() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../crates/illume-core/tests/data");
    let out_dir = scratch("exr-limit");
    for name in [
        "exr_short_of_its_blocks.exr",
        "exr_blocks_outside_the_image.exr",
    ] {
        let input = data.join(name);
        let script = format!(
            "ulimit -v 524288; exec '{}' convert '{}' '{}'",
            env!("CARGO_BIN_EXE_illume"),
            path(&input),
            path(&out_dir.join("out.png"))
        );
        let out = std::process::Command::new("sh")
            .args(["-c", &script])
            .output()
            .expect("sh runs");
        let err = stderr(&out);
        assert_eq!(
            out.status.code(),
            Some(1),
            "{name}: {:?}\n{err}",
            out.status
        );
        assert!(err.contains(name), "{name}: {err}");
        assert!(
            !out_dir.join("out.png").exists(),
            "{name}: an image was written"
        );
    }
}
