//! TOML configuration files (`illume render --config`) and bench scenarios
//! (`illume bench`): syntax, unknown keys, wrong types, NaN, out-of-range values.

use crate::corpus::{Case, Expect, RENDER_OUTPUT, error};

/// A `config` case running `illume render builtin:furnace FLAG VALUE` (`--config FILE`,
/// `--set TABLE.KEY=VALUE`); `c` is changed first (the file added).
fn render_with(
    name: &str,
    flag: &str,
    value: &str,
    c: impl FnOnce(Case) -> Case,
    expect: Expect,
) -> Case {
    let output = format!("{{dir}}/{RENDER_OUTPUT}");
    c(Case::new("config", name)).run(
        &["render", "builtin:furnace", flag, value, "-o", &output],
        expect,
    )
}

/// `illume render builtin:furnace --config {dir}/c.toml`, `c.toml` being `text` (its
/// own technique and size).
fn config(name: &str, text: &str, expect: Expect) -> Case {
    render_with(
        name,
        "--config",
        "{dir}/c.toml",
        |c| c.file("c.toml", text),
        expect,
    )
}

/// `illume render builtin:furnace --config {dir}/c.toml`, `c.toml` made by `make` (a
/// folder, a pipe, a link, nothing).
fn config_file(name: &str, make: impl FnOnce(Case) -> Case, expect: Expect) -> Case {
    render_with(name, "--config", "{dir}/c.toml", make, expect)
}

/// `illume render builtin:furnace --set ARGUMENT`.
fn set(name: &str, argument: &str, expect: Expect) -> Case {
    render_with(name, "--set", argument, |c| c, expect)
}

/// A small valid configuration with `extra` appended.
fn small(extra: &str) -> String {
    format!(
        "technique = \"reference\"\n[render]\nwidth = 8\nheight = 8\n[reference]\nspp = 1\n{extra}"
    )
}

/// `illume bench {dir}/s.toml` (report and cache inside the case's folder).
fn scenario(name: &str, text: &str, expect: Expect) -> Case {
    Case::new("scenario", name).file("s.toml", text).run(
        &[
            "bench",
            "{dir}/s.toml",
            "--output",
            "{dir}/out",
            "--cache",
            "{dir}/out/cache",
        ],
        expect,
    )
}

/// The valid scenario of [`scene_text`] with one `[[edit]]` of `fields` added.
fn edit(name: &str, fields: &str, expect: Expect) -> Case {
    scenario(
        name,
        &format!("{}[[edit]]\n{fields}", scene_text("", "")),
        expect,
    )
}

/// The valid scenario of [`scene_text`] with `from` replaced by `to`.
fn scenario_replacing(name: &str, from: &str, to: &str, expect: Expect) -> Case {
    let text = scene_text("", "");
    assert!(text.contains(from), "{name}: the scenario has no '{from}'");
    scenario(name, &text.replace(from, to), expect)
}

/// A valid scenario with `top` added to its top level and `technique` to its technique
/// table.
fn scene_text(top: &str, technique: &str) -> String {
    format!(
        "scene = \"builtin:furnace\"\nwidth = 8\nheight = 8\nduration_s = 0.1\nfps = 10\n{top}\n\
         [reference]\nspp = 1\nequal_time = false\n\
         [[technique]]\nname = \"reference\"\nsamples = 1\n{technique}\n"
    )
}

