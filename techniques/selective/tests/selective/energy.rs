//! Exactness: after any mix of instance, material and light changes interleaved with
//! partial updates, updating until nothing is stale leaves every accumulator equal to
//! a from-scratch trace of the pool in the final scene, bit for bit (§5.2: negative
//! photons cancel their positive twins exactly in integer quanta).

use illume_core::{Affine3A, Rgb, Vec3};
use illume_scene::{Edit, InstanceId, LightId, MaterialId};
use illume_selective::{GroupOrder, Selective, SelectiveSettings};
use illume_transport::{Budget, Technique, World};

fn small(order: GroupOrder, restart_fraction: f32) -> SelectiveSettings {
    SelectiveSettings {
        pilots_per_group: 12,
        ratio: 4,
        element_count: 1500,
        warm_up: false,
        order,
        restart_fraction,
        // The pool as written (N_p not raised for the elements): a grown pool is then
        // a fresh pool of the larger R.
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        ..SelectiveSettings::deterministic()
    }
}

fn instance(world: &World, name: &str) -> InstanceId {
    InstanceId(
        world
            .scene
            .instances
            .iter()
            .position(|i| i.name == name)
            .unwrap_or_else(|| panic!("no instance {name}")) as u32,
    )
}

/// A fresh technique on the final world, converged: the from-scratch oracle.
fn from_scratch(world: &World, settings: &SelectiveSettings) -> Selective {
    let mut s = Selective::for_world(world, settings.clone()).unwrap();
    s.converge(world);
    s
}

fn apply(world: &mut World, sel: &mut Selective, edit: Edit) {
    let changes = world.apply_edit(&edit).unwrap();
    let r = sel.scene_changed(world, &changes);
    assert_eq!(r, illume_transport::ChangeResponse::Updated);
}

fn run(order: GroupOrder, restart_fraction: f32) -> (u64, u64) {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let settings = small(order, restart_fraction);
    let mut sel = Selective::for_world(&world, settings.clone()).unwrap();
    sel.converge(&world);
    let sphere = instance(&world, "sphere");
    let tall = instance(&world, "tall_box");
    let budget = Budget {
        work: Some(1500),
        time_ms: None,
    };
    let mut moved = Affine3A::from_translation(Vec3::new(0.3, 0.0, 0.2))
        * world.scene.instances[sphere.index()].world_from_object;
    // Move the sphere, update part of the way, move it again (groups now hold two
    // different phantoms), change a material, move the light, move the box.
    apply(
        &mut world,
        &mut sel,
        Edit::SetInstanceTransform {
            instance: sphere,
            world_from_object: moved,
        },
    );
    sel.advance(&world, &budget);
    moved = Affine3A::from_translation(Vec3::new(-0.5, 0.1, 0.0)) * moved;
    apply(
        &mut world,
        &mut sel,
        Edit::SetInstanceTransform {
            instance: sphere,
            world_from_object: moved,
        },
    );
    sel.advance(&world, &budget);
    let mut m = world.scene.materials[1].clone();
    m.base_color = Rgb::new(0.2, 0.7, 0.3);
    apply(
        &mut world,
        &mut sel,
        Edit::SetMaterial {
            material: MaterialId(1),
            value: m,
        },
    );
    sel.advance(&world, &budget);
    let light = LightId(0);
    let node = world.scene.lights[0].node;
    let at = world.scene.nodes[node.index()].world_from_node;
    apply(
        &mut world,
        &mut sel,
        Edit::SetLightTransform {
            light,
            world_from_light: Affine3A::from_translation(Vec3::new(0.2, 0.0, -0.1)) * at,
        },
    );
    sel.advance(&world, &budget);
    let box_at = world.scene.instances[tall.index()].world_from_object;
    apply(
        &mut world,
        &mut sel,
        Edit::SetInstanceTransform {
            instance: tall,
            world_from_object: Affine3A::from_rotation_y(0.3) * box_at,
        },
    );
    sel.converge(&world);
    assert_eq!(sel.stale_groups(), 0);
    let oracle = from_scratch(&world, &settings);
    assert_eq!(sel.filled(), oracle.filled());
    crate::common::assert_same_accumulators(sel.accumulators(), oracle.accumulators());
    let nonzero = oracle
        .accumulators()
        .iter()
        .filter(|a| !a[0].is_zero() || !a[1].is_zero())
        .count();
    assert!(nonzero > 100, "the oracle lit {nonzero} elements");
    let c = sel.counters();
    (c.photons_invalid, c.restarts)
}

