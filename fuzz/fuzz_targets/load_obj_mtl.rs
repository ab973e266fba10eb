//! The OBJ loader with a material library on arbitrary bytes: the input is split at the
//! first line `%%MTL%%` into an OBJ file (with `mtllib input.mtl` put in front) and its
//! MTL library, so that both parsers and the textures they name are searched together.
//! Every input gives a scene or an error (or a warning), never a panic, an abort or a hang.
#![no_main]

mod common;

/// The line that separates the OBJ part from the MTL part of an input.
const SEPARATOR: &[u8] = b"\n%%MTL%%\n";

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let (obj, mtl) = match data.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) {
        Some(at) => (&data[..at], &data[at + SEPARATOR.len()..]),
        None => (data, &b""[..]),
    };
    common::scratch_file("mtl", mtl);
    let mut with_library = b"mtllib input.mtl\n".to_vec();
    with_library.extend_from_slice(obj);
    let path = common::scratch_file("obj", &with_library);
    let _ = illume_scene::load::load_scene(&path);
});
