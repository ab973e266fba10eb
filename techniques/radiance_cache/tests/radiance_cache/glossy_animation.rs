//! A glossy scene in motion agrees with the reference: `builtin:glossy-box` (a rough gold
//! sphere and a glossy blue box, both served by radiance records) over the frames where
//! its light stops and its sphere starts rolling (animation `light_then_objects`, 25
//! fps), `interpolated` and `per_frame` against the path tracer's indirect light.

use illume_core::Rgb;
use illume_core::image::RgbImage;
use illume_core::progress::Silent;
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_reference::{ReferenceSettings, ReferenceTechnique};
use illume_scene::Timeline;
use illume_transport::{GBuffer, Technique, World};

const W: u32 = 64;
const H: u32 = 48;

fn times() -> Vec<f64> {
    // 1.84 … 2.12 s: the light's last frames, then the sphere's first.
    (0..8).map(|i| 1.84 + i as f64 * 0.04).collect()
}

fn scene() -> illume_scene::Scene {
    illume_scene::builtin::load("glossy-box").unwrap()
}

/// Renders the timeline as the engine does; returns each frame's indirect light and
/// G-buffer.
fn run(temporal: TemporalMode) -> Vec<(RgbImage, GBuffer)> {
    let t = times();
    let timeline = Timeline::new(scene(), t.clone(), W, H).unwrap();
    let mut world = World::new(scene());
    world.set_time(t[0]);
    let settings = RadianceCacheSettings {
        theta_strata: 32,
        phi_strata: 32,
        temporal,
        ..RadianceCacheSettings::default()
    };
    let mut rc = RadianceCache::new(&world, &timeline, settings).unwrap();
    rc.precompute(&world, &mut Silent).unwrap();
    t.iter()
        .enumerate()
        .map(|(i, &time)| {
            if i > 0 {
                let changes = world.set_time(time);
                rc.scene_changed(&world, &changes);
            }
            let g = GBuffer::rasterize(&world, W, H);
            (rc.indirect(&world, &g), g)
        })
        .collect()
}

fn reference(frames: &[(RgbImage, GBuffer)]) -> Vec<RgbImage> {
    let mut world = World::new(scene());
    times()
        .iter()
        .zip(frames)
        .enumerate()
        .map(|(i, (&t, (_, g)))| {
            world.set_time(t);
            let mut r = ReferenceTechnique::new(ReferenceSettings {
                spp_per_frame: 256,
                seed: 500 + i as u64,
                ..ReferenceSettings::default()
            })
            .unwrap();
            r.advance(&world, &Default::default());
            r.indirect(&world, g)
        })
        .collect()
}

/// Energy of the glossy pixels against the reference's (relative difference), and the
/// 8×8-block error of whole frames, both over all frames.
fn agreement(frames: &[(RgbImage, GBuffer)], reference: &[RgbImage]) -> (f32, f64) {
    let (mut a, mut b) = (Rgb::ZERO, Rgb::ZERO);
    let mut block = 0.0;
    for ((img, g), r) in frames.iter().zip(reference) {
        for ((p, x), y) in g.pixels.iter().zip(img.pixels()).zip(r.pixels()) {
            if p.as_ref().is_some_and(|p| !p.hit.brdf().is_lambertian()) {
                a += *x;
                b += *y;
            }
        }
        block += illume_metrics::block_error(r, img, 8).unwrap();
    }
    (
        a.element_sum() / b.element_sum() - 1.0,
        block / frames.len() as f64,
    )
}

#[test]
fn a_glossy_scene_in_motion_agrees_with_the_reference() {
    let interpolated = run(TemporalMode::Interpolated);
    let per_frame = run(TemporalMode::PerFrame);
    // The G-buffers are the same in both runs (the same scene at the same times).
    let reference = reference(&per_frame);
    let glossy = per_frame[0]
        .1
        .pixels
        .iter()
        .flatten()
        .filter(|p| !p.hit.brdf().is_lambertian())
        .count();
    assert!(glossy > 150, "{glossy} glossy pixels");
    let (ei, bi) = agreement(&interpolated, &reference);
    let (ep, bp) = agreement(&per_frame, &reference);
    eprintln!(
        "glossy pixels' energy: interpolated {ei:+.4}, per_frame {ep:+.4}; block error {bi:.4} / {bp:.4}"
    );
    // Tolerances: those of the still glossy test (tests/radiance.rs), 5 % on energy for
    // records reused across frames of a moving light and sphere.
    assert!(ep.abs() < 0.05, "per_frame: energy {ep}");
    assert!(ei.abs() < 0.05, "interpolated: energy {ei}");
    assert!(bp < 0.06, "per_frame: block error {bp}");
    assert!(bi < 0.06, "interpolated: block error {bi}");
    assert!(bi <= 1.1 * bp, "interpolated {bi} against per_frame {bp}");
}
