//! Records and their gradients against closed forms: uniform radiance (no gradient),
//! distant radiance linear in direction (the rotation gradient), a half-plane emitter
//! (the translation derivative), and gathers traced through `continue_path` in real
//! worlds (a ground plane under a uniform sky, the furnace).

use illume_core::{PI, Rgb, Vec3};
use illume_radiance_cache::record::{HemisphereGather, Incoming, IrradianceRecord, RecordSettings};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Sky, Trs};
use illume_transport::World;

fn settings() -> RecordSettings {
    RecordSettings {
        r_min_m: 1e-3,
        r_max_m: 1e6,
        gradient_limit: false,
        ..RecordSettings::default()
    }
}

fn record_from(normal: Vec3, f: impl FnMut(Vec3) -> (Rgb, f32)) -> IrradianceRecord {
    let s = settings();
    let gather = HemisphereGather::from_fn(normal, &s, 7, f).unwrap();
    IrradianceRecord::from_gather(Vec3::ZERO, &gather, 0, None, &s)
}

#[test]
fn uniform_radiance_has_no_gradient() {
    let l = Rgb::new(0.3, 0.5, 0.7);
    let n = Vec3::new(0.3, 1.0, -0.2).normalize();
    // Distances vary with direction; the radiance does not.
    let r = record_from(n, |d| (l, 0.5 + 3.0 * d.x.abs()));
    let e = r.value.irradiance;
    assert!((e - l * PI).abs().max_element() < 1e-5 * PI, "{e}");
    assert_eq!(r.value.translation_gradient.max_length(), 0.0);
    let rot = r.value.rotation_gradient.max_length();
    assert!(rot < 1e-5 * e.max_element(), "rotation gradient {rot}");
}

/// Distant radiance L(ω) = a + b·ω: E = πa + (2π/3) b·n and ∇_r = (2π/3) n × b, since
/// ∫ ω ωᵀ dω over a hemisphere is (2π/3)·I.
#[test]
fn rotation_gradient_of_radiance_linear_in_direction() {
    let b = [
        Vec3::new(0.3, 0.2, -0.1),
        Vec3::new(-0.2, 0.1, 0.4),
        Vec3::new(0.0, -0.5, 0.2),
    ];
    let n = Vec3::new(0.3, 1.0, -0.2).normalize();
    let r = record_from(n, |d| {
        (
            Rgb::new(1.0 + b[0].dot(d), 1.0 + b[1].dot(d), 1.0 + b[2].dot(d)),
            f32::INFINITY,
        )
    });
    for (c, b) in b.iter().enumerate() {
        let e = PI + 2.0 * PI / 3.0 * b.dot(n);
        let got_e = r.value.irradiance[c];
        assert!(
            (got_e - e).abs() < 2e-3 * e,
            "channel {c}: E {got_e} vs {e}"
        );
        let expected = 2.0 * PI / 3.0 * n.cross(*b);
        let got = r.value.rotation_gradient.0[c];
        assert!(
            (got - expected).length() < 0.01 * expected.length(),
            "channel {c}: ∇_r {got} vs {expected}"
        );
    }
    // Escaping rays: no translation gradient, R_k at its upper clamp.
    assert_eq!(r.value.translation_gradient.max_length(), 0.0);
    assert_eq!(r.harmonic_distance_m, settings().r_max_m);
}

/// A half-plane emitter of radiance L at height h above p, its edge at horizontal offset
/// x from p (x > 0: p lies under the emitter). The directions that reach it are those on
/// the emitter's side of the plane through p and the edge, so (Lambert's formula for a
/// lune) E(x) = (πL/2)(1 + x/√(h² + x²)) and dE/dx = (πL/2)·h²/(h² + x²)^{3/2}.
fn half_plane(x: f32, h: f32, l: f32) -> (f32, f32) {
    let e = 0.5 * PI * l * (1.0 + x / (h * h + x * x).sqrt());
    let de = 0.5 * PI * l * h * h / (h * h + x * x).powf(1.5);
    (e, de)
}

#[test]
fn translation_gradient_under_a_half_plane_emitter() {
    let (h, l) = (1.0f32, 2.0f32);
    for x in [0.0f32, 0.5, -0.5, 1.0] {
        // p at the origin facing +Y; the emitter covers world x > −x at y = h.
        let r = record_from(Vec3::Y, |d| {
            if d.y <= 0.0 {
                return (Rgb::ZERO, f32::INFINITY);
            }
            let t = h / d.y;
            if d.x * t > -x {
                (Rgb::splat(l), t)
            } else {
                (Rgb::ZERO, f32::INFINITY)
            }
        });
        let (e, de) = half_plane(x, h, l);
        let got_e = r.value.irradiance.x;
        assert!((got_e - e).abs() < 0.01 * e, "x = {x}: E {got_e} vs {e}");
        let g = r.value.translation_gradient.0[0];
        assert!(
            (g.x - de).abs() < 0.03 * de,
            "x = {x}: dE/dx {} vs {de}",
            g.x
        );
        assert!(g.z.abs() < 0.03 * de, "x = {x}: dE/dz {} should be 0", g.z);
        assert!(
            g.y.abs() < 1e-6 * de,
            "the gradient lies in the tangent plane"
        );
    }
}

