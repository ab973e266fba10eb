//! Environment maps on arbitrary bytes (`--envmap FILE`): written as `input.exr` when
//! they start with OpenEXR's magic number, else `input.hdr` (Radiance), read by
//! `illume_scene::load_envmap` (scaled, turned); a map that loads becomes the sky of
//! `builtin:cornell-spot`, the scene is checked (`Scene::validate`) and, when valid, its
//! lights are built (the map's importance-sampling table) and the sky sampled. Every
//! input gives a value or an error, never a panic, an abort or a hang.
#![no_main]

mod common;

/// OpenEXR's magic number.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let ext = if data.starts_with(&EXR_MAGIC) {
        "exr"
    } else {
        "hdr"
    };
    let path = common::scratch_file(ext, data);
    let Ok(sky) = illume_scene::load_envmap(&path, 1.5, 30.0) else {
        return;
    };
    let mut scene = common::builtin("builtin:cornell-spot").clone();
    scene.replace_sky(sky);
    common::check_and_sample(&mut scene, 0.0);
});
