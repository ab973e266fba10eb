//! Mesh elements (§1, §3): grids partition their triangles; barycentrics and elements
//! map to each other; the furnace's indirect light is analytic.

use illume_core::{Rgb, Vec2};
use illume_selective::elements::{Elements, element_centre, locate, world_area};
use illume_selective::{Selective, SelectiveSettings};
use illume_transport::{GBuffer, Technique, World};

#[test]
fn element_areas_sum_to_their_triangle_and_round_trip() {
    for k in 1..=9u32 {
        let mut seen = vec![false; (k * k) as usize];
        for e in 0..k * k {
            let c = element_centre(k, e);
            assert!(
                c.x >= 0.0 && c.y >= 0.0 && c.x + c.y <= 1.0,
                "k {k} e {e}: {c}"
            );
            let (back, corners) = locate(k, c);
            assert_eq!(back, e, "k {k}: centre of {e} maps to {back}");
            let w: f32 = corners.iter().map(|c| c.2).sum();
            assert!((w - 1.0).abs() < 1e-5);
            assert!(corners.iter().all(|c| c.2 > 0.0 && c.0 + c.1 <= k));
            seen[e as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        // Uniform points: each element receives 1/k² of them (equal areas).
        let n = 200_000;
        let mut count = vec![0u32; (k * k) as usize];
        let mut rng = illume_core::sampling::Pcg32::new(k as u64, 1);
        for _ in 0..n {
            let b = illume_core::sampling::uniform_triangle(Vec2::new(
                rng.next_f64() as f32,
                rng.next_f64() as f32,
            ));
            count[locate(k, b).0 as usize] += 1;
        }
        let expect = n as f64 / (k * k) as f64;
        for (e, &c) in count.iter().enumerate() {
            assert!(
                (c as f64 - expect).abs() < 6.0 * expect.sqrt(),
                "k {k}: element {e} got {c} of {expect}"
            );
        }
    }
}

#[test]
fn element_counts_follow_the_target_and_the_display_is_consistent() {
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    for target in [500u32, 12_400, 50_000] {
        let el = Elements::new(&scene, target, 45.0);
        let triangles: usize = scene
            .instances
            .iter()
            .map(|i| scene.meshes[i.mesh.index()].indices.len())
            .sum();
        assert!(el.len() >= triangles, "at least one element per triangle");
        if target as usize > 4 * triangles {
            let ratio = el.len() as f64 / target as f64;
            assert!(
                (0.6..1.6).contains(&ratio),
                "{} elements for {target}",
                el.len()
            );
        }
    }
    // Object-space grids, world-space areas: a grid's k² elements share the triangle's
    // area equally, so their areas sum to the triangle's.
    let inst = &scene.instances[0];
    let mesh = &scene.meshes[inst.mesh.index()];
    let a = world_area(mesh, 0, &inst.world_from_object);
    assert!(a > 0.0);
}

#[test]
fn furnace_indirect_light_is_rho_squared_le_over_one_minus_rho() {
    // Closed sphere, ρ = 0.5, Le = 1: L = Le/(1 − ρ) in total; the light reflected at
    // least twice is ρ²·Le/(1 − ρ) = 0.5.
    let rho = 0.5f32;
    let world = World::new(illume_scene::builtin::furnace(rho, Rgb::ONE));
    let settings = SelectiveSettings {
        pilots_per_group: 400,
        ratio: 16,
        element_count: 2000,
        max_bounces: 200,
        warm_up: false,
        ..SelectiveSettings::deterministic()
    };
    let mut sel = Selective::for_world(&world, settings).unwrap();
    sel.converge(&world);
    let g = GBuffer::render(&world, 48, 36, Vec2::splat(0.5));
    let img = sel.indirect(&world, &g);
    let expect = rho * rho / (1.0 - rho);
    let mean = img.mean();
    for c in mean.to_array() {
        assert!(
            (c / expect - 1.0).abs() < 0.02,
            "indirect {mean} vs {expect}"
        );
    }
}

/// Barycentrics (b₁, b₂) of `p` in triangle `t` of `mesh` (the points lie in y = 0).
fn barycentrics(mesh: &illume_scene::Mesh, t: usize, p: illume_core::Vec3) -> Vec2 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    let (u, v, w) = (b - a, c - a, p - a);
    let det = u.x * v.z - u.z * v.x;
    Vec2::new((w.x * v.z - w.z * v.x) / det, (u.x * w.z - u.z * w.x) / det)
}

/// A floor of one large triangle beside a thin one sharing its long edge (one mesh,
/// both facing up), so the two sides of the edge get different grid sides.
fn fan_floor() -> illume_scene::Scene {
    use illume_core::Vec3;
    use illume_scene::builtin::SceneBuilder;
    use illume_scene::{Material, Mesh};
    let mut b = SceneBuilder::new();
    let m = b.material(Material::default());
    let mut mesh = Mesh {
        name: "fan".into(),
        ..Default::default()
    };
    // Large triangle (0,0,0) (0,0,4) (4,0,0): normal +y.
    mesh.positions.extend([
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::new(4.0, 0.0, 0.0),
    ]);
    mesh.indices.push([0, 1, 2]);
    // A thin triangle on the far side of its edge (0,0,4)–(4,0,0), sharing it whole
    // (a conforming mesh: no vertex of the model on the edge's inside).
    mesh.positions.push(Vec3::new(2.1, 0.0, 2.1));
    mesh.indices.push([2, 1, 3]);
    crate::common::one_mesh_scene(b, m, mesh, "fan")
}

/// Issue 34 goal 1: shared edges are split alike (grid sides are powers of two, the
/// finer a multiple of the coarser) and the displayed irradiance is continuous across
/// an edge between triangles of different k: the same value from both sides, to float
/// rounding, for arbitrary element values (no T-junction seam).
#[test]
fn displayed_irradiance_is_continuous_across_edges_of_different_k() {
    use illume_core::Vec3;
    use illume_transport::flux::Quanta;
    let scene = fan_floor();
    let mesh = &scene.meshes[0];
    let el = Elements::new(&scene, 400, 45.0);
    let g = &el.grids[0];
    let (k_big, k_small) = (g.k[0], g.k[1..].iter().copied().max().unwrap());
    assert!(k_big > k_small, "k {k_big} beside {k_small}: no split edge");
    for &k in &g.k {
        assert!(
            k.is_power_of_two() && k_big % k == 0,
            "grid sides {:?}",
            g.k
        );
    }
    let mut rng = illume_core::sampling::Pcg32::new(34, 1);
    let acc: Vec<[Quanta; 2]> = (0..el.len())
        .map(|_| {
            let mut q = || Quanta([0; 3].map(|_: i64| (rng.next_f64() * 1e6) as i64));
            [q(), q()]
        })
        .collect();
    let display = el.display(&scene, &acc, 1.0, 1);
    let peak = display
        .irradiance
        .iter()
        .map(|v| v[0].max_element())
        .fold(0.0f32, f32::max);
    let (mut worst, mut seam_before) = (0.0f32, 0.0f32);
    for i in 1..200 {
        let t = i as f32 / 200.0;
        let p = Vec3::new(4.0 * (1.0 - t), 0.0, 4.0 * t);
        let small = 1;
        let e_big = el.irradiance(&display, 0, 0, 0, barycentrics(mesh, 0, p), true);
        let e_small = el.irradiance(&display, 0, 0, small, barycentrics(mesh, small, p), true);
        worst = worst.max((e_big - e_small).abs().max_element());
        seam_before = seam_before.max(e_big.max_element());
    }
    assert!(seam_before > 0.0);
    // Bound: f32 interpolation rounding, 1e-5 of the largest displayed value.
    assert!(
        worst <= 1e-5 * peak,
        "seam of {worst} W/m² across the split edge (peak {peak})"
    );
}

/// Issue 34 goal 1: large triangles are split by the scene's size even when
/// `element_count` asks for fewer elements than the model has triangles.
#[test]
fn large_triangles_are_split_by_the_scene_size_whatever_the_count() {
    let scene = fan_floor();
    let diag = illume_selective::elements::scene_diagonal(&scene);
    // One element asked for: without the bound every triangle is one element.
    let coarse = Elements::new(&scene, 1, 45.0);
    assert_eq!(coarse.len(), 2);
    let el = Elements::with_max_side(&scene, 1, 45.0, 1.0 / 16.0);
    let side = diag / 16.0;
    let big = world_area(&scene.meshes[0], 0, &scene.instances[0].world_from_object) as f64;
    let k = el.grids[0].k[0] as f64;
    // k is one of the two powers of two around √(A/side²).
    let ideal = (big / (side * side)).sqrt();
    assert!(
        k <= 2.0 * ideal && ideal <= 2.0 * k,
        "k {k} for √(A/s²) = {ideal}"
    );
    assert!(el.len() > 2);
}

/// Issue 34 goal 1: the photons' energy lands in the elements whatever their size: the
/// accumulators of a fine element mesh sum, bit for bit, to those of the model's own
/// triangles for the same pool, and to the quanta of every impact after the first traced
/// by the shared kernel; each element's irradiance times its area sums back to it.
#[test]
fn energy_per_element_sums_to_the_pools() {
    use illume_transport::flux::Quanta;
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let run = |max_side: f32| {
        let settings = SelectiveSettings {
            pilots_per_group: 6,
            ratio: 4,
            element_count: 1,
            element_max_side: max_side,
            min_photons_per_element: 0,
            min_impacts_per_element: 0,
            warm_up: false,
            ..SelectiveSettings::deterministic()
        };
        let mut sel = Selective::for_world(&world, settings).unwrap();
        sel.converge(&world);
        let total: Quanta = sel.accumulators().iter().map(|a| a[0] + a[1]).sum();
        (sel, total)
    };
    let (coarse, coarse_total) = run(0.0);
    let (fine, fine_total) = run(1.0 / 32.0);
    assert!(
        fine.elements().len() > coarse.elements().len() + 1000,
        "{} elements against {}",
        fine.elements().len(),
        coarse.elements().len()
    );
    assert_eq!(fine.layout().pool(), coarse.layout().pool());
    assert!(coarse_total.channel_sum() > 0);
    assert_eq!(
        fine_total, coarse_total,
        "energy lost or gained between meshes"
    );
    // Every impact after the first, traced photon by photon through the shared kernel.
    let snapshot = illume_selective::retrace::Snapshot::of(&world, 0, fine.factors().exponent(2));
    let scramble = illume_core::sampling::HaltonScramble::new(fine.settings().seed);
    let path_settings = fine.settings().photon_path();
    let inv_quantum = 1.0 / fine.quantum_w();
    let mut kernel = Quanta::ZERO;
    for i in 0..fine.layout().pool() {
        let mut s = illume_selective::qmc::photon_stream(i, &scramble);
        if let Some((path, _)) = illume_selective::qmc::emit(&world.lights, &snapshot.cells, &mut s)
        {
            world.tracer.scoped(|t| {
                path.run(
                    &world,
                    t,
                    &mut s,
                    &path_settings,
                    &mut illume_transport::photon::PhotonPathStats::default(),
                    |imp| {
                        if imp.bounce >= 1 {
                            kernel += Quanta::from_flux(imp.flux, inv_quantum);
                        }
                    },
                )
            });
        }
    }
    assert_eq!(
        fine_total, kernel,
        "elements hold other energy than the kernel's impacts"
    );
}

/// Power-of-two sides by error diffusion: every side is one of the two powers of two
/// around √(area/target), and the mesh holds Σ area/target elements to within one
/// triangle's worth (equal triangles mix the two sides).
#[test]
fn power_of_two_sides_keep_the_element_count() {
    use illume_selective::elements::grid_sides;
    let areas = vec![10.0f64; 40];
    let target = 10.0 / 300.0; // 300 elements per triangle: 16² = 256 or 32² = 1024.
    let k = grid_sides(&areas, target);
    assert!(k.iter().all(|&k| k == 16 || k == 32), "{k:?}");
    let total: u32 = k.iter().map(|k| k * k).sum();
    let want = 40.0 * 300.0;
    assert!(
        (total as f64 - want).abs() <= 1024.0,
        "{total} elements for {want}"
    );
    // Triangles below the target: one element each.
    assert_eq!(grid_sides(&[0.001, 0.0, f64::NAN], 0.01), vec![1, 1, 1]);
}

/// Issue 34 goal 1: with `min_photons_per_element`, N_p is the smallest that gives the
/// pool that many photons per element; without it the pool is N_g·N_p·R as set.
#[test]
fn the_pool_grows_with_the_elements() {
    let world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let settings = |min: u32| SelectiveSettings {
        pilots_per_group: 8,
        ratio: 4,
        element_count: 3000,
        min_photons_per_element: min,
        min_impacts_per_element: 0,
        warm_up: false,
        ..SelectiveSettings::deterministic()
    };
    let plain = Selective::for_world(&world, settings(0)).unwrap();
    assert_eq!(plain.layout().pilots, 8);
    let scaled = Selective::for_world(&world, settings(16)).unwrap();
    let (l, n) = (scaled.layout(), scaled.elements().len() as u64);
    assert!(l.pool() >= 16 * n, "{} photons for {n} elements", l.pool());
    assert!(
        l.groups * (l.pilots - 1) * l.ratio < 16 * n,
        "N_p {} not the least",
        l.pilots
    );
}

/// Issue 34 goal 3: at its defaults selective lays out the paper's ROOM configuration on
/// `builtin:room` (§7: four lights → N_g = 2^5·3^2 = 288, 1 152 000 photons, about
/// 12 400 mesh elements).
#[test]
fn builtin_room_gets_the_papers_room_layout() {
    let world = World::new(illume_scene::builtin::load("room").unwrap());
    assert_eq!(world.scene.lights.len(), 4);
    let sel = Selective::for_world(
        &world,
        SelectiveSettings {
            warm_up: false,
            ..SelectiveSettings::default()
        },
    )
    .unwrap();
    assert_eq!(sel.factors().factors(), &[(2, 5), (3, 2)]);
    assert_eq!(sel.layout().pool(), 1_152_000);
    let n = sel.elements().len() as f64;
    assert!((n / 12_400.0 - 1.0).abs() < 0.1, "{n} elements");
}

/// Issue 34 goal 3: `scenarios/selective_house.toml`'s settings lay out the paper's HOUSE
/// configuration on `builtin:house` (§7: two lights, N_g = 2^4·3^2 = 144, 1 728 000
/// photons, about 377 900 mesh elements). The settings are read from the scenario file
/// itself, so the scenario cannot drift from what this test pins.
#[test]
fn builtin_house_with_its_scenario_gets_the_papers_house_layout() {
    let world = World::new(illume_scene::builtin::load("house").unwrap());
    assert_eq!(world.scene.lights.len(), 2);
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/selective_house.toml"
    ))
    .unwrap();
    let scenario: toml::Table = toml::from_str(&text).unwrap();
    let technique = &scenario["technique"].as_array().unwrap()[0];
    assert_eq!(technique["name"].as_str(), Some("selective"));
    let mut settings: SelectiveSettings = technique["settings"].clone().try_into().unwrap();
    settings.warm_up = false;
    let sel = Selective::for_world(&world, settings).unwrap();
    assert_eq!(sel.factors().factors(), &[(2, 4), (3, 2)]);
    assert_eq!(sel.layout().pool(), 1_728_000);
    let n = sel.elements().len() as f64;
    assert!((n / 377_900.0 - 1.0).abs() < 0.1, "{n} elements");
}
