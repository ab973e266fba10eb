//! Frames sampled off the pixel centre ([`Renderer::jitter`], rasterized through a
//! shifted projection): their mean over the R₂ offsets converges to the box filter of a
//! supersampled image (the window's still refinement), where the pixel-centre frame keeps
//! its aliased edges.

use crate::InteractiveBlack;
use illume_core::Vec2;
use illume_core::image::RgbImage;
use illume_core::sampling::r2_point;
use illume_render::{PrimaryVisibility, RenderSettings, Renderer, ShadowMode};
use illume_transport::World;

fn renderer(width: u32, height: u32, primary: PrimaryVisibility) -> Renderer {
    Renderer::new(RenderSettings {
        width,
        height,
        primary_visibility: primary,
        // Exact, deterministic shadows: the test is about primary visibility.
        shadows: ShadowMode::Rays,
        ..RenderSettings::default()
    })
}

/// Mean absolute difference per pixel and channel.
fn mean_abs(a: &RgbImage, b: &RgbImage) -> f64 {
    let sum: f64 = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(x, y)| f64::from((*x - *y).abs().element_sum()))
        .sum();
    sum / (3 * a.pixels().len()) as f64
}

#[test]
fn jittered_frames_average_to_the_supersampled_box_filter() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
    let (w, h, k) = (48u32, 36u32, 8u32);
    // The box filter: 8 × 8 centre rays a pixel, averaged.
    let fine = renderer(w * k, h * k, PrimaryVisibility::Rays)
        .render(&world, &mut InteractiveBlack, 0)
        .full;
    let boxed = fine.box_downsample(k);
    let centre = renderer(w, h, PrimaryVisibility::Raster)
        .render(&world, &mut InteractiveBlack, 0)
        .full;
    let mut jittered = renderer(w, h, PrimaryVisibility::Raster);
    let frames = 64u32;
    let mut sum = RgbImage::black(w, h);
    let mut e16 = f64::NAN;
    for i in 0..frames {
        jittered.jitter = Some(r2_point(i));
        let f = jittered.render(&world, &mut InteractiveBlack, 0).full;
        if i == 0 {
            // The sequence starts at the centre: the frame without an offset.
            assert_eq!(r2_point(0), Vec2::splat(0.5));
            assert_eq!(f.pixels(), centre.pixels());
        }
        for (s, p) in sum.pixels_mut().iter_mut().zip(f.pixels()) {
            *s += *p;
        }
        if i + 1 == 16 {
            e16 = mean_abs(&sum.map(|&p| p / 16.0), &boxed);
        }
    }
    let mean = sum.map(|&p| p / frames as f32);
    let (e_centre, e_mean) = (mean_abs(&centre, &boxed), mean_abs(&mean, &boxed));
    println!(
        "against 64 samples a pixel: centre {e_centre:.5}, mean of 16 frames {e16:.5}, \
         of {frames} {e_mean:.5}"
    );
    // Edges (the box's silhouettes, the spot's cone, the sphere) alias at the centre.
    assert!(
        e_centre > 1e-3,
        "the centre frame shows no aliasing: {e_centre}"
    );
    // Measured: 0.41× after 16 frames (the window's default), 0.15× after 64.
    assert!(
        e16 < 0.5 * e_centre,
        "16 jittered frames {e16} against the centre's {e_centre}"
    );
    assert!(
        e_mean < 0.2 * e_centre,
        "{frames} jittered frames {e_mean} against the centre's {e_centre}"
    );
    // The renderer goes back to the configured visibility without an offset.
    jittered.jitter = None;
    let back = jittered.render(&world, &mut InteractiveBlack, 0).full;
    assert_eq!(back.pixels(), centre.pixels());
}
