//! The display's density estimate over neighbouring elements (issue 34 goal 2, beyond
//! the paper): where elements hold few impacts, a display vertex gathers rings of its
//! neighbours; the energy stays, the noise falls, and the gather stops at creases.

use illume_core::{Vec2, Vec3};
use illume_scene::builtin::SceneBuilder;
use illume_scene::{Material, Mesh, Scene};
use illume_selective::elements::{Elements, Gather};
use illume_transport::flux::Quanta;

/// Quads per side of the floor and of the wall.
const N: u32 = 32;

/// A 4 × 4 m floor (y = 0) and a 4 × 4 m wall (x = 0) standing on its edge, each of
/// 2·N² equal triangles, in one mesh: the crease between them (90°) is sharper than the
/// 45° smoothing angle.
fn floor_and_wall() -> Scene {
    let mut b = SceneBuilder::new();
    let m = b.material(Material::default());
    let mut mesh = Mesh {
        name: "floor and wall".into(),
        ..Default::default()
    };
    let side = 4.0 / N as f32;
    for wall in [false, true] {
        let base = mesh.positions.len() as u32;
        for j in 0..=N {
            for i in 0..=N {
                let (u, v) = (i as f32 * side, j as f32 * side);
                mesh.positions.push(if wall {
                    Vec3::new(0.0, u, v)
                } else {
                    Vec3::new(u, 0.0, v)
                });
            }
        }
        let at = |i: u32, j: u32| base + j * (N + 1) + i;
        for j in 0..N {
            for i in 0..N {
                mesh.indices.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
                mesh.indices
                    .push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
            }
        }
    }
    crate::common::one_mesh_scene(b, m, mesh, "floor-and-wall")
}

/// Poisson-distributed impacts (mean `lambda`) from `rng`.
fn poisson(rng: &mut illume_core::sampling::Pcg32, lambda: f64) -> i64 {
    let (limit, mut p, mut n) = ((-lambda).exp(), 1.0, -1);
    while p > limit {
        p *= rng.next_f64();
        n += 1;
    }
    n
}

/// The floor's shown irradiance at every floor triangle's centre: its mean and relative
/// standard deviation, and its mean over the quads beside the wall.
fn floor_stats(el: &Elements, scene: &Scene, acc: &[[Quanta; 2]], counts: &[[i64; 2]]) -> [f64; 3] {
    let display = el.display_with_noise(scene, acc, counts, 1.0, 1);
    let floor = 2 * (N * N) as usize;
    let values: Vec<f64> = (0..floor)
        .map(|t| {
            el.irradiance(&display, 0, 0, t, Vec2::splat(1.0 / 3.0), true)
                .x as f64
        })
        .collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64;
    // Triangles of the quads in the column at x = 0, beside the wall: their mean.
    let column: Vec<f64> = (0..floor)
        .filter(|t| ((t / 2) as u32).is_multiple_of(N))
        .map(|t| values[t])
        .collect();
    let by_wall = column.iter().sum::<f64>() / column.len() as f64;
    [mean, var.sqrt() / mean, by_wall]
}

