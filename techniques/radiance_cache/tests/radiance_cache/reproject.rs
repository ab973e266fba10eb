//! The §4.3 reprojection: an unchanged world gives the gather back bit for bit; a quad
//! moved by a known step gives exact sampling at t + 1 outside the holes; on the cube in
//! a box, the next-frame irradiance is within 1 % of tracing the record again.

use illume_core::{Affine3A, Rgb, Vec3};
use illume_radiance_cache::HemisphereGather;
use illume_radiance_cache::record::{Incoming, RecordSettings};
use illume_radiance_cache::reproject::reproject;
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Trs};
use illume_transport::World;

fn settings(strata: u32, jitter: bool, incoming: Incoming) -> RecordSettings {
    RecordSettings {
        theta_strata: strata,
        phi_strata: strata,
        jitter,
        incoming,
        ..RecordSettings::default()
    }
}

#[test]
fn an_unchanged_world_gives_the_gather_back_bit_for_bit() {
    let world = World::new(illume_scene::builtin::load("cube-in-box").unwrap());
    let next = world.at_time(0.0);
    let s = settings(32, true, Incoming::Reflected);
    let p = Vec3::new(0.25, 0.0, -0.4);
    let (g, paths) = HemisphereGather::trace_keeping_paths(&world, p, Vec3::Y, 3, &s).unwrap();
    assert_eq!(
        g,
        HemisphereGather::trace(&world, p, Vec3::Y, 3, &s).unwrap()
    );
    let r = reproject(&world, &next, p, &g, &paths, &s, 64);
    assert_eq!(r.holes, 0);
    assert_eq!(r.gather.cells(), g.cells());
}

/// A black, double-sided quad emitting (1, 2, 3), 0.8 m wide, 1 m above the origin.
fn quad_world() -> World {
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        name: "emitter".into(),
        base_color: Rgb::ZERO,
        emission: Rgb::new(1.0, 2.0, 3.0),
        double_sided: true,
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::X * 0.4, Vec3::Z * 0.4, m));
    b.placed("quad", mesh, Trs::from_translation(Vec3::Y), true);
    World::new(b.finish("test:quad"))
}

#[test]
fn a_quad_moved_by_a_known_step_equals_exact_sampling_outside_the_holes() {
    let world = quad_world();
    let mut moved = world.scene.clone();
    moved.instances[0].world_from_object = Affine3A::from_translation(Vec3::new(0.07, 1.0, 0.03));
    let next = world.with_scene(moved);
    // Rays through the cells' centres, counting emission: the quad's cells are (1, 2, 3).
    let s = settings(48, false, Incoming::All);
    let (g, paths) =
        HemisphereGather::trace_keeping_paths(&world, Vec3::ZERO, Vec3::Y, 1, &s).unwrap();
    let r = reproject(&world, &next, Vec3::ZERO, &g, &paths, &s, 64);
    let exact = HemisphereGather::trace(&next, Vec3::ZERO, Vec3::Y, 1, &s).unwrap();
    let (m, n) = (48i64, 48i64);
    let at = |j: i64, k: i64| exact.cells()[(j * n + k.rem_euclid(n)) as usize].radiance;
    let (mut compared, mut boundary) = (0, 0);
    for j in 0..m {
        for k in 0..n {
            let i = (j * n + k) as usize;
            // Cells whose 3×3 neighbourhood at t + 1 is all quad or all sky: a point
            // landing in them is what the centre ray sees.
            let uniform = (j.max(1) - 1..=(j + 1).min(m - 1))
                .all(|jj| (k - 1..=k + 1).all(|kk| at(jj, kk) == at(j, k)));
            if !uniform {
                boundary += 1;
                continue;
            }
            if r.hole_cells[i] {
                continue;
            }
            compared += 1;
            assert_eq!(
                r.gather.cells()[i].radiance,
                exact.cells()[i].radiance,
                "cell ({j}, {k})"
            );
        }
    }
    // The quad covers a good part of the hemisphere, and the step moved it.
    let quad_cells = exact
        .cells()
        .iter()
        .filter(|c| c.radiance != Rgb::ZERO)
        .count();
    assert!(quad_cells > 300, "{quad_cells}");
    assert!(r.holes > 0, "the quad uncovered cells behind it");
    assert!(
        compared > (m * n) as usize * 8 / 10,
        "{compared} cells compared, {boundary} on edges"
    );
}

