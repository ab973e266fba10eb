//! Bench scenarios with `[[edit]]`s on arbitrary text: the scenario parser, then — for a
//! scenario on a builtin scene (a path in the input could name any file on the machine)
//! — what `illume bench` does before it renders: the scene loaded with the scenario's
//! camera, sky, `[sun]` and animation, every edit replayed and the scene checked after
//! each (`Scenario::load_scene`), each edit resolved against the scene, the frame times
//! and each technique's configuration and budget. No rendering. Every input gives a
//! value or an error, never a panic, an abort or a hang.
#![no_main]

use illume_bench::Scenario;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(scenario) = Scenario::parse(text, std::path::Path::new("fuzz.toml")) else {
        return;
    };
    let times = scenario.frame_times();
    let _ = scenario.measured_frames(times.len());
    for i in 0..scenario.techniques.len() {
        if let Ok(config) = scenario.technique_config(i) {
            let _ = scenario.technique_budget(i, &config);
        }
    }
    let builtin = scenario
        .scene_path()
        .is_ok_and(|p| p.to_string_lossy().starts_with("builtin:"));
    if !builtin {
        return;
    }
    let Ok(scene) = scenario.load_scene() else {
        return;
    };
    for i in scenario.edit_order() {
        let _ = scenario.edits[i].resolve(&scene);
        let _ = scenario.edit_label(i);
    }
});
