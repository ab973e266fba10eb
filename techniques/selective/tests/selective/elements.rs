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
