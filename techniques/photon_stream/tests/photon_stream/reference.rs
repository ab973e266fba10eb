//! The converged VSL indirect light against the reference path tracer's indirect-only
//! light (light reflected ≥ 2 times) on `builtin:cornell-spot`, static.

use illume_core::Vec2;
use illume_core::image::RgbImage;
use illume_photon_stream::{PhotonStream, PhotonStreamSettings, VisibilityMode};
use illume_reference::{ReferenceSettings, ReferenceTechnique};
use illume_transport::{Budget, GBuffer, SharedWorld, Technique, World};
use std::time::Instant;

const W: u32 = 96;
const H: u32 = 72;
const BLOCK: u32 = 8;

/// Relative L1 error of block means (shared metric, `illume_metrics::block_error`).
fn block_error(img: &RgbImage, reference: &RgbImage) -> f64 {
    illume_metrics::block_error(reference, img, BLOCK).expect("same sizes")
}

fn mean_ratio(img: &RgbImage, reference: &RgbImage) -> f64 {
    img.mean().element_sum() as f64 / reference.mean().element_sum() as f64
}

/// The indirect image of `settings` after 400 000 photons (a 10⁶-impact pool holds them
/// all), at the points of `g`.
fn converged(world: &SharedWorld, settings: PhotonStreamSettings, g: &GBuffer) -> RgbImage {
    let mut ps = PhotonStream::new(world, settings).unwrap();
    let w = world.read().unwrap();
    ps.advance(
        &w,
        &Budget {
            work: Some(400_000),
            ..Default::default()
        },
    );
    ps.indirect(&w, g)
}

/// The path tracer's indirect light (reflected ≥ 2 times) at the points of `g`, 256 spp.
fn reference_indirect(w: &World, g: &GBuffer) -> RgbImage {
    let mut r = ReferenceTechnique::new(ReferenceSettings {
        spp_per_frame: 256,
        ..Default::default()
    })
    .unwrap();
    r.advance(
        w,
        &Budget {
            work: Some(256),
            ..Default::default()
        },
    );
    r.indirect(w, g)
}

fn average(a: &RgbImage, b: &RgbImage) -> RgbImage {
    RgbImage::from_vec(
        W,
        H,
        a.pixels()
            .iter()
            .zip(b.pixels())
            .map(|(a, b)| (*a + *b) * 0.5)
            .collect(),
    )
    .unwrap()
}

/// Tolerances (deterministic seeds, so the measured values are fixed; margins cover
/// platform float differences):
/// * energy: the image mean within ±15 % of the reference's. Measured +6 %: VSLs carry
///   exactly the photon flux leaving each surface, so the total is right up to the
///   over-illumination of no visibility (positive) and the point/normal concentration
///   of energy at VSL centres (negative).
/// * shape: relative L1 of 6×6-pixel block means < 0.32. Measured 0.25 with 100 VSLs:
///   the paper's approximations (100 VSLs for 27 m² of surface, one normal per VSL, no
///   visibility) are biased; the reference's own block noise (two 128-spp halves) is
///   asserted below 0.05, so the bound measures bias, not noise.
/// * visibility: with shadow rays to every VSL the block error must drop below the
///   no-visibility error (over-illumination behind the tall box and sphere removed).
#[test]
fn converged_vsl_indirect_agrees_with_reference_indirect_and_visibility_reduces_the_error() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let w = world.read().unwrap();
    let g = GBuffer::render(&w, W, H, Vec2::splat(0.5));

    let t = Instant::now();
    let half = |seed| {
        let mut r = ReferenceTechnique::new(ReferenceSettings {
            spp_per_frame: 256,
            seed,
            ..Default::default()
        })
        .unwrap();
        r.advance(
            &w,
            &Budget {
                work: Some(256),
                ..Default::default()
            },
        );
        r.indirect(&w, &g)
    };
    let (ref_a, ref_b) = (half(0), half(1_000_000)); // disjoint sample indices
    let ref_img = average(&ref_a, &ref_b);
    let ref_noise = block_error(&ref_a, &ref_b) / 2.0;
    eprintln!(
        "reference: {:.1} s, mean {:?}, block noise {ref_noise:.3}",
        t.elapsed().as_secs_f64(),
        ref_img.mean()
    );
    assert!(
        ref_noise < 0.05,
        "reference too noisy for the comparison: {ref_noise}"
    );

    let mut errors = Vec::new();
    for vis in [
        VisibilityMode::Off,
        VisibilityMode::All,
        VisibilityMode::Stochastic,
    ] {
        let t = Instant::now();
        let settings = PhotonStreamSettings {
            vsl_count: 100,
            pool_size: 1_000_000,
            visibility: vis,
            warm_up: false,
            ..PhotonStreamSettings::deterministic()
        };
        let img = converged(&world, settings, &g);
        let (e, r) = (block_error(&img, &ref_img), mean_ratio(&img, &ref_img));
        eprintln!(
            "{vis:?}: {:.1} s, mean {:?}, block L1 {e:.3}, mean ratio {r:.3}",
            t.elapsed().as_secs_f64(),
            img.mean()
        );
        errors.push((e, r));
    }
    let (off, all) = (errors[0], errors[1]);
    assert!(
        (off.1 - 1.0).abs() < 0.15,
        "indirect energy ratio {} not within ±15 %",
        off.1
    );
    assert!(off.0 < 0.32, "block L1 error {} ≥ 0.32", off.0);
    assert!(
        all.0 < off.0,
        "visibility did not reduce the error: {} vs {}",
        all.0,
        off.0
    );
}

