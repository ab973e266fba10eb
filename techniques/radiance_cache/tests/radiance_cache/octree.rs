//! The record lookup: the octree over spheres of influence answers exactly what testing
//! every sphere answers, through growth of the root and removals, and stays valid.

use illume_core::Vec3;
use illume_core::sampling::{Pcg32, SampleStream};
use illume_radiance_cache::Octree;
use illume_radiance_cache::octree::sphere_contains;

fn point(rng: &mut Pcg32, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * (hi - lo) + Vec3::splat(lo)
}

#[test]
fn octree_matches_brute_force_on_ten_thousand_queries() {
    let mut rng = Pcg32::new(11, 3);
    let mut spheres: Vec<Option<(Vec3, f32)>> = Vec::new();
    let mut tree = Octree::new();
    // 3000 spheres in a 10 m box, radii log-uniform in [1 cm, 2 m]; the first ones near
    // the origin, so later ones make the root grow.
    for id in 0..3000u32 {
        let span = if id < 50 { 0.5 } else { 5.0 };
        let c = point(&mut rng, -span, span);
        let r = 0.01 * 200f32.powf(rng.next_1d());
        tree.insert(id, c, r).unwrap();
        spheres.push(Some((c, r)));
    }
    // Remove 500, move 200 (re-inserting an id replaces its sphere).
    for _ in 0..500 {
        let id = (rng.next_1d() * 3000.0) as usize;
        assert_eq!(tree.remove(id as u32), spheres[id].is_some());
        spheres[id] = None;
    }
    for _ in 0..200 {
        let id = (rng.next_1d() * 3000.0) as usize;
        let (c, r) = (point(&mut rng, -6.0, 6.0), 0.3 * rng.next_1d());
        tree.insert(id as u32, c, r).unwrap();
        spheres[id] = Some((c, r));
    }
    tree.validate().unwrap();
    assert_eq!(tree.len(), spheres.iter().flatten().count());
    let brute = |p: Vec3| -> Vec<u32> {
        spheres
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                s.filter(|&(c, r)| sphere_contains(c, r, p))
                    .map(|_| i as u32)
            })
            .collect()
    };
    let mut hits = 0;
    for q in 0..10_000 {
        // Mostly random points; every tenth at a stored centre or on its sphere's rim.
        let p = match (q % 10, spheres[q % 3000]) {
            (0, Some((c, _))) => c,
            (5, Some((c, r))) => c + Vec3::new(r, 0.0, 0.0),
            _ => point(&mut rng, -7.0, 7.0),
        };
        let expected = brute(p);
        hits += expected.len();
        assert_eq!(tree.containing(p), expected, "query {q} at {p}");
    }
    assert!(hits > 10_000, "the queries must find spheres ({hits})");
}

#[test]
fn bad_spheres_are_refused_and_an_empty_tree_answers_nothing() {
    let mut tree = Octree::new();
    assert!(tree.insert(0, Vec3::NAN, 1.0).is_err());
    assert!(tree.insert(0, Vec3::ZERO, -1.0).is_err());
    assert!(tree.insert(0, Vec3::ZERO, f32::INFINITY).is_err());
    assert!(tree.is_empty());
    assert!(tree.containing(Vec3::ZERO).is_empty());
    tree.validate().unwrap();
    // A zero radius holds its centre only.
    tree.insert(7, Vec3::ONE, 0.0).unwrap();
    assert_eq!(tree.containing(Vec3::ONE), [7]);
    assert!(tree.containing(Vec3::ONE * 1.001).is_empty());
    tree.validate().unwrap();
}
