//! Ward's weight (Eq. 2), the usable set (Eq. 3 as corrected) and the interpolation of
//! Eq. 1 with the gradient-corrected contributions of Eq. 4, on hand-computed cases.

use illume_core::{Rgb, Vec3};
use illume_radiance_cache::record::{
    IrradianceRecord, IrradianceValue, RgbGradient, WeightedSum, interpolate, usable, ward_error,
    ward_weight,
};

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

/// A record at `position` facing +Y with R_k = `r_k` and irradiance `e` (grey).
fn record(position: Vec3, r_k: f32, e: f32) -> IrradianceRecord {
    IrradianceRecord {
        position,
        normal: Vec3::Y,
        value: IrradianceValue {
            irradiance: Rgb::splat(e),
            ..IrradianceValue::ZERO
        },
        harmonic_distance_m: r_k,
        temporal_gradient: IrradianceValue::ZERO,
        frame: 0,
        lifespan_frames: 1,
        instance: None,
    }
}

#[test]
fn ward_weight_matches_hand_computed_values() {
    let (pk, nk, r) = (Vec3::ZERO, Vec3::Y, 2.0);
    // 1 m away in the tangent plane, same normal: 1/(1/2 + 0) = 2.
    assert!(close(ward_weight(Vec3::X, Vec3::Y, pk, nk, r), 2.0, 1e-6));
    // At the record, normal with n·n_k = 0.96: 1/(0 + √0.04) = 5.
    let n = Vec3::new(0.28, 0.96, 0.0);
    assert!(close(ward_weight(pk, n, pk, nk, r), 5.0, 1e-5));
    // Both: 0.5 m away (0.3, 0, 0.4) and the same tilt: 1/(0.25 + 0.2) = 2.2̅.
    let p = Vec3::new(0.3, 0.0, 0.4);
    assert!(close(ward_weight(p, n, pk, nk, r), 1.0 / 0.45, 1e-5));
    // At the record itself: infinite.
    assert!(ward_weight(pk, nk, pk, nk, r).is_infinite());
    // A normal facing away: √(1 − (−1)) = √2.
    assert!(close(
        ward_error(pk, -Vec3::Y, pk, nk, r),
        2f32.sqrt(),
        1e-6
    ));
}

#[test]
fn usable_set_is_w_at_least_one_over_a() {
    let (pk, nk, r) = (Vec3::ZERO, Vec3::Y, 2.0);
    let n = Vec3::new(0.28, 0.96, 0.0);
    let cases = [
        (Vec3::X, Vec3::Y),             // 1/w = 0.5
        (pk, n),                        // 1/w = 0.2
        (Vec3::new(0.3, 0.0, 0.4), n),  // 1/w = 0.45
        (Vec3::new(3.0, 0.0, 0.0), nk), // 1/w = 1.5, w ≈ 0.67
    ];
    let usable_at = |a: f32| -> Vec<bool> {
        cases
            .iter()
            .map(|&(p, n)| usable(ward_error(p, n, pk, nk, r), a))
            .collect()
    };
    // a = 0.5: w ≥ 2 (the boundary included).
    assert_eq!(usable_at(0.5), [true, true, true, false]);
    // a = 0.4: w ≥ 2.5.
    assert_eq!(usable_at(0.4), [false, true, false, false]);
    // The printed Eq. 3 (w ≥ a) would admit the last point at a = 0.4 (w ≈ 0.67):
    // 1.5 m beyond a record of R = 2 m, far outside its sphere of a·R = 0.8 m.
    let w_far = ward_weight(cases[3].0, cases[3].1, pk, nk, r);
    assert!(w_far >= 0.4 && !usable(1.0 / w_far, 0.4));
    // NaN never qualifies.
    assert!(!usable(f32::NAN, 1.0));
}

#[test]
fn interpolation_weights_gradient_corrected_contributions() {
    // Record 1 at the origin, E = 1 with ∇_p = 0.5 W/m³ along x in every channel;
    // record 2 at x = 1 m, E = 2, no gradient; R = 1 m for both.
    let mut r1 = record(Vec3::ZERO, 1.0, 1.0);
    r1.value.translation_gradient = RgbGradient([Vec3::X * 0.5; 3]);
    let r2 = record(Vec3::X, 1.0, 2.0);
    let p = Vec3::new(0.25, 0.0, 0.0);
    // Eq. 4: 1 + 0.25·0.5 = 1.125 and 2; Eq. 2 weights 4 and 4/3; Eq. 1: 43/32.
    assert!(close(r1.contribution(p, Vec3::Y).x, 1.125, 1e-6));
    let e = interpolate([&r1, &r2], p, Vec3::Y, 1.0).unwrap();
    assert!(close(e.x, 43.0 / 32.0, 1e-6), "{e}");
    assert_eq!(e.x, e.y);
    // a = 0.5 leaves record 2 out (1/w = 0.75).
    let e = interpolate([&r1, &r2], p, Vec3::Y, 0.5).unwrap();
    assert!(close(e.x, 1.125, 1e-6), "{e}");
    // No usable record: none.
    assert_eq!(
        interpolate([&r1, &r2], Vec3::splat(5.0), Vec3::Y, 0.5),
        None
    );
}

#[test]
fn rotation_gradient_enters_through_the_turn_of_the_normal() {
    // ∇_r = 0.3 W/(m²·rad) about +Z in the red channel only. A normal turned by β from
    // +Y towards +X: n_k × n = (0, 0, −sin β), so red drops by 0.3·sin β.
    let mut r = record(Vec3::ZERO, 1.0, 1.0);
    r.value.rotation_gradient = RgbGradient([Vec3::Z * 0.3, Vec3::ZERO, Vec3::ZERO]);
    let beta = 0.1f32;
    let n = Vec3::new(beta.sin(), beta.cos(), 0.0);
    let c = r.contribution(Vec3::ZERO, n);
    assert!(close(c.x, 1.0 - 0.3 * beta.sin(), 1e-6), "{c}");
    assert_eq!((c.y, c.z), (1.0, 1.0));
}

#[test]
fn a_record_at_the_point_wins_and_negative_extrapolation_is_clamped() {
    let exact = record(Vec3::ZERO, 1.0, 3.0);
    let near = record(Vec3::new(0.1, 0.0, 0.0), 1.0, 100.0);
    let e = interpolate([&near, &exact], Vec3::ZERO, Vec3::Y, 1.0).unwrap();
    assert_eq!(e, Rgb::splat(3.0));
    // A steep gradient extrapolates below zero: the result is clamped to 0.
    let mut steep = record(Vec3::ZERO, 1.0, 1.0);
    steep.value.translation_gradient = RgbGradient([Vec3::X * -20.0; 3]);
    let e = interpolate([&steep], Vec3::new(0.2, 0.0, 0.0), Vec3::Y, 1.0).unwrap();
    assert_eq!(e, Rgb::ZERO);
    let mut sum = WeightedSum::default();
    assert!(sum.is_empty() && sum.result().is_none());
    sum.add(0.0, Rgb::ONE);
    assert!(sum.is_empty(), "a zero weight adds nothing");
}