/// Without occluders (the empty Cornell box) visibility changes nothing, and the only
/// bias left is the concentration of each VSL's region at one point with one normal.
/// It loses energy (photons landing near a corner leave with the neighbouring face's
/// normal; the disk regularisation caps the near field) and must shrink as N_v grows:
/// measured ratios 0.68 / 0.84 / 0.96 for 25 / 100 / 400 VSLs.
#[test]
fn in_the_empty_box_vsl_shading_converges_to_the_reference_as_the_vsl_count_grows() {
    let mut scene = illume_scene::builtin::load("cornell-spot").unwrap();
    scene.instances.truncate(1); // walls only
    let world = World::new(scene).shared();
    let w = world.read().unwrap();
    let g = GBuffer::render(&w, W, H, Vec2::splat(0.5));
    let ref_img = reference_indirect(&w, &g);
    let ratios: Vec<f64> = [25u32, 100, 400]
        .iter()
        .map(|&n| {
            let settings = PhotonStreamSettings {
                vsl_count: n,
                pool_size: 1_000_000,
                warm_up: false,
                ..PhotonStreamSettings::deterministic()
            };
            mean_ratio(&converged(&world, settings, &g), &ref_img)
        })
        .collect();
    eprintln!("energy ratios for 25/100/400 VSLs: {ratios:.3?}");
    assert!(
        ratios[0] < ratios[1] && ratios[1] < ratios[2],
        "no convergence with N_v: {ratios:?}"
    );
    assert!(
        (ratios[2] - 1.0).abs() < 0.06,
        "400 VSLs: energy ratio {} not within ±6 %",
        ratios[2]
    );

    // The near field (issue 15) gathers what the VSL centres cannot give close to their
    // cells. Measured: 100 VSLs split at 3 cell sizes 1.025 (against 0.853 without),
    // 3200 cells all gathered (the `quality`/`still` estimator) 1.012. What remains is
    // the cells' averaging (a gather hit reads its cell's mean exitance) and, for the
    // split, the window taken at the VSL's centre on one side and at the hit on the
    // other; it shrinks with the cell size.
    for (n, scale, bound) in [(100u32, 3.0f32, 0.06), (3200, f32::INFINITY, 0.03)] {
        let settings = PhotonStreamSettings {
            vsl_count: n,
            pool_size: 1_000_000,
            warm_up: false,
            near_field_rays: 64,
            near_field_scale: scale,
            shading_stride: 1,
            ..PhotonStreamSettings::deterministic()
        };
        let ratio = mean_ratio(&converged(&world, settings, &g), &ref_img);
        eprintln!("{n} VSLs, near field at {scale} cell sizes: energy ratio {ratio:.3}");
        assert!(
            (ratio - 1.0).abs() < bound,
            "{n} VSLs, near field at {scale}: energy ratio {ratio} not within ±{bound}"
        );
    }
}

/// With everything gathered over coarse cells (100 for the box), a gather hit reads its
/// cell's mean exitance: the spot's sharp pool of light on the floor is smeared over
/// every cell it touches, and the walls and the boxes' sides that see a cell's dark part
/// read light that only its lit part has. `gather_direct` (beyond the paper) takes the
/// light arriving straight from the spot at each hit by a light sample and a shadow
/// ray, leaving the cells only light already scattered once: both the block error
/// (shape) and the energy must come closer to the reference's indirect light.
#[test]
fn taking_the_first_bounce_at_the_gather_hits_removes_the_cells_averaging() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap()).shared();
    let w = world.read().unwrap();
    let g = GBuffer::render(&w, W, H, Vec2::splat(0.5));
    let ref_img = reference_indirect(&w, &g);
    let gathered = |gather_direct: bool| {
        let settings = PhotonStreamSettings {
            vsl_count: 100,
            pool_size: 1_000_000,
            warm_up: false,
            near_field_rays: 256,
            near_field_scale: f32::INFINITY,
            gather_direct,
            shading_stride: 1,
            ..PhotonStreamSettings::deterministic()
        };
        let img = converged(&world, settings, &g);
        (block_error(&img, &ref_img), mean_ratio(&img, &ref_img))
    };
    let (cells_err, cells_ratio) = gathered(false);
    let (direct_err, direct_ratio) = gathered(true);
    eprintln!(
        "100 cells all gathered: block error {cells_err:.3}, energy ratio {cells_ratio:.3}; \
         first bounce at the hits: {direct_err:.3}, {direct_ratio:.3}"
    );
    assert!(
        direct_err < 0.8 * cells_err,
        "block error {direct_err:.3} with the first bounce at the hits, {cells_err:.3} without"
    );
    assert!(
        (direct_ratio - 1.0).abs() < 0.03,
        "energy ratio {direct_ratio:.3} with the first bounce at the hits not within ±3 %"
    );
}
