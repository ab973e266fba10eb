//! The temporal weighting function (Eq. 7–12) and temporal gradients (Eq. 17–23) on
//! hand-computed cases, with the paper's a^t = 0.05 and δt_max = 20.

use illume_core::{Rgb, Vec3};
use illume_radiance_cache::record::{IrradianceRecord, IrradianceValue, RgbGradient};
use illume_radiance_cache::temporal::{
    change_rate, contribution, extrapolated_gradient, interpolate_at, interpolated_gradient,
    is_valid, lifespan_frames, temporal_weight,
};

const A_T: f32 = 0.05;
const MAX_AGE: u32 = 20;

fn lifespan(e0: Rgb, e1: Rgb) -> u32 {
    lifespan_frames(change_rate(e0, e1), A_T, MAX_AGE)
}

#[test]
fn lifespans_follow_the_change_rate() {
    let one = Rgb::ONE;
    assert_eq!(lifespan(one, one), 20, "τ = 1: δt_max");
    assert_eq!(lifespan(one, one * 1.02), 3, "τ = 1.02");
    assert_eq!(
        lifespan(one, one * 0.98),
        3,
        "τ = 0.98: a darkening counts alike"
    );
    assert_eq!(lifespan(one, one * 1.2), 1, "τ = 1.2");
    assert_eq!(lifespan(Rgb::ZERO, one), 1, "E₀ = 0 < E₁: infinite change");
    assert_eq!(lifespan(Rgb::ZERO, Rgb::ZERO), 20, "dark and staying dark");
    // The channel with the largest |τ − 1| decides: blue changes by 20 %.
    assert_eq!(lifespan(one, Rgb::new(1.0, 1.01, 1.2)), 1);
    assert_eq!(lifespan(one, Rgb::new(1.0, 1.01, 1.0)), 6);
    // Not a number: the safe answer, one frame.
    assert_eq!(lifespan(Rgb::new(f32::NAN, 1.0, 1.0), one), 1);
    // δt_max = 1 leaves no reuse at all.
    assert_eq!(lifespan_frames(0.0, A_T, 1), 1);
}

/// The lifespan counts exactly the frames at which Eq. 10 (w^t ≥ 1/a^t) and Eq. 12
/// (t − t₀ < δt_max) hold, evaluated literally (changes chosen away from ties).
#[test]
fn lifespan_agrees_with_equations_10_and_12() {
    for i in 0..400 {
        let change = 0.0013 + 0.00731 * i as f32;
        let literal = (0..100u32)
            .take_while(|&age| temporal_weight(change, age) >= 1.0 / A_T && age < MAX_AGE)
            .count() as u32;
        assert_eq!(
            lifespan_frames(change, A_T, MAX_AGE),
            literal,
            "|τ−1| = {change}"
        );
    }
    assert!(temporal_weight(0.0, 5).is_infinite(), "Eq. 11");
    assert!(temporal_weight(0.3, 0).is_infinite());
    // Validity over frames: a record of frame 10 living 3 frames serves 10, 11 and 12.
    let valid: Vec<u32> = (0..20).filter(|&t| is_valid(10, 3, t)).collect();
    assert_eq!(valid, [10, 11, 12]);
}

fn hand_made_record() -> IrradianceRecord {
    IrradianceRecord {
        position: Vec3::new(1.0, 0.0, 0.0),
        normal: Vec3::Y,
        value: IrradianceValue {
            irradiance: Rgb::new(1.0, 2.0, 3.0),
            rotation_gradient: RgbGradient([Vec3::Z * 0.5; 3]),
            translation_gradient: RgbGradient([Vec3::X * 0.2, Vec3::ZERO, Vec3::Z * -0.1]),
        },
        harmonic_distance_m: 1.0,
        temporal_gradient: IrradianceValue {
            irradiance: Rgb::new(0.1, 0.0, -0.2),
            rotation_gradient: RgbGradient([Vec3::Z * 0.05, Vec3::ZERO, Vec3::ZERO]),
            translation_gradient: RgbGradient([Vec3::X * 0.01, Vec3::ZERO, Vec3::ZERO]),
        },
        frame: 4,
        lifespan_frames: 10,
        instance: None,
    }
}

#[test]
fn equation_17_on_a_hand_made_record() {
    let r = hand_made_record();
    // p − p_k = (0.5, 0, 0.2); n turned from +Y towards +X by β: n_k × n = (0, 0, −sin β).
    let p = Vec3::new(1.5, 0.0, 0.2);
    let beta = 0.2f32;
    let n = Vec3::new(beta.sin(), beta.cos(), 0.0);
    let s = beta.sin();
    // Three frames after t_k = 4:
    // R: 1 + 0.1·3 + (−s)(0.5 + 0.05·3) + 0.5·(0.2 + 0.01·3)
    // G: 2 + 0 + (−s)(0.5) + 0
    // B: 3 − 0.2·3 + (−s)(0.5) + 0.2·(−0.1)
    let expected = Rgb::new(
        1.0 + 0.3 - s * 0.65 + 0.5 * 0.23,
        2.0 - s * 0.5,
        3.0 - 0.6 - s * 0.5 - 0.02,
    );
    let got = contribution(&r, p, n, 7);
    assert!(
        (got - expected).abs().max_element() < 1e-5,
        "{got} vs {expected}"
    );
    // At t = t_k, Eq. 17 is Eq. 4.
    assert_eq!(contribution(&r, p, n, 4), r.contribution(p, n));
    // The offset is p − p_k (the paper prints p_k − p): moving p along +x raises red.
    let further = contribution(&r, p + Vec3::X * 0.1, n, 7);
    assert!(further.x > got.x);
}

