//! The `illume` command line end to end: images with the analytic answer, split images
//! that add up, animations with one CSV row per frame, and bad input rejected with a
//! message naming the file and the key.

use crate::common::{self, illume, ok, path};
use illume_core::image::RgbImage;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    common::scratch("cli", name)
}

#[test]
fn reference_render_of_the_furnace_gives_le_over_one_minus_rho() {
    // builtin:furnace: closed sphere, ρ = 0.5, Le = 1 ⇒ every pixel converges to 2.
    let dir = scratch("furnace");
    let exr = dir.join("furnace.exr");
    let out = illume(&[
        "render",
        "builtin:furnace",
        "--technique",
        "reference",
        "--spp",
        "64",
        "--width",
        "8",
        "--height",
        "8",
        "-o",
        path(&exr),
    ]);
    ok(&out);
    let img = RgbImage::read(&exr).unwrap();
    assert_eq!((img.width(), img.height()), (8, 8));
    let m = img.mean();
    for c in m.to_array() {
        assert!((c - 2.0).abs() < 0.06, "furnace mean {m}, expected 2");
    }
}

/// `--denoise` (issue 36, goal 6) end to end: the furnace's analytic answer (2
/// everywhere) is kept and the split parts sum to the full image (the filter's noise
/// reduction: illume-reference's `denoised_reference_still_keeps_the_furnace`); only
/// the reference takes the flag (a denoised still is never a technique's ground truth).
#[test]
fn reference_denoise_keeps_the_furnace() {
    let dir = scratch("denoise");
    let exr = dir.join("den.exr");
    ok(&illume(&[
        "render",
        "builtin:furnace",
        "--technique",
        "reference",
        "--spp",
        "8",
        "--width",
        "16",
        "--height",
        "16",
        "--split",
        "--denoise",
        "-o",
        path(&exr),
    ]));
    let denoised = RgbImage::read(&exr).unwrap();
    let m = denoised.mean().x;
    assert!((m - 2.0).abs() < 0.04, "denoised mean {m}, expected 2");
    let parts = RgbImage::read(&dir.join("den_direct.exr"))
        .unwrap()
        .add(&RgbImage::read(&dir.join("den_indirect.exr")).unwrap());
    for (a, b) in parts.pixels().iter().zip(denoised.pixels()) {
        assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
    }
    let out = illume(&[
        "render",
        "builtin:furnace",
        "--technique",
        "photon_stream",
        "--width",
        "8",
        "--height",
        "8",
        "--denoise",
        "-o",
        path(&dir.join("ps.exr")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--denoise") && err.contains("photon_stream"),
        "{err}"
    );
}

#[test]
fn photon_stream_still_splits_into_direct_plus_indirect() {
    let dir = scratch("split");
    let exr = dir.join("still.exr");
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--preset",
        "deterministic",
        "--width",
        "64",
        "--height",
        "48",
        "--split",
        "-o",
        path(&exr),
    ]);
    ok(&out);
    let read = |s: &str| RgbImage::read(&dir.join(s)).unwrap();
    let (full, direct, indirect) = (
        read("still.exr"),
        read("still_direct.exr"),
        read("still_indirect.exr"),
    );
    assert_eq!((full.width(), full.height()), (64, 48));
    let mut worst = 0.0f32;
    for ((f, d), i) in full
        .pixels()
        .iter()
        .zip(direct.pixels())
        .zip(indirect.pixels())
    {
        worst = worst.max((*f - (*d + *i)).abs().max_element());
    }
    assert!(worst < 1e-4, "full − (direct + indirect) up to {worst}");
    // The spot lights the box: both parts carry light.
    assert!(direct.mean().max_element() > 0.01 && indirect.mean().max_element() > 0.01);
}

#[test]
fn animate_writes_one_frame_and_one_csv_row_per_frame() {
    let dir = scratch("animate");
    let out = illume(&[
        "animate",
        "builtin:cornell-spot",
        "--duration",
        "0.4",
        "--fps",
        "10",
        "--work-per-frame",
        "2000",
        "--width",
        "32",
        "--height",
        "24",
        "--output",
        path(&dir),
    ]);
    ok(&out);
    let frames = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            let n = e.as_ref().unwrap().file_name();
            let n = n.to_string_lossy();
            n.starts_with("frame_") && n.ends_with(".png")
        })
        .count();
    assert_eq!(frames, 5, "0.4 s at 10 fps: t = 0, 0.1, …, 0.4, both ends");
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + frames,
        "header + one row per frame:\n{csv}"
    );
}

