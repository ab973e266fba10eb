//! Command-line values: sizes, sample counts, times, exposures, camera points, skies,
//! environment maps, outputs.

use crate::corpus::texture::png;
use crate::corpus::{Case, Expect, RENDER_OUTPUT, error, warning};

/// `illume render builtin:furnace` (reference, 1 spp, 8×8 unless `args` say otherwise)
/// with `args`, writing `{dir}/out/render.png` unless `args` give `-o`.
fn render(name: &str, args: &[&str], expect: Expect) -> Case {
    let output = format!("{{dir}}/{RENDER_OUTPUT}");
    let mut all = vec!["render", "builtin:furnace"];
    for (flag, default) in [
        ("--technique", "reference"),
        ("--spp", "1"),
        ("--width", "8"),
        ("--height", "8"),
    ] {
        if !args.contains(&flag) {
            all.extend([flag, default]);
        }
    }
    if !args.contains(&"-o") {
        all.extend(["-o", output.as_str()]);
    }
    all.extend_from_slice(args);
    Case::new("cli", name).run(&all, expect)
}

/// A small OpenEXR file whose header claims `w × h` pixels, consistently (data and
/// display windows, `chunkCount` and an offset table with one entry per chunk, all
/// pointing at the one real chunk of a 2×2 image): a reader that believed it would
/// allocate w·h pixels (120 GB for 100000²) before decoding a single chunk. `(2, 2)`
/// gives the valid image.
fn exr_claiming(w: i32, h: i32) -> Vec<u8> {
    use illume_core::image::{RgbImage, ToneMap};
    let path = std::env::temp_dir().join(format!("illume-corpus-{}.exr", std::process::id()));
    RgbImage::black(2, 2)
        .write(&path, &ToneMap::default())
        .expect("an EXR is written");
    let b = std::fs::read(&path).expect("the EXR is read back");
    let _ = std::fs::remove_file(&path);
    // Attributes: name\0 type\0 size (i32) value, up to a NUL; then the offset table.
    let mut attributes = Vec::new();
    let mut at = 8;
    while b[at] != 0 {
        let name_end = at + b[at..].iter().position(|&c| c == 0).expect("a name");
        let type_end = name_end
            + 1
            + b[name_end + 1..]
                .iter()
                .position(|&c| c == 0)
                .expect("a type");
        let size = i32::from_le_bytes(b[type_end + 1..type_end + 5].try_into().unwrap()) as usize;
        attributes.push((b[at..name_end].to_vec(), type_end + 5));
        at = type_end + 5 + size;
    }
    let header_end = at + 1;
    let value = |name: &[u8]| {
        attributes
            .iter()
            .find(|(n, _)| n == name)
            .map(|&(_, v)| v)
            .expect("a standard EXR attribute")
    };
    let first_chunk =
        u64::from_le_bytes(b[header_end..header_end + 8].try_into().unwrap()) as usize;
    // Scanlines per chunk of the file's compression (none, RLE, ZIPS: 1; ZIP: 16; …).
    let lines = match b[value(b"compression")] {
        0..=2 => 1,
        3 | 5 => 16,
        _ => 32,
    };
    let chunks = (h as usize).div_ceil(lines);
    let mut out = b[..header_end].to_vec();
    for window in [value(b"dataWindow"), value(b"displayWindow")] {
        out[window + 8..window + 12].copy_from_slice(&(w - 1).to_le_bytes());
        out[window + 12..window + 16].copy_from_slice(&(h - 1).to_le_bytes());
    }
    let count = value(b"chunkCount");
    out[count..count + 4].copy_from_slice(&(chunks as i32).to_le_bytes());
    let chunk_at = (header_end + 8 * chunks) as u64;
    for _ in 0..chunks {
        out.extend_from_slice(&chunk_at.to_le_bytes());
    }
    out.extend_from_slice(&b[first_chunk..]);
    out
}

/// `illume animate builtin:furnace` (0.1 s at 10 fps, 8×8, into `{dir}/out`) with
/// `args` (defaults are added only for the flags `args` lacks: clap refuses a repeat).
fn animate(name: &str, args: &[&str], expect: Expect) -> Case {
    let mut all = vec!["animate", "builtin:furnace"];
    all.extend_from_slice(args);
    for (flag, default) in [
        ("--duration", "0.1"),
        ("--fps", "10"),
        ("--width", "8"),
        ("--height", "8"),
        ("--output", "{dir}/out"),
    ] {
        if !args.contains(&flag) {
            all.extend([flag, default]);
        }
    }
    Case::new("cli", name).run(&all, expect)
}