/// Issue 34 goal 2: on a floor of tiny elements holding half an impact each on average (as
/// the finely tessellated objects of Dabrovic Sponza, whose triangles are each one
/// element), the gather at the default settings keeps the mean irradiance within 2 % of
/// the impacts' own, cuts the noise of the shown irradiance at least 2-fold against each vertex
/// showing its own elements (the paper's display), leaves a constant irradiance exact,
/// and does not gather across the crease to a wall 4× brighter.
#[test]
fn the_gather_keeps_the_energy_cuts_the_noise_and_stops_at_creases() {
    let scene = floor_and_wall();
    let mut el = Elements::new(&scene, 10, 45.0);
    assert_eq!(el.len(), 4 * (N * N) as usize, "one element per triangle");
    let floor = 2 * (N * N) as usize;
    let element_area = 16.0 / floor as f64;
    // Floor: E = 1 W/m² from half an impact per element on average (the grey sphere of
    // scenarios/selective_sponza.toml holds about that many); wall: E = 4 W/m².
    let (lambda, q_floor) = (0.5, (element_area / 0.5 * 1e6) as i64);
    let mut rng = illume_core::sampling::Pcg32::new(34, 2);
    let (mut acc, mut counts) = (Vec::new(), Vec::new());
    for e in 0..el.len() {
        let n = poisson(&mut rng, lambda);
        let q = if e < floor { q_floor } else { 4 * q_floor };
        acc.push([Quanta([n * q; 3]), Quanta::ZERO]);
        counts.push([n, 0]);
    }
    // The irradiance these impacts carry (their Poisson total, not its expectation).
    let floor_quanta: i64 = acc[..floor].iter().map(|a| a[0].0[0]).sum();
    let truth = floor_quanta as f64 / 16.0;
    let [plain_mean, plain_noise, _] = floor_stats(&el, &scene, &acc, &counts);
    let defaults = illume_selective::SelectiveSettings::default();
    el.set_gather(Gather {
        impacts: defaults.gather_impacts,
        max_rings: defaults.gather_rings,
    });
    let [mean, noise, by_wall] = floor_stats(&el, &scene, &acc, &counts);
    for (what, m) in [("plain", plain_mean), ("gathered", mean)] {
        assert!(
            (m / truth - 1.0).abs() < 0.02,
            "{what} floor mean {m} against {truth}"
        );
    }
    assert!(
        noise * 2.0 <= plain_noise,
        "relative noise {noise:.3} gathered against {plain_noise:.3} plain"
    );
    // The wall is 4× brighter: a gather across the crease would lift the floor beside it
    // towards 2.5× (half its rings on the wall); its own noise keeps it within 1.25×.
    assert!(
        by_wall < 1.25 * truth,
        "floor beside the wall shows {by_wall} (truth {truth}): gathered across the crease"
    );
    // A constant irradiance stays exact (the estimate is a ratio of flux to area).
    let flat: Vec<[Quanta; 2]> = (0..el.len())
        .map(|_| [Quanta([q_floor; 3]), Quanta::ZERO])
        .collect();
    let ones = vec![[1, 0]; el.len()];
    let [flat_mean, flat_noise, _] = floor_stats(&el, &scene, &flat, &ones);
    let exact = q_floor as f64 / element_area;
    assert!(
        (flat_mean / exact - 1.0).abs() < 1e-5 && flat_noise < 1e-5,
        "constant field shown as {flat_mean} ± {flat_noise} (exact {exact})"
    );
}

/// Issue 34 goal 7: the temporal filter's noise estimate gives an element side without
/// impacts the noise of one impact, not zero. Before, a vertex whose elements lost their
/// single impacts (a light that moved a little; a prefix of the pool shown after a
/// restart) counted as a real change and dropped to black in one frame, while impacts
/// arriving were held back as noise: the static parts boiled, and dimly.
#[test]
fn an_element_without_impacts_is_as_noisy_as_one_with_one() {
    let scene = floor_and_wall();
    let el = Elements::new(&scene, 10, 45.0);
    let floor = 2 * (N * N) as usize;
    let q = 1_000_000i64;
    // One impact of q on every element; then the floor's impacts gone (the wall keeps its own).
    let one: Vec<[Quanta; 2]> = (0..el.len())
        .map(|_| [Quanta([q; 3]), Quanta::ZERO])
        .collect();
    let ones = vec![[1i64, 0]; el.len()];
    let mut gone = one.clone();
    let mut counts = ones.clone();
    for e in 0..floor {
        gone[e] = [Quanta::ZERO; 2];
        counts[e] = [0, 0];
    }
    let before = el.display_with_noise(&scene, &one, &ones, 1.0, 1);
    let after = el.display_with_noise(&scene, &gone, &counts, 1.0, 1);
    // A floor vertex away from the wall: (x, z) = (2, 2) m is the floor's vertex
    // (N/2, N/2), shared by elements that all lost their impact.
    let floor_vertex = |d: &illume_selective::elements::Display| {
        let t = 2 * ((N / 2) * N + N / 2) as usize; // the quad at (N/2, N/2): its corner
        el.irradiance(d, 0, 0, t, Vec2::new(0.0, 0.0), true).x
    };
    assert!(floor_vertex(&before) > 0.0 && floor_vertex(&after) == 0.0);
    // The least noise of any vertex's front side: with one impact per element
    // everywhere it is positive; it must stay so once the floor's impacts are gone.
    let least = |noise: &[[f32; 2]]| noise.iter().map(|n| n[0]).fold(f32::INFINITY, f32::min);
    assert!(
        least(&after.noise) > 0.5 * least(&before.noise),
        "the empty floor's least noise {} against {} with one impact each",
        least(&after.noise),
        least(&before.noise)
    );
    // The filter moves such a vertex by alpha towards black, not all the way: the vertex
    // averages six elements, so its noise is 1/√6 of its value and a drop to zero lies
    // within 4σ (with σ = 0 it would pass in full).
    let mut shown = before.irradiance.clone();
    illume_selective::temporal::blend(&mut shown, &after, 0.2, 4.0);
    let shown_display = illume_selective::elements::Display {
        irradiance: shown,
        noise: after.noise.clone(),
    };
    let v = floor_vertex(&shown_display);
    let b = floor_vertex(&before);
    assert!(
        (v / b - 0.8).abs() < 1e-4,
        "the floor vertex shows {v} after losing its impacts ({b} before): expected 0.8 of it"
    );
}