#[test]
fn r_k_clamps_and_the_gradient_limit() {
    // Everything 1 mm away: R = 1 mm, raised to r_min.
    let s = RecordSettings {
        r_min_m: 0.05,
        r_max_m: 2.0,
        gradient_limit: false,
        ..RecordSettings::default()
    };
    let near = HemisphereGather::from_fn(Vec3::Y, &s, 0, |_| (Rgb::ONE, 1e-3)).unwrap();
    assert!((near.harmonic_mean_distance() - 1e-3).abs() < 1e-7);
    let r = IrradianceRecord::from_gather(Vec3::ZERO, &near, 0, None, &s);
    assert_eq!(r.harmonic_distance_m, 0.05);
    // Everything escapes: infinite, lowered to r_max.
    let far = HemisphereGather::from_fn(Vec3::Y, &s, 0, |_| (Rgb::ONE, f32::INFINITY)).unwrap();
    assert!(far.harmonic_mean_distance().is_infinite());
    let r = IrradianceRecord::from_gather(Vec3::ZERO, &far, 0, None, &s);
    assert_eq!(r.harmonic_distance_m, 2.0);
    // Under the half-plane with the edge overhead (x = 0, h = 1): half the rays hit the
    // plane, so R = 2·(3h/2) = 3 m, but E/|∇_p E| = h = 1 m: the gradient limit binds.
    let gather = |limit| {
        let s = RecordSettings {
            gradient_limit: limit,
            ..settings()
        };
        let g = HemisphereGather::from_fn(Vec3::Y, &s, 3, |d| {
            if d.y > 0.0 && d.x > 0.0 {
                (Rgb::ONE, 1.0 / d.y)
            } else {
                (Rgb::ZERO, f32::INFINITY)
            }
        })
        .unwrap();
        IrradianceRecord::from_gather(Vec3::ZERO, &g, 0, None, &s).harmonic_distance_m
    };
    let (unlimited, limited) = (gather(false), gather(true));
    assert!((unlimited - 3.0).abs() < 0.03, "R = {unlimited}");
    assert!((limited - 1.0).abs() < 0.03, "R = {limited}");
}

#[test]
fn bad_record_points_are_errors() {
    let s = settings();
    assert!(HemisphereGather::from_fn(Vec3::ZERO, &s, 0, |_| (Rgb::ONE, 1.0)).is_err());
    assert!(HemisphereGather::from_fn(Vec3::NAN, &s, 0, |_| (Rgb::ONE, 1.0)).is_err());
    let world = World::new(illume_scene::builtin::furnace(0.5, Rgb::ONE));
    let e = IrradianceRecord::compute(&world, Vec3::INFINITY, Vec3::Y, 0, None, 0, &s)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("radiance_cache:"), "{e}");
}

/// A one-sided diffuse plane (albedo ρ, 2 km square) 1 m below a record that faces it,
/// under a uniform sky L: the plane reflects ρL everywhere (it sees the whole sky and
/// nothing else), so the reflected irradiance is πρL (the 2 km plane misses only a
/// 10⁻⁶ part of the projected solid angle), and R_k is the harmonic mean of h/cos θ
/// under cosine weighting: h/E[cos θ] = 3h/2.
#[test]
fn a_gather_through_continue_path_sees_a_plane_under_the_sky() {
    let (rho, sky) = (0.6f32, Rgb::new(1.0, 0.5, 0.25));
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        base_color: Rgb::splat(rho),
        double_sided: false,
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::Z * 1000.0, Vec3::X * 1000.0, m)); // faces +y
    b.placed("ground", mesh, Trs::IDENTITY, false);
    let mut scene = b.finish("test:ground-under-sky");
    scene.sky = Some(Sky::Uniform { radiance: sky });
    let world = World::new(scene);
    let s = settings();
    let p = Vec3::new(0.2, 1.0, -0.3);
    let r = IrradianceRecord::compute(&world, p, -Vec3::Y, 0, None, 5, &s).unwrap();
    let expected = sky * (PI * rho);
    let e = r.value.irradiance;
    assert!(
        (e - expected).abs().max_element() < 1e-4 * expected.max_element(),
        "{e} vs {expected}"
    );
    assert!(
        (r.harmonic_distance_m - 1.5).abs() < 0.01,
        "R = {}",
        r.harmonic_distance_m
    );
    assert!(r.value.translation_gradient.max_length() < 1e-4 * e.max_element());
    assert!(r.value.rotation_gradient.max_length() < 1e-4 * e.max_element());
    // Facing the sky instead: nothing is reflected towards the record (the renderer's
    // direct light covers the sky), unless all incoming light is asked for: πL.
    let up = IrradianceRecord::compute(&world, p, Vec3::Y, 0, None, 5, &s).unwrap();
    assert_eq!(up.value.irradiance, Rgb::ZERO);
    let all = RecordSettings {
        incoming: Incoming::All,
        ..s
    };
    let up = IrradianceRecord::compute(&world, p, Vec3::Y, 0, None, 5, &all).unwrap();
    assert!((up.value.irradiance - sky * PI).abs().max_element() < 1e-5 * PI);
}