/// `illume precompute builtin:sun-room` (uniform keys, 8×8, 1 spp, into
/// `{dir}/out/x.illumepc`) with `args`.
fn precompute(name: &str, args: &[&str], expect: Expect) -> Case {
    let mut all = vec![
        "precompute",
        "builtin:sun-room",
        "--width",
        "8",
        "--height",
        "8",
        "--output",
        "{dir}/out/x.illumepc",
        "--spp",
        "1",
        "--schedule",
        "uniform",
    ];
    all.extend_from_slice(args);
    Case::new("cli", name).run(&all, expect)
}

/// The header text of [`illumepc`] as a shard's `partial` file (no PCA components).
fn partial(header: String) -> String {
    header
        .replace("kind = \"pca\"", "kind = \"partial\"")
        .replace("components = 1", "components = 0")
}

/// `illume precompute merge {dir}/x.illumepc` (`bytes`) into `{dir}/out/m.illumepc`.
fn merge_file(name: &str, bytes: &[u8], expect: Expect) -> Case {
    Case::new("cli", name)
        .file("x.illumepc", bytes.to_vec())
        .run(
            &[
                "precompute",
                "merge",
                "{dir}/x.illumepc",
                "--output",
                "{dir}/out/m.illumepc",
            ],
            expect,
        )
}

/// `illume render builtin:sun-room --technique precomputed` reading `{dir}/x.illumepc`
/// (`bytes`).
fn precomputed_file(name: &str, bytes: &[u8], expect: Expect) -> Case {
    render(
        name,
        &[
            "--technique",
            "precomputed",
            "--set",
            "precomputed.data={dir}/x.illumepc",
        ],
        expect,
    )
    .file("x.illumepc", bytes.to_vec())
    .runs_replaced("builtin:furnace", "builtin:sun-room")
}

/// FNV-1a 64, as the `.illumepc` format checksums its header and sections.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// An `.illumepc` file (format version 1) with correct checksums whose keys are at
/// `hours` (TOML numbers, `nan` allowed) and whose one section `mean.r` holds `values`
/// (none: no section): only the reader's field checks can refuse it.
fn illumepc(hours: &[&str], values: &[f32]) -> Vec<u8> {
    illumepc_edited(hours, values, |h| h)
}

/// [`illumepc`] with its header text changed by `edit` before the checksum is taken.
fn illumepc_edited(hours: &[&str], values: &[f32], edit: impl Fn(String) -> String) -> Vec<u8> {
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let sections = if values.is_empty() {
        "[]".to_owned()
    } else {
        format!(
            "[{{ name = \"mean.r\", format = \"f32\", values = {}, fnv1a64 = \"{:016x}\" }}]",
            values.len(),
            fnv1a64(&data)
        )
    };
    let mut header = format!(
        "kind = \"pca\"\nscene_source = \"builtin:sun-room\"\nscene_fingerprint = \"0000000000000000\"\n\
         domain = \"screen\"\nwidth = 8\nheight = 8\nchannels = 3\n\
         camera = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.8]\n\
         exposure = 1.0\nshard = [0, 1]\ncomponents = 1\ncolour = \"per-channel\"\n\
         eigenvalues = [[1.0]]\nsections = {sections}\n[settings]\n[sun]\n"
    );
    for h in hours {
        header.push_str(&format!("[[keys]]\nhours = {h}\nlevel = 0\ndark = false\n"));
    }
    let header = edit(header);
    let mut out = b"ILLUMEPC".to_vec();
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(&fnv1a64(header.as_bytes()).to_le_bytes());
    out.extend_from_slice(&data);
    out
}

/// A 16×16 linear EXR whose pixel (0, 0) is `value` in every channel (the rest 0.5).
fn exr_with(value: f32) -> Vec<u8> {
    use illume_core::Rgb;
    use illume_core::image::{RgbImage, ToneMap};
    let mut image = RgbImage::filled(16, 16, Rgb::splat(0.5));
    image.pixels_mut()[0] = Rgb::splat(value);
    let path = std::env::temp_dir().join(format!(
        "illume-corpus-{}-{}.exr",
        std::process::id(),
        value.to_bits()
    ));
    image
        .write(&path, &ToneMap::default())
        .expect("an EXR is written");
    let bytes = std::fs::read(&path).expect("the EXR is read back");
    let _ = std::fs::remove_file(&path);
    bytes
}