#[test]
fn retracing_matches_a_from_scratch_trace_exactly_with_light_retrace() {
    // restart_fraction 1: the moved spot light (all the power) is re-traced, not restarted.
    let (invalid, restarts) = run(GroupOrder::Priority, 1.0);
    assert_eq!(restarts, 0);
    assert!(invalid > 0);
}

#[test]
fn retracing_matches_a_from_scratch_trace_exactly_with_restart() {
    let (_, restarts) = run(GroupOrder::Random, 0.5);
    assert_eq!(restarts, 1, "the moved light restarts the solution");
}

/// Beyond the paper: a static scene's pool grows by rounds of N_p correctives per group
/// up to `max_photons`; the grown pool equals a fresh pool of the larger R exactly, and
/// stays exact through a change made after growing.
#[test]
fn a_grown_pool_equals_a_fresh_pool_of_the_larger_ratio() {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let base = small(GroupOrder::Priority, 0.5);
    let round = {
        let s = Selective::for_world(&world, base.clone()).unwrap();
        s.layout().groups * s.layout().pilots
    };
    let pool = round * base.ratio as u64;
    let grown_settings = SelectiveSettings {
        // Two and a half rounds of head room: two rounds fit, the third does not.
        max_photons: pool + 2 * round + round / 2,
        ..base.clone()
    };
    let mut sel = Selective::for_world(&world, grown_settings).unwrap();
    sel.converge(&world);
    assert_eq!(sel.layout().ratio, base.ratio as u64 + 2);
    assert_eq!(sel.filled(), pool + 2 * round);
    assert_eq!(sel.counters().growth_rounds, 2);
    let larger = SelectiveSettings {
        ratio: base.ratio + 2,
        ..base.clone()
    };
    assert!(sel.accumulators() == from_scratch(&world, &larger).accumulators());

    // A change after growing: the grown pool is updated as a whole.
    let sphere = instance(&world, "sphere");
    let moved = Affine3A::from_translation(Vec3::new(0.2, 0.0, -0.3))
        * world.scene.instances[sphere.index()].world_from_object;
    apply(
        &mut world,
        &mut sel,
        Edit::SetInstanceTransform {
            instance: sphere,
            world_from_object: moved,
        },
    );
    sel.converge(&world);
    assert!(sel.accumulators() == from_scratch(&world, &larger).accumulators());
    // Without max_photons the pool stays at N_g·N_p·R.
    assert_eq!(from_scratch(&world, &base).filled(), pool);
}

/// A change before the pool is traced (an edit before the first frame), or between a
/// partial fill and the warm-up, leaves the same accumulators as a fresh trace of the
/// new scene: the fill brings stale groups up to date before it traces in the current
/// state.
#[test]
fn changes_before_or_during_the_fill_are_exact() {
    for filled_first in [0u64, 700] {
        let mut world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
        let settings = SelectiveSettings {
            warm_up: true,
            ..small(GroupOrder::Priority, 0.5)
        };
        let mut sel = Selective::for_world(&world, settings.clone()).unwrap();
        sel.fill(&world, filled_first);
        let sphere = instance(&world, "sphere");
        let moved = Affine3A::from_translation(Vec3::new(0.3, 0.0, 0.2))
            * world.scene.instances[sphere.index()].world_from_object;
        apply(
            &mut world,
            &mut sel,
            Edit::SetInstanceTransform {
                instance: sphere,
                world_from_object: moved,
            },
        );
        // The warm-up fills the whole pool at the first advance.
        sel.advance(
            &world,
            &Budget {
                work: Some(1),
                time_ms: None,
            },
        );
        assert_eq!(sel.filled(), sel.layout().pool());
        sel.converge(&world);
        assert!(
            sel.accumulators() == from_scratch(&world, &settings).accumulators(),
            "a change after {filled_first} photons of the fill is not exact"
        );
    }
}
