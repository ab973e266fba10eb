//! The reference path tracer against an independent renderer (Mitsuba 3's `path`
//! integrator) on the shared glTF Cornell scenes.
//!
//! The expected per-channel image means were measured with Mitsuba 3.9.1 (llvm_ad_rgb,
//! 2 × 2048 spp at 320×240, relative standard error ≤ 1e-4) by
//! `benches/crosscheck/mitsuba_render.py` under DESIGN.md's conventions; the table and the
//! method are in `benches/crosscheck/README.md`. With a box pixel filter, an image's mean
//! is the average radiance over the whole film, independent of resolution, so a smaller
//! render estimates the same numbers.

use illume_reference::{ReferenceRenderer, ReferenceSettings};
use illume_transport::World;
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    illume_scene::shared_scenes_dir()
}

/// (full, direct) means from Mitsuba; indirect = full − direct.
fn check(file: &str, full: [f32; 3], direct: [f32; 3]) {
    let path = scenes_dir().join("gltf").join(file);
    let scene = illume_scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let world = World::new(scene);
    let mut r = ReferenceRenderer::new(
        ReferenceSettings {
            seed: 1,
            ..Default::default()
        },
        160,
        120,
    );
    r.add_samples(&world, 48);
    let imgs = r.images();
    let (f, d, i) = (imgs.full.mean(), imgs.direct.mean(), imgs.indirect.mean());
    for c in 0..3 {
        let indirect = full[c] - direct[c];
        for (what, got, want) in [
            ("full", f[c], full[c]),
            ("direct", d[c], direct[c]),
            ("indirect", i[c], indirect),
        ] {
            let rel = (got - want).abs() / want;
            assert!(
                rel < 0.01,
                "{file} {what} channel {c}: illume {got:.6} vs Mitsuba {want:.6} (rel {rel:.4})"
            );
        }
    }
}

#[test]
fn cornell_spot_means_match_mitsuba_within_one_percent() {
    check(
        "cornell_spot.gltf",
        [0.143098, 0.105894, 0.097205],
        [0.091607, 0.072385, 0.071773],
    );
}

#[test]
fn cornell_area_means_match_mitsuba_within_one_percent() {
    check(
        "cornell_area.gltf",
        [0.253466, 0.194697, 0.105369],
        [0.159317, 0.123793, 0.074249],
    );
}
