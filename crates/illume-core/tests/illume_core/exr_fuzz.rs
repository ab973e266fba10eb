//! Regressions found by fuzzing `RgbImage::read` on OpenEXR input (`fuzz/`, target
//! `read_exr`): each file is an error naming it, without a large allocation.

use illume_core::image::RgbImage;
use std::path::Path;

#[test]
fn an_exr_whose_blocks_claim_gigabytes_is_refused_before_decoding() {
    // 816 bytes found by `read_exr` (2026-11-26): a valid-looking header whose scan-line
    // blocks span gigabytes; the exr crate reserved 1.85 GB for one chunk.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/exr_block_bomb.exr");
    let err = RgbImage::read(&path)
        .expect_err("the file is refused")
        .to_string();
    assert!(err.contains("exr_block_bomb.exr"), "{err}");
    assert!(err.contains("blocks of"), "{err}");
}
