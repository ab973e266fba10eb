//! The reference's denoised still (`illume render --technique reference --denoise`,
//! issue 36 goal 6): the shared à-trous filter (`illume_render::denoise`) on the path
//! tracer's still, reached through the registration as the engine reaches it.

use illume_core::image::RgbImage;
use illume_reference::{Descriptor, ReferenceRenderer, ReferenceSettings};
use illume_transport::{Registration, World};

/// `illume render --technique reference --denoise` (goal 6): without the filter the
/// still is the reference's own, bit for bit; with it, `builtin:furnace` (every pixel
/// converges to 2) keeps its answer while the noise falls, and the parts sum to the
/// whole. Never ground truth: the reference's settings take no denoising (the bench's and
/// the tests' references cannot be filtered by a setting or `--set`).
#[test]
fn denoised_reference_still_keeps_the_furnace() {
    let scene = illume_scene::builtin::load("furnace").unwrap();
    let s = ReferenceSettings {
        spp: 8,
        ..Default::default()
    };
    let size = (16, 16);
    let still = Descriptor::STILL.expect("the reference's own still");
    let denoised_still = Descriptor::DENOISED_STILL.expect("the reference's denoised still");
    let silent = &mut illume_core::progress::Silent;
    let raw = still(scene.clone(), &s, size, silent).unwrap();
    let mut r = ReferenceRenderer::new(s.clone(), size.0, size.1);
    r.add_samples(&World::new(scene.clone()), s.spp);
    assert!(
        raw.full.pixels() == r.images().full.pixels(),
        "raw = the reference's"
    );
    let denoised = denoised_still(scene, &s, size, silent).unwrap();
    let rms = |img: &RgbImage| {
        let n = img.pixels().len() as f32;
        (img.pixels()
            .iter()
            .map(|p| (p.x - 2.0).powi(2))
            .sum::<f32>()
            / n)
            .sqrt()
    };
    let (m, e_raw, e_den) = (denoised.full.mean().x, rms(&raw.full), rms(&denoised.full));
    eprintln!("furnace 8 spp: denoised mean {m:.4}, RMS error {e_den:.4} (raw {e_raw:.4})");
    assert!((m - 2.0).abs() < 0.04, "mean {m}");
    assert!(e_den < 0.5 * e_raw, "{e_den} vs raw {e_raw}");
    let parts = denoised.direct.add(&denoised.indirect);
    assert!(parts.pixels() == denoised.full.pixels());
    let e = toml::from_str::<ReferenceSettings>("denoise = true").expect_err("no such setting");
    assert!(e.to_string().contains("denoise"), "{e}");
}