/// Every command-line case.
pub fn cases() -> Vec<Case> {
    let envmap = |name: &str, bytes: Vec<u8>, expect: Expect| {
        render(name, &["--envmap", "{dir}/sky.exr"], expect).file("sky.exr", bytes)
    };
    vec![
        render("valid", &[], Expect::Success),
        render("width_zero", &["--width", "0"], error(&["--width", "1×1"])),
        render(
            "height_zero",
            &["--height", "0"],
            error(&["--height", "1×1"]),
        ),
        render(
            "width_100000",
            &["--width", "100000"],
            error(&["--width", "16384"]),
        ),
        render("width_negative", &["--width", "-8"], error(&["--width"])),
        render(
            "width_beyond_u32",
            &["--width", "4294967296"],
            error(&["--width"]),
        ),
        render(
            "size_beyond_the_memory_cap",
            &["--width", "16384", "--height", "16384"],
            error(&["--width", "MiB"]),
        ),
        render(
            "size_within_memory_beyond_the_cap",
            &[
                "--width",
                "4096",
                "--height",
                "4096",
                "--technique",
                "photon_stream",
            ],
            error(&["--width", "MiB"]),
        ),
        render("spp_zero", &["--spp", "0"], error(&["--spp", "0"])),
        render("spp_negative", &["--spp", "-1"], error(&["--spp"])),
        render("time_nan", &["--time", "nan"], error(&["--time", "finite"])),
        render("time_inf", &["--time=inf"], error(&["--time", "finite"])),
        render("time_negative", &["--time", "-1"], Expect::Success),
        render(
            "exposure_1e30",
            &["--exposure", "1e30"],
            error(&["--exposure", "64"]),
        ),
        render(
            "exposure_nan",
            &["--exposure", "NaN"],
            error(&["--exposure", "finite"]),
        ),
        render("seed_negative", &["--seed", "-1"], error(&["--seed"])),
        render(
            "look_from_nan",
            &["--look-from", "nan,0,0", "--look-at", "0,0,0"],
            error(&["--look-from", "finite"]),
        ),
        render(
            "look_from_two_numbers",
            &["--look-from", "1,2", "--look-at", "0,0,0"],
            error(&["--look-from", "X,Y,Z"]),
        ),
        render(
            "look_from_3e38",
            &["--look-from", "3e38,0,0", "--look-at", "0,0,0"],
            error(&["--look-from", "1e18"]),
        ),
        render(
            "look_from_equals_look_at",
            &["--look-from", "1,1,1", "--look-at", "1,1,1"],
            error(&["--look-from", "same"]),
        ),
        render(
            "look_from_without_look_at",
            &["--look-from", "1,1,1"],
            error(&["--look-at"]),
        ),
        render("sky_nan", &["--sky", "nan,0,0"], error(&["--sky"])),
        render(
            "sky_negative",
            &["--sky", "-1,0,0"],
            error(&["--sky", "≥ 0"]),
        ),
        render("sky_1e39", &["--sky", "1e39,1,1"], error(&["--sky"])),
        render(
            "sky_1e36",
            &["--sky", "1e36,1,1"],
            error(&["light power", "sky"]),
        ),
        render(
            "envmap_missing",
            &["--envmap", "{dir}/sky.exr"],
            error(&["sky.exr", "No such file"]),
        ),
        envmap(
            "envmap_zero_bytes",
            Vec::new(),
            error(&["sky.exr", "environment map"]),
        ),
        envmap(
            "envmap_junk",
            crate::corpus::obj::junk(5000, 19),
            error(&["sky.exr", "environment map"]),
        ),
        envmap(
            "envmap_exr_bomb",
            exr_claiming(100_000, 100_000),
            error(&["sky.exr", "100000×100000"]),
        ),
        envmap("envmap_exr_valid", exr_claiming(2, 2), Expect::Success),
        render(
            "envmap_png",
            &["--envmap", "{dir}/sky.png"],
            error(&["sky.png", "HDR"]),
        )
        .file("sky.png", png(4, 2)),
        render(
            "envmap_scale_nan",
            &["--envmap", "{dir}/sky.exr", "--envmap-scale", "nan"],
            error(&["sky.exr", "scale"]),
        ),
        render(
            "envmap_pipe",
            &["--envmap", "{dir}/sky.exr"],
            error(&["sky.exr", "not a regular file"]),
        )
        .fifo("sky.exr"),
        render(
            "technique_unknown",
            &["--technique", "magic"],
            error(&["--technique", "magic"]),
        ),
        render(
            "preset_unknown",
            &["--preset", "fastest"],
            error(&["--preset", "fastest"]),
        ),
        render(
            "animation_unknown",
            &["--animation", "dance"],
            error(&["dance"]),
        ),
        render(
            "output_unknown_extension",
            &["-o", "{dir}/out/render.jpg"],
            error(&["render.jpg", ".png"]),
        ),
        render(
            "output_without_extension",
            &["-o", "{dir}/out/render"],
            error(&["out/render", ".png"]),
        ),
        render(
            "output_is_a_folder",
            &["-o", "{dir}/out/render.png"],
            error(&["render.png"]),
        )
        .dir("out/render.png"),
        render(
            "output_under_a_file",
            &["-o", "{dir}/out/file/render.png"],
            error(&["out/file"]),
        )
        .dir("out")
        .file("out/file", "a file, not a folder"),
        render(
            "output_in_a_read_only_folder",
            &["-o", "/proc/illume-corpus.png"],
            error(&["/proc/illume-corpus.png"]),
        ),
        render(
            "scene_builtin_unknown",
            &[],
            error(&["builtin:nope", "cornell-spot"]),
        )
        .runs_replaced("builtin:furnace", "builtin:nope"),
        render(
            "scene_unknown_extension",
            &[],
            error(&["x.fbx", "unknown scene format"]),
        )
        .runs_replaced("builtin:furnace", "{dir}/x.fbx")
        .file("x.fbx", "Kaydara FBX Binary"),
        animate("animate_fps_nan", &["--fps", "nan"], error(&["--fps"])),
        // Radiance caching's default mode plans the whole timeline: real-time frames
        // come at times not known in advance.
        animate(
            "radiance_cache_interpolated_realtime",
            &["--technique", "radiance_cache", "--realtime"],
            error(&["radiance_cache.temporal", "--realtime"]),
        ),
        animate(
            "radiance_cache_reuse_realtime",
            &[
                "--technique",
                "radiance_cache",
                "--realtime",
                "--set",
                "radiance_cache.temporal=reuse",
                "--set",
                "radiance_cache.theta_strata=4",
                "--set",
                "radiance_cache.phi_strata=4",
            ],
            Expect::Success,
        ),
        animate("animate_fps_negative", &["--fps", "-5"], error(&["--fps"])),
        animate(
            "animate_duration_negative",
            &["--duration", "-1"],
            error(&["--duration"]),
        ),
        animate(
            "animate_too_many_frames",
            &["--fps", "1e9", "--duration", "1e9"],
            error(&["--fps", "1000000"]),
        ),
        animate(
            "animate_vsls_4e9",
            &["--set", "photon_stream.vsl_count=4000000000"],
            error(&["vsl_count"]),
        ),
        animate(
            "animate_work_per_frame_negative",
            &["--work-per-frame", "-1"],
            error(&["--work-per-frame"]),
        ),
        animate("animate_output_is_a_file", &[], error(&["out"])).file("out", "a file"),
        Case::new("cli", "compare_zero_byte_images")
            .file("a.exr", Vec::new())
            .file("b.exr", Vec::new())
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["a.exr"]),
            ),
        Case::new("cli", "compare_truncated_png")
            .file("a.png", png(16, 16)[..40].to_vec())
            .file("b.png", png(16, 16))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.png"],
                error(&["a.png"]),
            ),
        Case::new("cli", "compare_exr_bomb")
            .file("a.exr", exr_claiming(100_000, 100_000))
            .file("b.exr", exr_claiming(2, 2))
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["a.exr", "100000×100000"]),
            ),
        // Issue 38: a PNG header within the decoder's own limit but beyond illume's as
        // linear RGB is refused on its header, saying the limit.
        Case::new("cli", "compare_png_header_claims_10000_squared")
            .file(
                "a.png",
                crate::corpus::texture::png_claiming(10_000, 10_000),
            )
            .file("b.png", png(2, 2))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.png"],
                error(&["a.png", "10000×10000", "1024 MiB"]),
            ),
        Case::new("cli", "compare_different_sizes")
            .file("a.png", png(16, 16))
            .file("b.png", png(8, 8))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.png"],
                error(&["16", "8"]),
            ),
        // --- issue 38 ---
        animate(
            "animate_work_per_frame_zero",
            &["--technique", "reference", "--work-per-frame", "0"],
            error(&["--work-per-frame 0", "spp_per_frame"]),
        ),
        animate(
            "animate_work_per_frame_u64_max",
            &[
                "--technique",
                "reference",
                "--work-per-frame",
                "18446744073709551615",
            ],
            error(&["--work-per-frame 18446744073709551615", "4294967295"]),
        ),
        animate(
            "animate_over_user_files",
            &[],
            error(&["out", "frame_00000.png", "frames.csv", "preview.mp4"]),
        )
        .file("out/preview.mp4", "a user's film")
        .file("out/frames.csv", "a user's table\n")
        .file("out/frame_00000.png", png(8, 8)),
        animate(
            "animate_over_user_gif_and_shard_csv",
            &[],
            error(&["out", "frames_0_of_2.csv", "preview.gif"]),
        )
        .file("out/preview.gif", "a user's gif")
        .file("out/frames_0_of_2.csv", "a user's table\n"),
        animate(
            "animate_collect_over_user_frame",
            &["--collect", "2"],
            error(&["out", "frame_00050.png"]),
        )
        .file("out/frame_00050.png", png(8, 8)),
        // Issue 38, fifth round: a whole precompute, PCA included, fits the corpus's
        // address-space cap. faer's x86 product reserved twice the L3 size (600 MiB on a
        // 300 MiB-L3 Xeon) in every thread that multiplied, and the PCA aborted with
        // `memory allocation of 629145600 bytes failed` after rendering its keys.
        precompute("precompute_pca_under_the_memory_cap", &[], Expect::Success).dir("out"),
        precompute(
            "precompute_step_min_1e-9",
            &["--step-min", "1e-9"],
            error(&["step_min", "86400"]),
        ),
        // Issue 38: keys this machine cannot hold for the PCA (289 cube keys of 3000-pixel
        // faces, hundreds of GiB) are refused before the first is rendered, saying why.
        precompute(
            "precompute_keys_beyond_memory",
            &["--domain", "cube", "--set", "precomputed.cube_face=3000"],
            error(&["x.illumepc", "289 keys", "3000×18000", "MiB available"]),
        ),
        // A face beyond the cube's cap (six faces within the atlas's 2²⁶ texels).
        precompute(
            "precompute_cube_face_beyond_the_cap",
            &["--domain", "cube", "--set", "precomputed.cube_face=4096"],
            error(&["precomputed.cube_face", "4096", "3344"]),
        ),
        precompute(
            "precompute_output_is_a_user_file",
            &[],
            error(&["x.illumepc", "not an .illumepc file"]),
        )
        .file("out/x.illumepc", "my notes"),
        precompute(
            "precompute_sky_3e38",
            &["--sky", "3e38,1,1"],
            error(&["--sky", "light power"]),
        ),
        precomputed_file(
            "illumepc_key_time_nan",
            &illumepc(&["6.0", "nan"], &[]),
            error(&["x.illumepc", "keys[1].hours", "NaN"]),
        ),
        precomputed_file(
            "illumepc_key_times_equal",
            &illumepc(&["6.0", "6.0"], &[]),
            error(&["x.illumepc", "keys[1].hours", "strictly increasing"]),
        ),
        precomputed_file(
            "illumepc_key_times_unsorted",
            &illumepc(&["12.0", "6.0"], &[]),
            error(&["x.illumepc", "keys[1].hours", "6"]),
        ),
        precomputed_file(
            "illumepc_value_nan",
            &illumepc(&["6.0", "12.0"], &[f32::NAN, 1.0]),
            error(&["x.illumepc", "section mean.r value 0", "NaN"]),
        ),
        precomputed_file(
            "illumepc_value_inf",
            &illumepc(&["6.0", "12.0"], &[1.0, f32::INFINITY]),
            error(&["x.illumepc", "section mean.r value 1", "inf"]),
        ),
        // Issue 38: what a header makes a merge allocate is bounded on read. A shard
        // count of 4·10⁹ (a 32 GB table of shards) and dark keys of 16384² pixels (3 GiB
        // of black each) are refused before anything is allocated.
        merge_file(
            "illumepc_merge_shard_count_4e9",
            &illumepc_edited(&["6.0", "12.0"], &[], |h| {
                partial(h)
                    .replace("shard = [0, 1]", "shard = [0, 4000000000]")
                    .replace("dark = false", "dark = true")
            }),
            error(&["x.illumepc", "shard", "86400"]),
        ),
        merge_file(
            "illumepc_merge_dark_keys_16384_squared",
            &illumepc_edited(&["6.0", "12.0", "18.0"], &[], |h| {
                partial(h)
                    .replace("width = 8\nheight = 8", "width = 16384\nheight = 16384")
                    .replace("[settings]\n", "[settings]\nschedule = \"uniform\"\n")
                    .replace("dark = false", "dark = true")
            }),
            error(&["x.illumepc", "3 keys of 16384×16384", "MiB available"]),
        ),
        merge_file(
            "illumepc_screen_65536_wide",
            &illumepc_edited(&["6.0"], &[], |h| {
                partial(h).replace("width = 8", "width = 65536")
            }),
            error(&["x.illumepc", "width/height", "65536×8", "16384"]),
        ),
        Case::new("cli", "compare_metric_empty")
            .file("a.png", png(8, 8))
            .file("b.png", png(8, 8))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.png", "--metric", ""],
                error(&["--metric", "at least one"]),
            ),
        Case::new("cli", "compare_infinite_pixel")
            .file("a.exr", exr_with(f32::INFINITY))
            .file("b.exr", exr_with(1.0))
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["a.exr", "pixel (0, 0)", "inf"]),
            ),
        Case::new("cli", "compare_nan_pixel")
            .file("a.exr", exr_with(1.0))
            .file("b.exr", exr_with(f32::NAN))
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["b.exr", "pixel (0, 0)", "NaN"]),
            ),
        Case::new("cli", "compare_png_with_exr")
            .file("a.png", png(16, 16))
            .file("b.exr", exr_with(1.0))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.exr"],
                warning(&["a.png", "b.exr", "linear", "tone-mapped"]),
            ),
        Case::new("cli", "compare_error_map_exr")
            .file("a.exr", exr_with(1.0))
            .file("b.exr", exr_with(1.0))
            .run(
                &[
                    "compare",
                    "{dir}/a.exr",
                    "{dir}/b.exr",
                    "--error-map",
                    "{dir}/out/map.exr",
                ],
                error(&["--error-map", "map.exr", ".png"]),
            ),
        Case::new("cli", "compare_error_map_folder")
            .file("a.exr", exr_with(1.0))
            .file("b.exr", exr_with(1.0))
            .dir("out/map.png")
            .run(
                &[
                    "compare",
                    "{dir}/a.exr",
                    "{dir}/b.exr",
                    "--error-map",
                    "{dir}/out/map.png",
                ],
                error(&["--error-map", "map.png"]),
            ),
        render(
            "envmap_png_named_hdr",
            &["--envmap", "{dir}/sky.hdr"],
            error(&["sky.hdr", "not a Radiance HDR", "Png"]),
        )
        .file("sky.hdr", png(8, 8)),
        Case::new("cli", "compare_empty_exr_says_empty")
            .file("a.exr", Vec::new())
            .file("b.exr", exr_with(1.0))
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["a.exr", "empty file"]),
            ),
        Case::new("cli", "compare_truncated_exr_says_truncated")
            .file("a.exr", exr_with(1.0)[..60].to_vec())
            .file("b.exr", exr_with(1.0))
            .run(
                &["compare", "{dir}/a.exr", "{dir}/b.exr"],
                error(&["a.exr", "truncated"]),
            ),
        Case::new("cli", "convert_valid")
            .file("a.exr", exr_with(1.0))
            .run(
                &[
                    "convert",
                    "{dir}/a.exr",
                    "{dir}/out/a.png",
                    "--exposure",
                    "-1",
                ],
                Expect::Success,
            ),
        Case::new("cli", "convert_nan_pixel")
            .file("a.exr", exr_with(f32::NAN))
            .run(
                &["convert", "{dir}/a.exr", "{dir}/out/a.png"],
                error(&["a.exr", "pixel (0, 0)", "not finite"]),
            ),
        Case::new("cli", "convert_output_jpg")
            .file("a.exr", exr_with(1.0))
            .run(
                &["convert", "{dir}/a.exr", "{dir}/out/a.jpg"],
                error(&["a.jpg", ".png"]),
            ),
        Case::new("cli", "compare_pipe")
            .fifo("a.png")
            .file("b.png", png(8, 8))
            .run(
                &["compare", "{dir}/a.png", "{dir}/b.png"],
                error(&["a.png", "not a regular file"]),
            ),
    ]
}

impl Case {
    /// Every run's argument `from` replaced by `to`.
    fn runs_replaced(mut self, from: &str, to: &str) -> Self {
        for r in &mut self.runs {
            for a in &mut r.args {
                if a == from {
                    *a = to.to_owned();
                }
            }
        }
        self
    }
}