/// The furnace (a closed sphere, albedo ρ, emission Le): radiance Le/(1 − ρ) everywhere,
/// of which ρLe/(1 − ρ) reflected. A record at the centre gathers πρLe/(1 − ρ) through
/// `continue_path`'s paths (a Monte Carlo estimate), R_k = 1 m (the radius), and the
/// same key gives the same record.
#[test]
fn a_gather_through_continue_path_in_the_furnace() {
    let (rho, le) = (0.5f32, 1.0f32);
    let world = World::new(illume_scene::builtin::furnace(rho, Rgb::splat(le)));
    let s = settings();
    let n = Vec3::new(0.2, 0.3, 1.0).normalize();
    let r = IrradianceRecord::compute(&world, Vec3::ZERO, n, 0, None, 42, &s).unwrap();
    let expected = PI * rho * le / (1.0 - rho);
    for c in 0..3 {
        let e = r.value.irradiance[c];
        assert!(
            (e - expected).abs() < 0.03 * expected,
            "channel {c}: {e} vs {expected}"
        );
    }
    assert!(
        (r.harmonic_distance_m - 1.0).abs() < 0.01,
        "R = {}",
        r.harmonic_distance_m
    );
    let again = IrradianceRecord::compute(&world, Vec3::ZERO, n, 0, None, 42, &s).unwrap();
    assert_eq!(r, again);
    let other = IrradianceRecord::compute(&world, Vec3::ZERO, n, 0, None, 43, &s).unwrap();
    assert_ne!(r.value.irradiance, other.value.irradiance);
}

/// The same half-plane as a real emissive quad (2 km wide, 1 m up, facing down), traced:
/// the tracer's distances and the emission seen directly give the closed form too.
#[test]
fn translation_gradient_under_a_traced_half_plane() {
    let (h, l, x) = (1.0f32, 2.0f32, 0.5f32);
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        base_color: Rgb::ZERO,
        emission: Rgb::splat(l),
        double_sided: false,
        ..Default::default()
    });
    // Faces −y (X × Z = −Y), covering world x ∈ [−x, 2000 − x].
    let mesh = b.mesh(quad(
        Vec3::new(1000.0 - x, h, 0.0),
        Vec3::X * 1000.0,
        Vec3::Z * 1000.0,
        m,
    ));
    b.placed("emitter", mesh, Trs::IDENTITY, false);
    let world = World::new(b.finish("test:half-plane"));
    let s = RecordSettings {
        incoming: Incoming::All,
        ..settings()
    };
    let r = IrradianceRecord::compute(&world, Vec3::ZERO, Vec3::Y, 0, None, 1, &s).unwrap();
    let (e, de) = half_plane(x, h, l);
    assert!(
        (r.value.irradiance.x - e).abs() < 0.01 * e,
        "E {} vs {e}",
        r.value.irradiance.x
    );
    let g = r.value.translation_gradient.0[0];
    assert!((g.x - de).abs() < 0.03 * de, "dE/dx {} vs {de}", g.x);
}

/// The default R_max (half the scene's diagonal) does not bind inside a closed room: at
/// the floor centre of the cube-in-box the unclamped harmonic mean distance is below it
/// (and above the default R_min).
#[test]
fn default_r_k_clamps_do_not_bind_in_the_cube_in_box() {
    let world = World::new(illume_scene::builtin::load("cube-in-box").unwrap());
    let diagonal = world.scene.bounds().extent().length();
    let s = illume_radiance_cache::RadianceCacheSettings::default().record_settings(diagonal);
    let gather =
        HemisphereGather::trace(&world, Vec3::new(0.0, 1e-3, 0.3), Vec3::Y, 0, &s).unwrap();
    let r = gather.harmonic_mean_distance();
    assert!(
        r < s.r_max_m && r > s.r_min_m,
        "R = {r} m, clamps [{}, {}]",
        s.r_min_m,
        s.r_max_m
    );
}
