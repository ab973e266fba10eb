//! The gltf loader on arbitrary bytes: every input gives a scene or an error, never a
//! panic, an abort or a hang.
#![no_main]

mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("gltf", data);
    let _ = illume_scene::load::load_scene(&path);
});