/// Every configuration and scenario case.
pub fn cases() -> Vec<Case> {
    let c = "c.toml";
    let s = "s.toml";
    let mut out = vec![
        config("valid", &small(""), Expect::Success),
        config(
            "syntax_error",
            "[render\nwidth = 8\n",
            error(&[c, "line 1"]),
        ),
        config(
            "unterminated_string",
            "technique = \"refer\n",
            error(&[c, "line 1"]),
        ),
        config(
            "unknown_top_level_key",
            &small("colour = 1\n"),
            error(&[c, "colour"]),
        ),
        config(
            "unknown_render_key",
            "[render]\nwidht = 8\n",
            error(&[c, "widht"]),
        ),
        config(
            "unknown_technique_key",
            "[reference]\nssp = 4\n",
            error(&[c, "ssp"]),
        ),
        config("unknown_table", "[magic]\nx = 1\n", error(&[c, "magic"])),
        config(
            "unknown_technique",
            "technique = \"magic\"\n",
            error(&[c, "magic"]),
        ),
        config(
            "width_is_a_string",
            "[render]\nwidth = \"wide\"\n",
            error(&[c, "width"]),
        ),
        config(
            "width_negative",
            "[render]\nwidth = -8\n",
            error(&[c, "width"]),
        ),
        config(
            "width_beyond_u64",
            "[render]\nwidth = 99999999999999999999\n",
            error(&[c, "width"]),
        ),
        config(
            "width_zero",
            "technique = \"reference\"\n[render]\nwidth = 0\nheight = 8\n",
            error(&[c, "width"]),
        ),
        config(
            "width_100000",
            "technique = \"reference\"\n[render]\nwidth = 100000\nheight = 8\n",
            error(&[c, "width", "16384"]),
        ),
        config(
            "spp_zero",
            &small("").replace("spp = 1", "spp = 0"),
            error(&[c, "spp"]),
        ),
        config(
            "max_depth_zero",
            &small("max_depth = 0\n"),
            error(&[c, "max_depth"]),
        ),
        config(
            "area_light_samples_zero",
            &small("").replace("height = 8\n", "height = 8\narea_light_samples = 0\n"),
            error(&[c, "area_light_samples"]),
        ),
        config(
            "shadow_map_resolution_zero",
            &small("[render.shadow_maps]\nresolution = 0\n"),
            error(&[c, "resolution"]),
        ),
        config(
            "shadow_map_bias_nan",
            &small("[render.shadow_maps]\ndepth_bias_texels = nan\n"),
            error(&[c, "depth_bias_texels"]),
        ),
        config(
            "shadow_map_bias_inf",
            &small("[render.shadow_maps]\nslope_bias_texels = inf\n"),
            error(&[c, "slope_bias_texels"]),
        ),
        config(
            "photon_stream_nan",
            "[render]\nwidth = 8\nheight = 8\n[photon_stream]\noversampling = nan\n",
            error(&[c, "oversampling"]),
        ),
        config(
            "photon_stream_vsls_4e9",
            "[render]\nwidth = 8\nheight = 8\n[photon_stream]\nvsl_count = 4000000000\n",
            error(&[c, "vsl_count"]),
        ),
        // Issue 38: a type error inside a technique's table names the table, the key and
        // the value on the error's first line (not only in the parser's excerpt).
        config(
            "photon_stream_vsl_count_a_string",
            "[render]\nwidth = 8\nheight = 8\n[photon_stream]\nvsl_count = \"x\"\n",
            error(&[c, "photon_stream.vsl_count = \"x\"", "line 5"]),
        ),
        config(
            "shadow_map_resolution_a_string",
            &small("[render.shadow_maps]\nresolution = \"high\"\n"),
            error(&[c, "render.shadow_maps.resolution = \"high\""]),
        ),
        config(
            "photon_stream_share_above_one",
            "[render]\nwidth = 8\nheight = 8\n[photon_stream]\nstream_share = 1.5\n",
            error(&[c, "stream_share"]),
        ),
        config(
            "photon_stream_share_nan",
            "[render]\nwidth = 8\nheight = 8\n[photon_stream]\nstream_share = nan\n",
            error(&[c, "stream_share"]),
        ),
        config(
            "selective_nan",
            "technique = \"selective\"\n[render]\nwidth = 8\nheight = 8\n[selective]\nmasking_contrast_threshold = nan\n",
            error(&[c, "masking_contrast_threshold"]),
        ),
        config(
            "radiance_cache_nan",
            "[render]\nwidth = 8\nheight = 8\n[radiance_cache]\naccuracy = nan\n",
            error(&[c, "accuracy"]),
        ),
        config(
            "empty_file",
            "[render]\nwidth = 8\nheight = 8\n",
            Expect::Success,
        ),
        config(
            "binary_junk",
            &String::from_utf8_lossy(&crate::corpus::obj::junk(2048, 13)),
            error(&[c]),
        ),
        config("table_as_value", "render = 5\n", error(&[c, "render"])),
        config_file("missing_file", |c| c, error(&[c, "No such file"])),
        config_file(
            "folder",
            |c| c.dir("c.toml"),
            error(&[c, "not a regular file"]),
        ),
        config_file(
            "pipe",
            |c| c.fifo("c.toml"),
            error(&[c, "not a regular file"]),
        ),
        config_file(
            "dev_zero",
            |c| c.link("c.toml", "/dev/zero"),
            error(&[c, "not a regular file"]),
        ),
        set(
            "set_unknown_key",
            "render.widht=8",
            error(&["--set", "widht"]),
        ),
        set(
            "set_nan",
            "render.shadow_maps.pcf_texels=nan",
            error(&["--set", "pcf_texels"]),
        ),
        set(
            "set_without_equals",
            "render.width",
            error(&["--set", "TABLE.KEY=VALUE"]),
        ),
    ];
    out.extend([
        scenario("syntax_error", "scene = \n", error(&[s, "line 1"])),
        scenario(
            "unknown_key",
            &scene_text("colour = 1", ""),
            error(&[s, "colour"]),
        ),
        scenario(
            "unknown_technique_key",
            &scene_text("", "budgett_ms = 1"),
            error(&[s, "budgett_ms"]),
        ),
        scenario_replacing(
            "wrong_type",
            "width = 8",
            "width = \"8\"",
            error(&[s, "width"]),
        ),
        scenario_replacing(
            "no_scene",
            "scene = \"builtin:furnace\"\n",
            "",
            error(&[s, "scene"]),
        ),
        scenario(
            "no_technique",
            "scene = \"builtin:furnace\"\nduration_s = 1\nfps = 1\n",
            error(&[s, "technique"]),
        ),
        scenario_replacing(
            "fps_1e9",
            "fps = 10",
            "fps = 1e9",
            error(&[s, "duration_s/fps", "1000000"]),
        ),
        scenario_replacing(
            "duration_1e9",
            "duration_s = 0.1",
            "duration_s = 1e9",
            error(&[s, "duration_s/fps", "1000000"]),
        ),
        scenario_replacing("fps_nan", "fps = 10", "fps = nan", error(&[s, "fps"])),
        scenario_replacing("fps_zero", "fps = 10", "fps = 0", error(&[s, "fps"])),
        scenario_replacing("fps_negative", "fps = 10", "fps = -5", error(&[s, "fps"])),
        scenario_replacing(
            "duration_inf",
            "duration_s = 0.1",
            "duration_s = inf",
            error(&[s, "duration_s"]),
        ),
        scenario(
            "start_nan",
            &scene_text("start_s = nan", ""),
            error(&[s, "start_s"]),
        ),
        scenario(
            "times_not_increasing",
            &scene_text("times_s = [0.0, 0.5, 0.5]", "")
                .replace("duration_s = 0.1\nfps = 10\n", ""),
            error(&[s, "times_s"]),
        ),
        scenario(
            "times_nan",
            &scene_text("times_s = [0.0, nan]", "").replace("duration_s = 0.1\nfps = 10\n", ""),
            error(&[s, "times_s"]),
        ),
        scenario(
            "times_and_fps",
            &scene_text("times_s = [0.0]", ""),
            error(&[s, "times_s"]),
        ),
        scenario_replacing("width_zero", "width = 8", "width = 0", error(&[s, "width"])),
        scenario_replacing(
            "width_100000",
            "width = 8",
            "width = 100000",
            error(&[s, "width", "16384"]),
        ),
        scenario_replacing(
            "reference_spp_zero",
            "spp = 1",
            "spp = 0",
            error(&[s, "reference.spp"]),
        ),
        scenario(
            "latency_threshold_nan",
            &scene_text("latency_threshold = nan", ""),
            error(&[s, "latency_threshold"]),
        ),
        scenario(
            "budget_nan",
            &scene_text("", "budget_ms = nan"),
            error(&[s, "budget_ms"]),
        ),
        scenario(
            "budget_negative",
            &scene_text("", "budget_ms = -1.0"),
            error(&[s, "budget_ms"]),
        ),
        scenario(
            "budget_1e300",
            &scene_text("", "budget_ms = 1e300"),
            error(&[s, "budget_ms"]),
        ),
        scenario_replacing(
            "work_zero",
            "samples = 1",
            "samples = 0",
            error(&[s, "work"]),
        ),
        scenario_replacing(
            "technique_unknown",
            "name = \"reference\"",
            "name = \"magic\"",
            error(&[s, "magic"]),
        ),
        scenario(
            "technique_settings_unknown_key",
            &scene_text("", "[technique.settings]\nspp_per_fram = 2"),
            error(&[s, "spp_per_fram"]),
        ),
        // Issue 38: the same in a bench scenario's technique settings, which reach the
        // configuration as a table (no position): the key is named.
        scenario_replacing(
            "technique_settings_wrong_type",
            "name = \"reference\"\nsamples = 1",
            "name = \"photon_stream\"\n[technique.settings]\nvsl_count = \"x\"",
            error(&[s, "technique[0]", "vsl_count = \"x\""]),
        ),
        scenario(
            "render_table_wrong_type",
            &scene_text("[render]\narea_light_samples = \"many\"", ""),
            error(&[s, "render.area_light_samples = \"many\""]),
        ),
        scenario_replacing(
            "technique_settings_nan",
            "name = \"reference\"\nsamples = 1",
            "name = \"photon_stream\"\n[technique.settings]\noversampling = nan",
            error(&[s, "oversampling"]),
        ),
        scenario(
            "render_table_width",
            &scene_text("[render]\nwidth = 9", ""),
            error(&[s, "render.width"]),
        ),
        scenario(
            "render_table_unknown_key",
            &scene_text("[render]\nbogus = 9", ""),
            error(&[s, "bogus"]),
        ),
        scenario(
            "reference_frames_out_of_range",
            &scene_text("reference_frames = [5]", ""),
            error(&[s, "reference_frames"]),
        ),
        edit(
            "edit_nan",
            "at_s = 0.0\ninstance = \"sphere\"\ntranslation = [nan, 0, 0]\n",
            error(&[s, "edit[0]", "finite"]),
        ),
        edit(
            "edit_without_target",
            "at_s = 0.0\ntranslation = [0, 0, 0]\n",
            error(&[s, "edit[0]", "exactly one"]),
        ),
        edit(
            "edit_at_inf",
            "at_s = inf\ninstance = \"sphere\"\ntranslation = [0, 0, 0]\n",
            error(&[s, "edit[0]", "at_s"]),
        ),
        // Issue 38: edits go through the loader's checks.
        edit(
            "edit_emission_3e38",
            "at_s = 0.0\nmaterial = \"furnace\"\nemission = [3e38, 3e38, 3e38]\n",
            error(&[s, "edit[0]", "material \"furnace\"", "power"]),
        ),
        edit(
            "edit_albedo_2",
            "at_s = 0.0\nmaterial = \"furnace\"\nbase_color = [2, 2, 2]\n",
            error(&[s, "edit[0]", "base colour", "[0, 1]"]),
        ),
        edit(
            "edit_albedo_negative",
            "at_s = 0.05\nmaterial = \"furnace\"\nbase_color = [-1, 0.5, 0.5]\n",
            error(&[s, "edit[0]", "base colour", "-1"]),
        ),
        edit(
            "edit_unknown_instance",
            "at_s = 0.0\ninstance = \"teapot\"\ntranslation = [0, 0, 0]\n",
            error(&[s, "teapot"]),
        ),
        scenario_replacing(
            "scene_missing",
            "builtin:furnace",
            "nowhere.gltf",
            error(&[s, "nowhere.gltf"]),
        ),
        scenario_replacing(
            "scene_malformed",
            "builtin:furnace",
            "bad.obj",
            error(&["bad.obj", "line 1"]),
        )
        .file("bad.obj", "f 0 0 0\n"),
        scenario(
            "binary_junk",
            &String::from_utf8_lossy(&crate::corpus::obj::junk(2048, 17)),
            error(&[s]),
        ),
        Case::new("scenario", "pipe").fifo("s.toml").run(
            &["bench", "{dir}/s.toml", "--output", "{dir}/out"],
            error(&[s, "not a regular file"]),
        ),
        Case::new("scenario", "dev_zero")
            .link("s.toml", "/dev/zero")
            .run(
                &["bench", "{dir}/s.toml", "--output", "{dir}/out"],
                error(&[s, "not a regular file"]),
            ),
    ]);
    out
}
