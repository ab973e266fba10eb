//! Regressions found by fuzzing `RgbImage::read` on OpenEXR input (`fuzz/`, target
//! `read_exr`): each file is an error naming it, without a large allocation.

use illume_core::image::RgbImage;
use std::path::Path;

/// The error reading `tests/data/NAME` gives, checked to name the file.
fn refusal(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    let err = RgbImage::read(&path)
        .expect_err("the file is refused")
        .to_string();
    assert!(err.contains(name), "{err}");
    err
}

#[test]
fn an_exr_whose_blocks_claim_gigabytes_is_refused_before_decoding() {
    // 816 bytes found by `read_exr` (2026-11-26): a valid-looking header whose scan-line
    // blocks span gigabytes; the exr crate reserved 1.85 GB for one chunk.
    let err = refusal("exr_block_bomb.exr");
    assert!(err.contains("blocks of"), "{err}");
}

#[test]
fn an_exr_too_short_for_the_blocks_it_claims_is_refused_before_decoding() {
    // 1 063 bytes found by `read_exr` (2026-11-28): a header claiming an image of about
    // 1 GB decoded, with far fewer bytes than its blocks need; the image was allocated
    // (1 GB, 2 s) before the first block's position was found wrong.
    let err = refusal("exr_short_of_its_blocks.exr");
    assert!(err.contains("blocks of pixel data"), "{err}");
    assert!(err.contains("the file has 1063"), "{err}");
}