#[test]
fn a_one_centimetre_step_keeps_the_irradiance_within_one_percent() {
    // A frame's motion at 1 m/s and 100 frames per second (our assumption for the
    // paper's cube, whose speed and frame rate the paper does not give): the holes
    // the quad leaves behind are filled from their neighbours, which costs little.
    let world = quad_world();
    let mut moved = world.scene.clone();
    moved.instances[0].world_from_object = Affine3A::from_translation(Vec3::new(0.01, 1.0, 0.0));
    let next = world.with_scene(moved);
    let s = settings(64, true, Incoming::All);
    let (g, paths) =
        HemisphereGather::trace_keeping_paths(&world, Vec3::ZERO, Vec3::Y, 1, &s).unwrap();
    let r = reproject(&world, &next, Vec3::ZERO, &g, &paths, &s, 64);
    let exact = HemisphereGather::trace(&next, Vec3::ZERO, Vec3::Y, 1, &s).unwrap();
    assert!(r.holes > 0);
    let (e, x) = (r.gather.irradiance(), exact.irradiance());
    for c in 0..3 {
        assert!((e[c] / x[c] - 1.0).abs() < 0.01, "{e} vs {x}");
    }
}

#[test]
fn next_frame_irradiance_on_the_cube_in_box_is_within_one_percent_of_tracing_again() {
    // The paper's test scene (§6), at an assumed 100 frames per second with the cube
    // moving 1 m/s (the paper gives neither). Records
    // on a 5×5 grid over the floor at frames t and t + 1 with the same rays; the paper
    // reports the estimate "99 % accurate". The worst record, 2 cm from the face coming
    // at it, is printed: there the cube's face spreads over 2–4 times more cells than it
    // has points, and the filled gaps are the estimate's main error.
    let world = World::new(illume_scene::builtin::load("cube-in-box").unwrap()).at_time(0.5);
    let next = world.at_time(0.51);
    let s = settings(64, true, Incoming::Reflected);
    let (mut sum_est, mut sum_kept, mut count, mut worst) = (0.0f64, 0.0f64, 0, 0.0f32);
    for (i, (x, z)) in (0..25).map(|i| {
        (
            i,
            (-0.8 + 0.4 * (i % 5) as f32, -0.8 + 0.4 * (i / 5) as f32),
        )
    }) {
        let p = Vec3::new(x, 0.0, z);
        // Not under the cube (x ∈ [−0.2, 0.2] at t, z ∈ [−0.6, −0.2]).
        if x.abs() < 0.25 && (-0.65..=-0.15).contains(&z) {
            continue;
        }
        let key = 100 + i as u64;
        let (g, paths) =
            HemisphereGather::trace_keeping_paths(&world, p, Vec3::Y, key, &s).unwrap();
        let r = reproject(&world, &next, p, &g, &paths, &s, 64);
        let again = HemisphereGather::trace(&next, p, Vec3::Y, key, &s).unwrap();
        let (e0, e1, est) = (g.irradiance(), again.irradiance(), r.gather.irradiance());
        for c in 0..3 {
            let err = (est[c] / e1[c] - 1.0).abs();
            worst = worst.max(err);
            sum_est += err as f64;
            sum_kept += (e0[c] / e1[c] - 1.0).abs() as f64;
            count += 1;
        }
    }
    let (mean, kept) = (sum_est / count as f64, sum_kept / count as f64);
    eprintln!(
        "{} records: mean error {mean:.5}, worst {worst:.5}, E(t) kept as is {kept:.5}",
        count / 3
    );
    assert!(mean < 0.01, "mean error {mean}");
    assert!(kept > 0.0, "the records see the cube move");
}
