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

/// Mean absolute difference per pixel and channel over the pixels `keep` selects.
fn mean_abs_where(a: &RgbImage, b: &RgbImage, keep: &[bool]) -> f64 {
    let (sum, n) = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .zip(keep)
        .filter(|(_, k)| **k)
        .fold((0.0f64, 0usize), |(s, n), ((x, y), _)| {
            (s + f64::from((*x - *y).abs().element_sum()), n + 3)
        });
    sum / n.max(1) as f64
}

/// Temporal anti-aliasing under a moving camera: frames at R₂ offsets blended into
/// their reprojected history come closer to each frame's box filter (64 rays a pixel)
/// than frames at pixel centres on the edges, and no further from it elsewhere.
#[test]
fn temporal_aa_brings_moving_frames_towards_the_box_filter() {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
    let (w, h) = (64u32, 48u32);
    let plain = renderer(w, h, PrimaryVisibility::Raster);
    let mut taa = renderer(w, h, PrimaryVisibility::Raster);
    taa.settings.temporal_aa = true;
    let home = world.scene.camera.world_from_camera;
    let (mut whole, mut edges) = ([0.0f64; 2], [0.0f64; 2]);
    let frames = 24u32;
    for i in 0..frames {
        // A slow pan and dolly: ≈ 0.3 pixel a frame at the image centre.
        let t = i as f32;
        world
            .apply_edit(&illume_scene::Edit::SetCameraTransform {
                world_from_camera: home
                    * illume_core::Affine3A::from_rotation_translation(
                        illume_core::Quat::from_rotation_y(0.002 * t),
                        illume_core::Vec3::new(0.003 * t, 0.0, -0.004 * t),
                    ),
            })
            .expect("edit");
        let boxed = boxed(&world, w, h);
        let p = plain
            .render(&world, &mut InteractiveBlack, u64::from(i))
            .full;
        let a = taa.render(&world, &mut InteractiveBlack, u64::from(i)).full;
        if i >= 8 {
            // Edges: pixels whose centre sample is off the box filter by > 10 %.
            let edge: Vec<bool> = p
                .pixels()
                .iter()
                .zip(boxed.pixels())
                .map(|(x, y)| (*x - *y).abs().max_element() > 0.1 * y.max_element().max(1e-3))
                .collect();
            for (k, img) in [&p, &a].into_iter().enumerate() {
                whole[k] += mean_abs(img, &boxed);
                edges[k] += mean_abs_where(img, &boxed, &edge);
            }
        }
    }
    println!(
        "moving camera, frames 8–23 against 64 rays a pixel: whole image plain {:.5}, \
         temporal AA {:.5}; edge pixels plain {:.5}, temporal AA {:.5}",
        whole[0] / 16.0,
        whole[1] / 16.0,
        edges[0] / 16.0,
        edges[1] / 16.0
    );
    // Measured: whole image 0.00496 → 0.00466, edges 0.0483 → 0.0189.
    assert!(whole[1] < whole[0], "whole image: {whole:?}");
    assert!(edges[1] < 0.5 * edges[0], "edges: {edges:?}");
}

/// The box filter of `world`'s direct light: 8 × 8 centre rays a pixel.
fn boxed(world: &World, w: u32, h: u32) -> RgbImage {
    renderer(w * 8, h * 8, PrimaryVisibility::Rays)
        .render(world, &mut InteractiveBlack, 0)
        .full
        .box_downsample(8)
}

/// A moving object leaves no trail: with the camera still, where the sphere was the
/// blended frame is as close to each frame's box filter as the plain one, and the
/// instance's own motion carries its history along (its pixels as close as plain).
#[test]
fn temporal_aa_leaves_no_trail_behind_a_moving_object() {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").expect("builtin"));
    let (w, h) = (64u32, 48u32);
    let plain = renderer(w, h, PrimaryVisibility::Raster);
    let mut taa = renderer(w, h, PrimaryVisibility::Raster);
    taa.settings.temporal_aa = true;
    let sphere = world
        .scene
        .instances
        .iter()
        .position(|i| i.name.to_lowercase().contains("sphere"))
        .expect("cornell-spot has a sphere");
    let home = world.scene.instances[sphere].world_from_object;
    let (mut vacated, mut worst) = (0usize, 0.0f64);
    for i in 0..16u32 {
        // 2 cm a frame to the side: about a pixel a frame here.
        world
            .apply_edit(&illume_scene::Edit::SetInstanceTransform {
                instance: illume_scene::InstanceId(sphere as u32),
                world_from_object: illume_core::Affine3A::from_translation(illume_core::Vec3::new(
                    0.02 * i as f32,
                    0.0,
                    0.0,
                )) * home,
            })
            .expect("edit");
        let boxed = boxed(&world, w, h);
        let pf = plain.render(&world, &mut InteractiveBlack, u64::from(i));
        let a = taa.render(&world, &mut InteractiveBlack, u64::from(i)).full;
        if i < 8 {
            continue;
        }
        // Pixels the sphere covered 4 frames ago and does not now (by the plain frame's
        // G-buffer against one rendered with the sphere there).
        let mut then = World::new(world.scene.clone());
        then.apply_edit(&illume_scene::Edit::SetInstanceTransform {
            instance: illume_scene::InstanceId(sphere as u32),
            world_from_object: illume_core::Affine3A::from_translation(illume_core::Vec3::new(
                0.02 * (i - 4) as f32,
                0.0,
                0.0,
            )) * home,
        })
        .expect("edit");
        let before = illume_transport::GBuffer::rasterize(&then, w, h);
        let sees = |g: &illume_transport::GBuffer, j: usize| {
            g.pixels[j]
                .as_ref()
                .is_some_and(|p| p.hit.instance.index() == sphere)
        };
        let left: Vec<bool> = (0..(w * h) as usize)
            .map(|j| sees(&before, j) && !sees(&pf.gbuffer, j))
            .collect();
        vacated += left.iter().filter(|&&b| b).count();
        let (ep, ea) = (
            mean_abs_where(&pf.full, &boxed, &left),
            mean_abs_where(&a, &boxed, &left),
        );
        worst = worst.max(ea - ep);
    }
    println!(
        "pixels the sphere left: {vacated}; worst excess error of temporal AA there {worst:.5}"
    );
    assert!(
        vacated > 50,
        "the sphere did not move across pixels: {vacated}"
    );
    assert!(worst < 0.01, "a trail behind the sphere: {worst}");
}
