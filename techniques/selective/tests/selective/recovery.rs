//! Progressive update (§3, §5.3): after a change, the error against the from-scratch
//! solution of the new scene falls as groups are re-traced and ends at zero; priority
//! order finds the photons a sphere move invalidated sooner than random order.

use illume_core::{Affine3A, Vec3};
use illume_scene::{Edit, InstanceId, LightId, SceneChange};
use illume_selective::{GroupOrder, Selective, SelectiveSettings};
use illume_transport::{Technique, World};

fn settings(order: GroupOrder) -> SelectiveSettings {
    SelectiveSettings {
        pilots_per_group: 60,
        ratio: 16,
        element_count: 3000,
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        warm_up: false,
        restart_fraction: 1.0,
        order,
        ..SelectiveSettings::deterministic()
    }
}

fn sphere(world: &World) -> InstanceId {
    InstanceId(
        world
            .scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .unwrap() as u32,
    )
}

fn sphere_move(world: &mut World) -> Vec<SceneChange> {
    let s = sphere(world);
    let to = Affine3A::from_translation(Vec3::new(0.3, 0.0, 0.0))
        * world.scene.instances[s.index()].world_from_object;
    world
        .apply_edit(&Edit::SetInstanceTransform {
            instance: s,
            world_from_object: to,
        })
        .unwrap()
}

fn light_move(world: &mut World) -> Vec<SceneChange> {
    let node = world.scene.lights[0].node;
    let at = world.scene.nodes[node.index()].world_from_node;
    world
        .apply_edit(&Edit::SetLightTransform {
            light: LightId(0),
            world_from_light: Affine3A::from_translation(Vec3::new(0.25, 0.0, 0.1)) * at,
        })
        .unwrap()
}

/// L1 distance in quanta between two accumulator sets.
fn error(a: &Selective, b: &Selective) -> f64 {
    a.accumulators()
        .iter()
        .zip(b.accumulators())
        .map(|(x, y)| {
            (0..2)
                .map(|s| {
                    (x[s] - y[s])
                        .0
                        .iter()
                        .map(|q| q.unsigned_abs() as f64)
                        .sum::<f64>()
                })
                .sum::<f64>()
        })
        .sum()
}

/// Errors after every group, and relevant photons found after every group.
fn curve(change: fn(&mut World) -> Vec<SceneChange>, order: GroupOrder) -> (Vec<f64>, Vec<u64>) {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let mut sel = Selective::for_world(&world, settings(order)).unwrap();
    sel.converge(&world);
    let changes = change(&mut world);
    sel.scene_changed(&world, &changes);
    let mut oracle = Selective::for_world(&world, settings(order)).unwrap();
    oracle.converge(&world);
    let mut errors = vec![error(&sel, &oracle)];
    let mut found = vec![0];
    let start = sel.counters().photons_invalid;
    while sel.stale_groups() > 0 {
        sel.step(&world);
        errors.push(error(&sel, &oracle));
        found.push(sel.counters().photons_invalid - start);
    }
    (errors, found)
}

fn assert_falls(name: &str, errors: &[f64]) {
    let n = errors.len() - 1;
    assert!(errors[0] > 0.0, "{name}: the change made no difference");
    assert_eq!(
        errors[n], 0.0,
        "{name}: not exactly the from-scratch solution at the end"
    );
    let window = (n / 10).max(1);
    let mut previous = errors[0];
    for k in (window..=n).step_by(window) {
        assert!(
            errors[k] <= 1.05 * previous,
            "{name}: error rose from {previous} to {} at group {k} of {n}",
            errors[k]
        );
        previous = errors[k];
    }
}

#[test]
fn error_falls_to_zero_after_a_sphere_move_and_a_light_move() {
    let (sphere_errors, _) = curve(sphere_move, GroupOrder::Priority);
    assert_falls("sphere", &sphere_errors);
    let (light_errors, _) = curve(light_move, GroupOrder::Priority);
    assert_falls("light", &light_errors);
}

#[test]
fn priority_order_finds_relevant_photons_sooner_than_random_order() {
    let (_, priority) = curve(sphere_move, GroupOrder::Priority);
    let (_, random) = curve(sphere_move, GroupOrder::Random);
    let n = priority.len() - 1;
    assert_eq!(
        priority[n], random[n],
        "the same photons are relevant either way"
    );
    for f in [0.10, 0.25, 0.50] {
        let k = (n as f64 * f).round() as usize;
        assert!(
            priority[k] > random[k],
            "at {:.0} % of the groups: priority found {} of {}, random {}",
            f * 100.0,
            priority[k],
            priority[n],
            random[k]
        );
    }
}
