//! Reading a .exr image (compare, environment maps) on arbitrary bytes.
#![no_main]

mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let path = common::scratch_file("exr", data);
    let _ = illume_core::image::RgbImage::read(&path);
});