#[test]
fn interpolated_gradient_gives_the_midpoint() {
    // Eq. 21: E_k = 1 at frame 0, E_l = 1.2 at frame 4 → 1.1 at frame 2.
    let k = IrradianceValue {
        irradiance: Rgb::ONE,
        ..IrradianceValue::ZERO
    };
    let l = IrradianceValue {
        irradiance: Rgb::splat(1.2),
        rotation_gradient: RgbGradient([Vec3::X * 0.4; 3]),
        translation_gradient: RgbGradient([Vec3::Y * -0.8; 3]),
    };
    let g = interpolated_gradient(&k, 0, &l, 4).unwrap();
    let mut record = IrradianceRecord {
        position: Vec3::ZERO,
        normal: Vec3::Y,
        value: k,
        harmonic_distance_m: 1.0,
        temporal_gradient: g,
        frame: 0,
        lifespan_frames: 4,
        instance: None,
    };
    let e = contribution(&record, Vec3::ZERO, Vec3::Y, 2);
    assert!((e - Rgb::splat(1.1)).abs().max_element() < 1e-6, "{e}");
    // Eq. 22–23 move the gradients the same way: half of l's at frame 2.
    assert!((g.rotation_gradient.0[1] - Vec3::X * 0.1).length() < 1e-6);
    assert!((g.translation_gradient.0[2] - Vec3::Y * -0.2).length() < 1e-6);
    // At frame 4 the record would reach l's values exactly (continuity, Fig. 5e).
    record.lifespan_frames = 5;
    let at_l = contribution(&record, Vec3::new(0.3, 0.0, 0.0), Vec3::Y, 4);
    let l_record = IrradianceRecord {
        value: l,
        temporal_gradient: IrradianceValue::ZERO,
        frame: 4,
        ..record
    };
    let l_value = contribution(&l_record, Vec3::new(0.3, 0.0, 0.0), Vec3::Y, 4);
    assert!((at_l - l_value).abs().max_element() < 1e-6);
    // The replacement must come later.
    assert!(interpolated_gradient(&k, 4, &l, 4).is_err());
    assert!(interpolated_gradient(&k, 5, &l, 4).is_err());
}

#[test]
fn extrapolated_gradient_is_the_next_frame_difference() {
    // Eq. 18–20: E(t_k + 1) − E(t_k), and the same for both gradients.
    let now = IrradianceValue {
        irradiance: Rgb::new(1.0, 2.0, 3.0),
        rotation_gradient: RgbGradient([Vec3::X; 3]),
        translation_gradient: RgbGradient([Vec3::Y; 3]),
    };
    let next = IrradianceValue {
        irradiance: Rgb::new(1.5, 2.0, 2.0),
        rotation_gradient: RgbGradient([Vec3::X * 3.0; 3]),
        translation_gradient: RgbGradient([Vec3::ZERO; 3]),
    };
    let g = extrapolated_gradient(&now, &next);
    assert_eq!(g.irradiance, Rgb::new(0.5, 0.0, -1.0));
    assert_eq!(g.rotation_gradient.0[0], Vec3::X * 2.0);
    assert_eq!(g.translation_gradient.0[2], -Vec3::Y);
}

#[test]
fn interpolation_over_frames_uses_valid_records_only() {
    let mut a = hand_made_record();
    a.temporal_gradient = IrradianceValue::ZERO;
    a.position = Vec3::ZERO;
    a.value.translation_gradient = RgbGradient::ZERO;
    a.value.rotation_gradient = RgbGradient::ZERO;
    let mut b = a;
    b.value.irradiance = Rgb::splat(10.0);
    b.frame = 8;
    b.lifespan_frames = 2;
    // a: frames 4..14, b: frames 8..10; both at the same place.
    let at = |t| interpolate_at([&a, &b], Vec3::new(0.1, 0.0, 0.0), Vec3::Y, 0.5, t);
    let near = |e: Option<Rgb>, want: Rgb| e.is_some_and(|e| (e - want).abs().max_element() < 1e-5);
    assert_eq!(at(3), None);
    assert!(near(at(5), a.value.irradiance));
    assert!(near(at(9), (a.value.irradiance + Rgb::splat(10.0)) * 0.5));
    assert!(near(at(12), a.value.irradiance));
    assert_eq!(at(14), None);
}