#[test]
fn bad_input_is_named_in_the_error() {
    let dir = scratch("bad");
    // An unknown settings key: the file and the key are named, nothing is written.
    let toml = dir.join("bad.toml");
    std::fs::write(&toml, "[photon_stream]\nvsl_cont = 20\n").unwrap();
    let png = dir.join("never.png");
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--config",
        path(&toml),
        "-o",
        path(&png),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("bad.toml") && err.contains("vsl_cont"),
        "{err}"
    );
    assert!(!png.exists());
    // A missing scene file is named.
    let out = illume(&["render", path(&dir.join("nowhere.gltf")), "-o", path(&png)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("nowhere.gltf"), "{err}");
    // An unknown preset is named with the valid ones.
    let out = illume(&["render", "builtin:cornell-spot", "--preset", "fast"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("fast") && err.contains("quality"), "{err}");
    // A negative or non-finite frame cap for the window is refused before any window.
    #[cfg(feature = "view")]
    for bad in ["-1", "inf", "NaN", "lots"] {
        let out = illume(&["view", "builtin:cornell-spot", "--max-fps", bad]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "--max-fps {bad} accepted");
        assert!(err.contains("--max-fps"), "--max-fps {bad}: {err}");
    }
}

#[test]
fn a_scene_without_lights_is_lit_by_spot_from_above_and_seen_from_look_from() {
    // The Stanford bunny (PLY) has no light: black, with a warning naming the way out;
    // --spot-from-above lights it. --look-from/--look-at move the camera: looking away
    // from the bunny leaves only the background.
    let bunny = illume_scene::shared_scenes_dir().join("stanford_bunny/bun_zipper_res4.ply");
    let dir = scratch("bunny");
    let render = |name: &str, extra: &[&str]| {
        let exr = dir.join(name);
        let mut args = vec![
            "render",
            path(&bunny),
            "--preset",
            "deterministic",
            "--width",
            "48",
            "--height",
            "36",
            "-o",
            path(&exr),
        ];
        args.extend_from_slice(extra);
        let out = illume(&args);
        ok(&out);
        (
            RgbImage::read(&exr).unwrap().mean().max_element(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (unlit, err) = render("unlit.exr", &[]);
    assert_eq!(unlit, 0.0);
    assert!(err.contains("--spot-from-above"), "{err}");
    let (lit, _) = render("lit.exr", &["--spot-from-above"]);
    assert!(lit > 0.01, "lit bunny mean {lit}");
    // A sky lights it too: no warning then.
    let (sky, err) = render("sky.exr", &["--sky", "1,1,1"]);
    assert!(sky > 0.1 && !err.contains("render black"), "{sky}: {err}");
    let (away, _) = render(
        "away.exr",
        &[
            "--spot-from-above",
            "--look-from",
            "0,0.1,0.5",
            "--look-at",
            "0,0.1,5",
        ],
    );
    assert!(
        away < 0.2 * lit,
        "looking away still sees {away} (bunny {lit})"
    );
    // Impossible views and malformed points are errors that say why.
    let out = illume(&[
        "render",
        path(&bunny),
        "--look-from",
        "0.1,0.1,0.1",
        "--look-at",
        "0.1,0.1,0.1",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("the same"));
    let out = illume(&[
        "render",
        path(&bunny),
        "--look-from",
        "1,2",
        "--look-at",
        "0,0,0",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("X,Y,Z"));
}

/// The linear pixels of an EXR, for bit-for-bit comparisons.
fn pixels(p: &Path) -> Vec<[u32; 3]> {
    RgbImage::read(p)
        .unwrap()
        .pixels()
        .iter()
        .map(|v| v.to_array().map(f32::to_bits))
        .collect()
}

#[test]
fn set_reaches_any_technique_setting_and_unknown_keys_are_named() {
    let dir = scratch("set");
    let animate = |name: &str, extra: &[&str]| {
        let out_dir = dir.join(name);
        let mut args = vec![
            "animate",
            "builtin:cornell-spot",
            "--duration",
            "0.1",
            "--fps",
            "10",
            "--width",
            "40",
            "--height",
            "30",
            "--exr",
            "--output",
            path(&out_dir),
        ];
        args.extend_from_slice(extra);
        ok(&illume(&args));
        pixels(&out_dir.join("frame_00001.exr"))
    };
    // --set photon_stream.vsl_count=50 is the same run as the same key in a file (and as
    // the old --vsls 50, checked bit for bit against the binary before the change).
    let toml = dir.join("vsls.toml");
    std::fs::write(&toml, "[photon_stream]\nvsl_count = 50\n").unwrap();
    let by_set = animate("set", &["--set", "photon_stream.vsl_count=50"]);
    let by_file = animate("file", &["--config", path(&toml)]);
    let default = animate("default", &[]);
    assert_eq!(by_set, by_file);
    assert_ne!(by_set, default, "50 VSLs render like the default 100");
    // An unknown key or a wrongly typed value names the argument and the key.
    for (arg, key) in [
        ("reference.nope=1", "nope"),
        ("photon_stream.vsl_count=lots", "vsl_count"),
    ] {
        let out = illume(&[
            "render",
            "builtin:cornell-spot",
            "--technique",
            "reference",
            "--set",
            arg,
            "-o",
            path(&dir.join("never.png")),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{arg} accepted");
        assert!(err.contains(arg) && err.contains(key), "{err}");
    }
    assert!(!dir.join("never.png").exists());
}

#[test]
fn a_config_files_technique_is_honoured_unless_the_flag_says_otherwise() {
    // The README's example: `technique = "reference"` in a --config file.
    let dir = scratch("config-technique");
    let toml = dir.join("ref.toml");
    std::fs::write(&toml, "technique = \"reference\"\n[reference]\nspp = 4\n").unwrap();
    let out_png = dir.join("x.png");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "builtin:cornell-spot",
            "--config",
            path(&toml),
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            path(&out_png),
        ];
        args.extend_from_slice(extra);
        let out = illume(&args);
        ok(&out);
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = run(&[]);
    assert!(err.contains("reference 16×12"), "{err}");
    let err = run(&["--technique", "photon_stream"]);
    assert!(err.contains("photon_stream 16×12"), "{err}");
    // --spp is the reference's; a technique without such a setting warns.
    let err = run(&["--technique", "photon_stream", "--spp", "8"]);
    assert!(err.contains("--spp") && err.contains("ignored"), "{err}");
}

#[test]
fn help_lists_every_technique_and_its_presets() {
    for command in ["render", "animate"] {
        let out = illume(&[command, "--help"]);
        ok(&out);
        let help = String::from_utf8_lossy(&out.stdout);
        for name in ["reference", "photon_stream"] {
            assert!(
                help.contains(name),
                "{command} --help lacks {name}:\n{help}"
            );
        }
        assert!(
            help.contains("--preset still") && help.contains("--set"),
            "{help}"
        );
    }
}

/// `--sky R,G,B` puts a uniform sky around any scene: light through the open Cornell
/// box's front makes it brighter and bluer (the sky is blue); bad values are named.
#[test]
fn sky_flag_lights_the_scene_and_is_seen_behind_it() {
    let dir = scratch("sky");
    let render = |extra: &[&str], name: &str| {
        let exr = dir.join(name);
        let mut args = vec![
            "render",
            "builtin:cornell-spot",
            "--technique",
            "reference",
            "--spp",
            "4",
            "--width",
            "24",
            "--height",
            "18",
            "-o",
            path(&exr),
        ];
        args.extend_from_slice(extra);
        ok(&illume(&args));
        RgbImage::read(&exr).unwrap()
    };
    let dark = render(&[], "dark.exr");
    let lit = render(&["--sky", "0.5,1,2"], "lit.exr");
    assert!(
        lit.mean().x > dark.mean().x && lit.mean().z > lit.mean().x,
        "{} → {}",
        dark.mean(),
        lit.mean()
    );
    // An environment map: a uniform one of the same radiance gives the same image as
    // --sky up to noise; bad files are named.
    let env = dir.join("env.exr");
    RgbImage::filled(16, 8, illume_core::Vec3::new(0.25, 0.5, 1.0))
        .write(&env, &Default::default())
        .unwrap();
    let mapped = render(&["--envmap", path(&env), "--envmap-scale", "2"], "env.exr");
    assert!(
        ((mapped.mean() - lit.mean()) / lit.mean())
            .abs()
            .max_element()
            < 0.1,
        "{} vs {}",
        mapped.mean(),
        lit.mean()
    );
    for (file, words) in [
        ("nowhere.exr", "nowhere.exr"),
        ("lit.png", "not an HDR image"),
    ] {
        let out = illume(&[
            "render",
            "builtin:cornell-spot",
            "--envmap",
            path(&dir.join(file)),
        ]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(words), "{err}");
    }
    for bad in ["1,-1,0", "1,2", "nan,1,1"] {
        let out = illume(&["render", "builtin:cornell-spot", "--sky", bad]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--sky") && err.contains(bad), "{err}");
    }
}

/// `illume info` says which materials have a specular part and that photon_stream
/// approximates them; a Lambertian scene says so too.
#[test]
fn info_names_glossy_materials_and_the_photon_stream_caveat() {
    let run = |scene: &str| {
        let out = illume(&["info", scene]);
        ok(&out);
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let lambert = run("builtin:cornell-spot");
    assert!(
        lambert.contains("all Lambertian") && lambert.contains("sky          none"),
        "{lambert}"
    );
    // What each animation drives.
    assert!(lambert.contains("moves sphere, spot_light"), "{lambert}");
    let sphere = illume_scene::shared_scenes_dir().join("cornell_box/CornellBox-Sphere.obj");
    let glossy = run(path(&sphere));
    assert!(
        glossy.contains("specular part")
            && glossy.contains("leftSphere")
            && glossy.contains("photon_stream"),
        "{glossy}"
    );
}

/// A non-finite `--time`, or an exposure that is not a finite number of stops within
/// ±64, is an error naming the flag, not a panic or a black image (issue 14, defects 1
/// and 8).
#[test]
fn non_finite_time_is_refused() {
    for arg in ["--exposure=NaN", "--exposure=1e30", "--exposure=-100"] {
        let out = illume(&[
            "render",
            "builtin:cornell-spot",
            arg,
            "--width",
            "8",
            "--height",
            "6",
        ]);
        assert_eq!(out.status.code(), Some(2), "{arg}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("--exposure"));
    }
    for bad in ["NaN", "inf", "-inf"] {
        let arg = format!("--time={bad}");
        let out = illume(&[
            "render",
            "builtin:cornell-spot",
            &arg,
            "--width",
            "8",
            "--height",
            "6",
        ]);
        assert_eq!(
            out.status.code(),
            Some(2),
            "clap's usage error, not a panic"
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--time") && !err.contains("panicked"), "{err}");
    }
}

/// A named pipe given as a scene is refused at once instead of blocking (issue 14,
/// defect 10).
#[test]
fn a_pipe_as_scene_is_refused_without_hanging() {
    let dir = scratch("fifo");
    let fifo = dir.join("scene.obj");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success(), "mkfifo failed");
    let start = std::time::Instant::now();
    let out = illume(&["info", path(&fifo)]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("scene.obj") && err.contains("not a regular file"),
        "{err}"
    );
    // A pipe that blocked would block for ever: 60 s tells the two apart on a loaded
    // machine too (the refusal itself takes a process start).
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
}

/// Sizes and counts beyond what can be allocated are refused before anything is
/// allocated, naming the setting and the limit (issue 14, defect 6).
#[test]
fn huge_sizes_and_counts_are_refused_up_front() {
    let start = std::time::Instant::now();
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--width",
        "100000",
        "--height",
        "100000",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--width/--height") && err.contains("16384"),
        "{err}"
    );
    let dir = scratch("huge");
    let out = illume(&[
        "animate",
        "builtin:cornell-spot",
        "--duration",
        "1e9",
        "--fps",
        "1000",
        "-o",
        path(&dir),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--duration") && err.contains("1000000 frames"),
        "{err}"
    );
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--set",
        "photon_stream.vsl_count=4000000000",
        "--width",
        "8",
        "--height",
        "6",
        "-o",
        path(&dir.join("x.png")),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("vsl_count") && err.contains("1000000"),
        "{err}"
    );
    // Allocating 4 × 10⁹ lights would take far longer (or abort): 60 s tells the two
    // apart on a loaded machine too.
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
}

/// An OS error is printed once (issue 14, item 14).
#[test]
fn os_errors_are_printed_once() {
    let out = illume(&["info", "/nonexistent/scene.obj"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(err.contains("/nonexistent/scene.obj"), "{err}");
}

/// An output that cannot be written is refused before rendering (issue 14, defect 12).
#[test]
fn unwritable_outputs_fail_before_rendering() {
    let dir = scratch("bad_output");
    std::fs::write(dir.join("file.txt"), "a file, not a folder").unwrap();
    for (out, words) in [
        (dir.join("x.jpg"), ".exr (linear) or .png"),
        (dir.join("file.txt/x.png"), "cannot create the folder"),
    ] {
        let start = std::time::Instant::now();
        let run = illume(&[
            "render",
            "builtin:cornell-spot",
            "--technique",
            "reference",
            "--spp",
            "100000",
            "-o",
            path(&out),
        ]);
        assert!(!run.status.success());
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(words), "{err}");
        // 100 000 samples a pixel would take hours: 60 s tells a refusal before
        // rendering from one after it on a loaded machine too.
        assert!(
            start.elapsed().as_secs() < 60,
            "rendered first: {:?}",
            start.elapsed()
        );
    }
}

#[test]
fn a_missing_texture_is_a_warning_unless_strict() {
    let dir = scratch("strict");
    std::fs::write(
        dir.join("t.mtl"),
        "newmtl red\nKd 0.8 0.1 0.1\nmap_Kd gone.png\n",
    )
    .unwrap();
    let obj = dir.join("t.obj");
    std::fs::write(
        &obj,
        "mtllib t.mtl\nv -1 0 -1\nv 1 0 -1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl red\nf 1/1 3/3 2/2\n",
    )
    .unwrap();
    let exr = dir.join("t.exr");
    let args = [
        "render",
        path(&obj),
        "--sky",
        "1,1,1",
        "--width",
        "16",
        "--height",
        "12",
        "--preset",
        "deterministic",
        "-o",
        path(&exr),
    ];
    let out = illume(&args);
    ok(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning") && err.contains("gone.png") && err.contains("t.mtl line 3"),
        "{err}"
    );
    let _ = std::fs::remove_file(&exr);
    let mut strict = args.to_vec();
    strict.push("--strict");
    let out = illume(&strict);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("gone.png") && err.contains("t.mtl line 3"),
        "{err}"
    );
    assert!(!exr.exists(), "no image is written when loading fails");
}

/// The value of `column` in the last row of a frames.csv.
fn last_csv_value(csv: &str, column: &str) -> Option<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next()?.split(',').collect();
    let k = header.iter().position(|h| *h == column)?;
    lines.last()?.split(',').nth(k)?.parse().ok()
}

#[test]
fn selective_runs_on_its_thread_in_real_time_and_on_the_frame_thread_with_fixed_work() {
    let small = [
        "--set",
        "selective.pilots_per_group=8",
        "--set",
        "selective.ratio=4",
        "--set",
        "selective.element_count=2000",
    ];
    let realtime = scratch("selective-realtime");
    let mut args = vec![
        "animate",
        "builtin:cornell-spot",
        "--technique",
        "selective",
        "--animation",
        "move_sphere",
        "--realtime",
        "--duration",
        "0.5",
        "--width",
        "32",
        "--height",
        "24",
        "--output",
        path(&realtime),
    ];
    args.extend(small);
    let out = illume(&args);
    ok(&out);
    let csv = std::fs::read_to_string(realtime.join("frames.csv")).unwrap();
    let steps = last_csv_value(&csv, "selective.thread_steps");
    assert!(
        steps.is_some_and(|s| s > 0.0),
        "--realtime: the streaming thread took no step ({steps:?}):\n{csv}"
    );
    // The printed median frame time is the median interval of frames.csv's wall times.
    let stderr = String::from_utf8_lossy(&out.stderr);
    let printed: f64 = stderr
        .split("median frame ")
        .nth(1)
        .and_then(|r| r.split(" ms").next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no median frame time printed:\n{stderr}"));
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == "wall_s")
        .expect("wall_s column");
    let walls: Vec<f64> = lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect();
    let d: Vec<f64> = walls.windows(2).map(|w| (w[1] - w[0]) * 1e3).collect();
    assert!(
        d.len() >= 2,
        "a 0.5 s real-time run renders several frames: {walls:?}"
    );
    // A median: at least half the intervals on each side of it (frames.csv keeps µs, the
    // message 2 decimals of a ms).
    let slack = 0.006;
    let below = d.iter().filter(|&&x| x <= printed + slack).count();
    let above = d.iter().filter(|&&x| x >= printed - slack).count();
    assert!(
        2 * below >= d.len() && 2 * above >= d.len(),
        "printed median {printed} ms is not the median of frames.csv's intervals {d:?}:\n{stderr}"
    );

    let fixed = scratch("selective-fixed");
    let mut args = vec![
        "animate",
        "builtin:cornell-spot",
        "--technique",
        "selective",
        "--duration",
        "0.2",
        "--fps",
        "10",
        "--work-per-frame",
        "1000",
        "--width",
        "32",
        "--height",
        "24",
        "--output",
        path(&fixed),
    ];
    args.extend(small);
    ok(&illume(&args));
    let csv = std::fs::read_to_string(fixed.join("frames.csv")).unwrap();
    assert_eq!(
        last_csv_value(&csv, "selective.thread_steps"),
        None,
        "--work-per-frame runs no thread:\n{csv}"
    );
    assert!(last_csv_value(&csv, "selective.photons_traced").is_some_and(|p| p > 0.0));

    // An out-of-range setting is refused before anything renders, naming the key.
    let png = fixed.join("never.png");
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--technique",
        "selective",
        "--set",
        "selective.ratio=1",
        "-o",
        path(&png),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("selective.ratio"),
        "{err}"
    );
    assert!(!png.exists());
}

#[test]
fn demo_streams_its_frames_to_disk_and_leaves_a_preview() {
    let dir = scratch("demo");
    ok(&illume(&[
        "demo",
        "--duration",
        "0.6",
        "--width",
        "32",
        "--height",
        "24",
        "--output",
        path(&dir),
    ]));
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let frames = names
        .iter()
        .filter(|n| n.starts_with("frame_") && n.ends_with(".png"))
        .count();
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    assert!(frames >= 2, "{names:?}");
    assert_eq!(
        csv.lines().count(),
        1 + frames,
        "one CSV row per frame on disk"
    );
    // Every frame decodes at the requested size.
    for i in 0..frames {
        let img = image::open(dir.join(format!("frame_{i:05}.png"))).unwrap();
        assert_eq!((img.width(), img.height()), (32, 24));
    }
    assert!(
        names
            .iter()
            .any(|n| n == "preview.gif" || n == "preview.mp4"),
        "{names:?}"
    );
    assert!(
        !names
            .iter()
            .any(|n| n.contains("partial") || n.contains(".tmp")),
        "temporary files left behind: {names:?}"
    );
}

#[test]
fn animate_clears_its_own_earlier_frames_and_refuses_a_folder_it_did_not_write() {
    let dir = scratch("animate-folder");
    let run = |duration: &str| {
        illume(&[
            "animate",
            "builtin:cornell-spot",
            "--duration",
            duration,
            "--fps",
            "10",
            "--work-per-frame",
            "1000",
            "--width",
            "16",
            "--height",
            "12",
            "--output",
            path(&dir),
        ])
    };
    let frames = || {
        std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                let n = e.as_ref().unwrap().file_name();
                n.to_string_lossy().starts_with("frame_")
            })
            .count()
    };
    ok(&run("0.5"));
    assert_eq!(frames(), 6);
    // A shorter re-run leaves no stale frame of the longer one.
    ok(&run("0.2"));
    assert_eq!(
        frames(),
        3,
        "stale frames of the earlier, longer run remain"
    );
    // A file illume did not write: refused, named, and nothing is touched.
    let notes = dir.join("notes.txt");
    std::fs::write(&notes, "mine").unwrap();
    let out = run("0.1");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("notes.txt"), "{err}");
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "mine");
    assert_eq!(frames(), 3);
}

/// PNG output is exposed automatically (the log-average luminance to middle grey, one
/// exposure for the full image and its split parts), `--exposure` adds stops on top, and
/// `--exposure-mode fixed` maps radiance without it.
#[test]
fn png_exposure_is_automatic_by_default_and_fixed_on_request() {
    use illume_core::image::{ToneMap, auto_exposure_ev, to_srgb8};
    let dir = scratch("exposure");
    let render = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "render",
            "builtin:cornell-spot",
            "--technique",
            "reference",
            "--spp",
            "4",
            "--width",
            "16",
            "--height",
            "12",
            "-o",
            path(out),
        ];
        args.extend_from_slice(extra);
        ok(&illume(&args));
    };
    let exr = dir.join("linear.exr");
    render(&exr, &[]);
    let linear = RgbImage::read(&exr).unwrap();
    let auto = auto_exposure_ev(&linear).unwrap();
    assert!(auto > 0.5, "the spot-lit box is dim at exposure 0: {auto}");
    for (extra, ev) in [
        (vec![], auto),
        (vec!["--exposure=-1.5"], auto - 1.5),
        (vec!["--exposure-mode", "fixed"], 0.0),
        (vec!["--exposure-mode", "fixed", "--exposure", "2"], 2.0),
    ] {
        let png = dir.join("out.png");
        render(&png, &extra);
        let got = image::open(&png).unwrap().to_rgb8().into_raw();
        let want = to_srgb8(
            &linear,
            &ToneMap {
                exposure_ev: ev,
                ..Default::default()
            },
        );
        assert!(got == want, "{extra:?}: the PNG is not exposed at {ev} EV");
    }
}

#[test]
fn data_flag_reads_a_precomputed_file_like_the_set_key() {
    // A tiny day of sun-room (the Slurm test's settings), then one frame between two keys
    // through `--data FILE` and through `--set precomputed.data=FILE`: the same image.
    let dir = scratch("data-flag");
    // In folders that do not exist yet: `precompute` makes them, as `render -o` does.
    let day = dir.join("new/folder/day.illumepc");
    let size = ["--width", "24", "--height", "16"];
    let mut args = vec!["precompute", "builtin:sun-room", "--schedule", "uniform"];
    args.extend([
        "--from",
        "3",
        "--to",
        "15",
        "--step-min",
        "120",
        "--spp",
        "4",
        "--components",
        "4",
    ]);
    args.extend(size);
    args.extend(["--output", path(&day)]);
    let out = illume(&args);
    ok(&out);
    // stderr is a pipe here: progress comes as plain lines (a batch job's log).
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        // 3:00–15:00 every 2 h, 15:00 included.
        err.contains("precomputed keys: started, 7 to do")
            && err.contains("precomputed keys: done in"),
        "{err}"
    );
    // The sky's image (rendered once, as long as two keys or so) is a phase of its own,
    // before the keys: a long run's log is never silent.
    let sky = err.find("precomputed sky (once for the day): started, 1 to do");
    let keys = err.find("precomputed keys: started");
    assert!(
        sky.is_some() && sky < keys && err.contains("precomputed sky (once for the day): done in"),
        "{err}"
    );
    let set = format!("precomputed.data={}", path(&day));
    let render = |extra: &[&str], out: &Path| {
        let mut a = vec!["render", "builtin:sun-room", "--time", "30000"];
        a.extend(["--technique", "precomputed"]);
        a.extend(size);
        a.extend(extra);
        a.extend(["-o", path(out)]);
        illume(&a)
    };
    let by_flag = dir.join("flag.exr");
    let by_set = dir.join("set.exr");
    ok(&render(&["--data", path(&day)], &by_flag));
    ok(&render(&["--set", &set], &by_set));
    let (a, b) = (
        RgbImage::read(&by_flag).unwrap(),
        RgbImage::read(&by_set).unwrap(),
    );
    assert!(a.mean().max_element() > 0.0, "the frame is black");
    assert_eq!(a.pixels(), b.pixels(), "--data and --set give other images");

    // A missing file is an error naming it; --data with another technique is refused.
    let missing = dir.join("missing.illumepc");
    let out = render(&["--data", path(&missing)], &dir.join("x.exr"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("missing.illumepc"),
        "{err}"
    );
    let out = illume(&[
        "render",
        "builtin:sun-room",
        "--technique",
        "reference",
        "--data",
        path(&day),
        "-o",
        path(&dir.join("y.exr")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--data") && err.contains("precomputed"),
        "{err}"
    );
}

/// Output into a pipe whose reader has gone (`illume … | head -1`) ends the process
/// quietly (SIGPIPE's default action, or exit 0 if everything fitted in the pipe before
/// the reader left), never with a panic in `println!`.
#[test]
fn a_closed_pipe_ends_the_output_without_a_panic() {
    use std::process::Stdio;
    for _ in 0..3 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_illume"))
            .args(["render", "--help"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("illume starts");
        drop(child.stdout.take()); // the reader leaves before reading anything
        let out = child.wait_with_output().expect("illume ends");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !stderr.contains("panicked") && out.status.code() != Some(101),
            "{:?}: {stderr}",
            out.status
        );
    }
}

/// `render --supersample 2` at W×H is the same technique rendered at 2W×2H with each 2×2
/// block averaged (a box filter), for every image it writes (photon_stream's `still`
/// preset: the same image every run). A size past the renderer's limit once multiplied is
/// refused naming the flag.
#[test]
fn supersample_renders_larger_and_averages_blocks() {
    let dir = common::scratch("cli", "supersample");
    let (small, big) = (dir.join("ss.exr"), dir.join("big.exr"));
    for (out, size, k) in [(&small, ("32", "24"), "2"), (&big, ("64", "48"), "1")] {
        ok(&illume(&[
            "render",
            "builtin:cornell-spot",
            "--width",
            size.0,
            "--height",
            size.1,
            "--supersample",
            k,
            "--split",
            "-o",
            path(out),
        ]));
    }
    for suffix in ["", "_direct", "_indirect"] {
        let read = |p: &Path| {
            let name = format!("{}{suffix}.exr", p.file_stem().unwrap().to_str().unwrap());
            RgbImage::read(&dir.join(name)).unwrap()
        };
        let (a, b) = (read(&small), read(&big).box_downsample(2));
        assert_eq!((a.width(), a.height()), (32, 24), "{suffix}");
        for (x, y) in a.pixels().iter().zip(b.pixels()) {
            assert!(
                (*x - *y).abs().max_element() <= 1e-6 * (1.0 + y.max_element()),
                "{suffix}"
            );
        }
    }
    let out = illume(&[
        "render",
        "builtin:cornell-spot",
        "--width",
        "5000",
        "--height",
        "4000",
        "--supersample",
        "4",
        "-o",
        path(&dir.join("x.exr")),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--supersample 4") && stderr.contains("16384"),
        "{stderr}"
    );
}

/// In real time the frame writer runs below every normal thread (`SCHED_IDLE`), so that
/// encoding the frames never takes a core from the renderer; offline it keeps nice 19
/// (`frames::WriterPriority`). Read from the kernel while the run goes on: the policy in
/// field 41 of `/proc/PID/task/TID/stat` (5: `SCHED_IDLE`, 0: `SCHED_OTHER`) and the
/// nice value in field 19.
#[cfg(target_os = "linux")]
#[test]
fn the_frame_writer_runs_below_every_thread_in_real_time() {
    // The last (policy, nice) seen of the writer thread within 10 s, polled until it is
    // `want` (the thread may be seen before it lowered itself).
    let policy_and_nice = |realtime: bool, want: (u32, i32)| -> Option<(u32, i32)> {
        let out = scratch(if realtime {
            "writer-realtime"
        } else {
            "writer-offline"
        });
        let mut args = vec![
            "animate",
            "builtin:cornell-spot",
            "--technique",
            "photon_stream",
            "--width",
            "64",
            "--height",
            "48",
            "--duration",
            "3",
            "--output",
            path(&out),
        ];
        if realtime {
            args.push("--realtime");
        } else {
            args.extend(["--fps", "100"]);
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_illume"))
            .args(&args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let tasks = PathBuf::from(format!("/proc/{}/task", child.id()));
        let read = || -> Option<(u32, i32)> {
            let writer = std::fs::read_dir(&tasks).ok()?.flatten().find(|t| {
                std::fs::read_to_string(t.path().join("comm"))
                    .is_ok_and(|c| c.trim() == "frame writer")
            })?;
            let stat = std::fs::read_to_string(writer.path().join("stat")).ok()?;
            // Field 2 (the name) is in parentheses; fields 3, 4, … follow, split on
            // spaces: field n is rest[n − 3].
            let rest: Vec<&str> = stat.rsplit_once(") ")?.1.split(' ').collect();
            Some((rest[41 - 3].parse().ok()?, rest[19 - 3].parse().ok()?))
        };
        let mut seen = None;
        for _ in 0..1000 {
            seen = read().or(seen);
            if seen == Some(want) {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        let _ = child.kill();
        let _ = child.wait();
        seen
    };
    let seen = policy_and_nice(true, (5, 0));
    assert!(
        seen.is_some_and(|(policy, _)| policy == 5),
        "real time: the writer is not SCHED_IDLE (policy, nice: {seen:?})"
    );
    let seen = policy_and_nice(false, (0, 19));
    assert_eq!(seen, Some((0, 19)), "offline: not SCHED_OTHER at nice 19");
}
