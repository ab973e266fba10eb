//! Halton periodicity (§4.2, Eq. 3) and the groups' coherence in light and emission
//! cell; the pool's index layout (§5.1, Fig. 1).

use illume_core::sampling::{HaltonScramble, HaltonStream, PRIMES, radical_inverse};
use illume_selective::groups::GroupLayout;
use illume_selective::qmc::{GroupFactors, LightCells, emit};
use illume_transport::World;

/// |Φ_b(i) − Φ_b(i + m·N_g)| < b^−k_b in every factored base, plain and scrambled.
fn check_eq3(factors: &GroupFactors) {
    let n_g = factors.groups();
    let scramble = HaltonScramble::new(7);
    for &(base, k) in factors.factors() {
        let d = PRIMES.iter().position(|&p| p == base).unwrap();
        let bound = (base as f64).powi(-(k as i32));
        for i in (0..100_000u64).step_by(97) {
            for m in [1u64, 2, 3, 17, 100] {
                let j = i + m * n_g;
                let plain = (radical_inverse(base, i) - radical_inverse(base, j)).abs();
                assert!(
                    plain < bound,
                    "base {base}: i {i}, m {m}: {plain} ≥ {bound}"
                );
                let value = |index| {
                    let mut s = HaltonStream::scrambled(index, &scramble);
                    for _ in 0..d {
                        s.next_f64();
                    }
                    s.next_f64()
                };
                let scrambled = (value(i) - value(j)).abs();
                assert!(
                    scrambled < bound,
                    "scrambled base {base}: i {i}, m {m}: {scrambled} ≥ {bound}"
                );
            }
        }
    }
}

#[test]
fn halton_periodicity_holds_for_288_and_10080() {
    let ng288 = GroupFactors::new(&[[2, 5], [3, 2]]);
    assert_eq!(ng288.groups(), 288);
    check_eq3(&ng288);
    let ng10080 = GroupFactors::new(&[[2, 5], [3, 2], [5, 1], [7, 1]]);
    assert_eq!(ng10080.groups(), 10_080);
    check_eq3(&ng10080);
    // The paper's defaults (§7): 4 lights → 2^5·3² = 288, 2 lights → 2^4·3² = 144.
    assert_eq!(GroupFactors::paper_default(4).groups(), 288);
    assert_eq!(GroupFactors::paper_default(2).groups(), 144);
    assert_eq!(GroupFactors::paper_default(1).groups(), 72);
}

/// A scene with four point lights of unequal power.
fn four_lights() -> World {
    let mut scene = illume_scene::builtin::load("cornell-spot").unwrap();
    let base = scene.lights[0].clone();
    for (k, scale) in [(1, 0.5f32), (2, 2.0), (3, 0.25)] {
        let mut l = base.clone();
        l.name = format!("extra{k}");
        if let illume_scene::LightKind::Spot { intensity, .. } = &mut l.kind {
            *intensity *= scale;
        }
        scene.lights.push(l);
    }
    World::new(scene)
}

#[test]
fn photons_one_group_apart_leave_the_same_light_in_the_same_emission_cell() {
    let world = four_lights();
    let probe = LightCells::new(&world.lights, 0);
    assert_eq!(probe.units().len(), 4);
    let factors = GroupFactors::paper_default(4);
    assert_eq!(factors.groups(), 288);
    let cells = LightCells::new(&world.lights, factors.exponent(2));
    assert_eq!(cells.cell_count(), 32);
    // Cells follow power: the 2× light owns the most, every light at least one.
    let owned: Vec<u32> = cells.units().iter().map(|u| u.cells).collect();
    assert_eq!(owned.iter().sum::<u32>(), 32);
    assert!(owned.iter().all(|&c| c >= 1), "{owned:?}");
    assert_eq!(owned.iter().max(), Some(&owned[2]), "{owned:?}");
    let scramble = HaltonScramble::new(3);
    let n_g = factors.groups();
    let bound = 1.0 / 9.0; // second emission coordinate: base 3, k = 2
    for i in (0..20_000u64).step_by(13) {
        let trace = |index: u64| {
            let mut s = HaltonStream::scrambled(index, &scramble);
            let (path, unit) = emit(&world.lights, &cells, &mut s).unwrap();
            (unit, path.ray.dir)
        };
        let (unit_a, _) = trace(i);
        for m in [1u64, 5, 40] {
            let (unit_b, _) = trace(i + m * n_g);
            assert_eq!(
                unit_a,
                unit_b,
                "photons {i} and {} chose different lights",
                i + m * n_g
            );
        }
        // The emission coordinate of base 3 agrees within 3^-2 (Eq. 3).
        let coord = |index: u64| {
            let mut s = HaltonStream::scrambled(index, &scramble);
            s.next_f64();
            s.next_f64()
        };
        assert!((coord(i) - coord(i + n_g)).abs() < bound);
    }
}

#[test]
fn fig1_pilots_and_correctives_partition_the_pool() {
    let layout = GroupLayout {
        groups: 4,
        pilots: 3,
        ratio: 5,
    };
    let n = layout.pool();
    assert_eq!(n, 60);
    let mut owner = vec![None; n as usize];
    for g in 0..layout.groups {
        let photons = layout.photons_of(g, u64::MAX);
        assert_eq!(photons.len() as u64, layout.per_group());
        for &i in &photons {
            assert!(owner[i as usize].is_none(), "photon {i} in two groups");
            owner[i as usize] = Some(g);
            assert_eq!(layout.group_of(i), g);
        }
        // Pilots: g·N_p … (g+1)·N_p − 1, consecutive.
        assert_eq!(photons[..3], [3 * g, 3 * g + 1, 3 * g + 2]);
        // Correctives: N_g·N_p + g + c·N_g, all ≡ g (mod N_g) past the pilots.
        for &i in &photons[3..] {
            assert!(i >= 12);
            assert_eq!((i - 12) % 4, g);
            assert_eq!(i % 4, g, "12 is a multiple of N_g, so i ≡ g (mod N_g) too");
        }
    }
    assert!(
        owner.iter().all(|o| o.is_some()),
        "every photon has a group"
    );
    // Eq. 6: a pilot i raises group i mod N_g, whose correctives lie m·N_g away.
    for i in 0..12 {
        let h = layout.raised_by_pilot(i);
        assert_eq!(h, i % 4);
        assert!(layout.correctives_of(h).all(|c| (c - i) % 4 == 0));
    }
    // An index-order fill that reached photon 20 leaves later photons out.
    assert!(layout.photons_of(1, 20).iter().all(|&i| i < 20));
}
