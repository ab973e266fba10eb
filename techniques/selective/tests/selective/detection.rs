//! Detection (§5.2): a photon is flagged for re-tracing exactly when its path differs
//! between from-scratch traces of the old and the new scene; scripted pilot hits give
//! the hand-computed priorities (§5.3); phantoms follow the M₁ → M₂ → M₃ example.

use illume_core::sampling::HaltonScramble;
use illume_core::{Affine3A, Rgb, Vec3};
use illume_scene::{InstanceId, Material};
use illume_selective::groups::GroupLayout;
use illume_selective::masking::{MaskingView, TextureMasking};
use illume_selective::qmc::{GroupFactors, emit, photon_stream};
use illume_selective::retrace::{Frustum, Snapshot, TraceContext, UnionWorld};
use illume_selective::{Selective, SelectiveSettings};
use illume_transport::photon::PhotonPathStats;
use illume_transport::{Technique, World};

use crate::common;

/// A floor, a grey box above it and a point light.
fn box_scene() -> World {
    common::box_scene(|b| {
        b.material(Material {
            base_color: Rgb::splat(0.6),
            ..Default::default()
        })
    })
}

type Impacts = Vec<(u32, u32, [u32; 3])>;

fn path_of(world: &World, snapshot: &Snapshot, scramble: &HaltonScramble, i: u64) -> Impacts {
    let settings = SelectiveSettings::default().photon_path();
    let mut s = photon_stream(i, scramble);
    let mut out = Vec::new();
    if let Some((path, _)) = emit(&world.lights, &snapshot.cells, &mut s) {
        world.tracer.scoped(|t| {
            path.run(
                world,
                t,
                &mut s,
                &settings,
                &mut PhotonPathStats::default(),
                |imp| {
                    out.push((
                        imp.hit.instance.0,
                        imp.hit.triangle,
                        imp.hit.position.to_array().map(f32::to_bits),
                    ))
                },
            )
        });
    }
    out
}

#[test]
fn flagged_photons_are_exactly_those_whose_paths_changed() {
    let old = box_scene();
    let mut new = old.with_scene(old.scene.clone());
    let boxed = InstanceId(1);
    let to = Affine3A::from_translation(Vec3::new(0.9, 0.0, -0.4))
        * new.scene.instances[1].world_from_object;
    new.apply_edit(&illume_scene::Edit::SetInstanceTransform {
        instance: boxed,
        world_from_object: to,
    })
    .unwrap();
    let factors = GroupFactors::paper_default(1);
    let k2 = factors.exponent(2);
    let (s_old, s_new) = (Snapshot::of(&old, 0, k2), Snapshot::of(&new, 1, k2));
    let union = UnionWorld::new(&new, &s_old, &s_new);
    assert_eq!(union.world.scene.instances.len(), 3, "one phantom");
    let scramble = HaltonScramble::new(0);
    let elements = illume_selective::elements::Elements::new(&old.scene, 500, 45.0);
    let layout = GroupLayout {
        groups: factors.groups(),
        pilots: 4,
        ratio: 4,
    };
    let frustum = Frustum::of(&new.scene, 1.0);
    let masking = TextureMasking::disabled();
    let ctx = TraceContext {
        elements: &elements,
        layout,
        scramble: &scramble,
        path: SelectiveSettings::default().photon_path(),
        inv_quantum: 1e6,
        frustum: &frustum,
        masking: &masking,
        view: MaskingView::of(&frustum, 240),
    };
    let (mut flagged, mut changed) = (0, 0);
    for i in 0..4000u64 {
        let out = ctx.retrace(&union, &s_old, &s_new, &[i]);
        let differs = path_of(&old, &s_old, &scramble, i) != path_of(&new, &s_new, &scramble, i);
        assert_eq!(
            out.invalid == 1,
            differs,
            "photon {i}: flagged {} but paths differ: {differs}",
            out.invalid
        );
        flagged += out.invalid;
        changed += differs as u64;
    }
    assert_eq!(flagged, changed);
    assert!(
        changed > 200 && changed < 3000,
        "{changed} of 4000 photons changed"
    );
}

#[test]
fn phantoms_follow_m1_m2_m3_and_pilots_raise_the_groups_that_hold_them() {
    let mut world = box_scene();
    let settings = SelectiveSettings {
        pilots_per_group: 20,
        ratio: 4,
        element_count: 500,
        warm_up: false,
        visibility_weight: 0.0,
        // The pool as written (N_p not raised for the elements).
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        ..SelectiveSettings::deterministic()
    };
    let mut sel = Selective::for_world(&world, settings).unwrap();
    sel.converge(&world);
    let n_g = sel.layout().groups;
    let m1 = world.scene.instances[1].world_from_object;
    let m2 = Affine3A::from_translation(Vec3::new(0.8, 0.0, 0.0)) * m1;
    let m3 = Affine3A::from_translation(Vec3::new(-1.6, 0.0, 0.3)) * m2;
    let edit = |world: &mut World, sel: &mut Selective, to: Affine3A| {
        let c = world
            .apply_edit(&illume_scene::Edit::SetInstanceTransform {
                instance: InstanceId(1),
                world_from_object: to,
            })
            .unwrap();
        sel.scene_changed(world, &c);
    };
    // t₂: M₁ → M₂. Every group holds the phantom at M₁.
    edit(&mut world, &mut sel, m2);
    assert_eq!(sel.stale_groups(), n_g);
    // Re-trace a third of the groups (they are now current at M₂). Whenever a stale
    // group has P > 0 (its residue's pilots met the box), the highest is re-traced next
    // (V = 1: no visibility weight), and its P is then 0.
    let mut followed = 0;
    for _ in 0..n_g / 3 {
        let best = (0..n_g)
            .filter(|&g| sel.is_stale(g))
            .max_by(|&a, &b| {
                sel.priority(a)
                    .p
                    .total_cmp(&sel.priority(b).p)
                    .then(b.cmp(&a))
            })
            .unwrap();
        let top = sel.priority(best).p;
        sel.step(&world);
        if top > 0.0 {
            assert!(
                !sel.is_stale(best),
                "group {best} with P = {top} was not next"
            );
            assert_eq!(sel.priority(best).p, 0.0);
            followed += 1;
        }
    }
    assert!(followed > 0, "no pilot met the moved box");
    assert_eq!(n_g - sel.stale_groups(), n_g / 3);
    // t₃: M₂ → M₃. Groups re-traced at t₂ hold a phantom at M₂; the others still hold
    // the one at M₁ — never both (one epoch per group).
    edit(&mut world, &mut sel, m3);
    assert_eq!(sel.stale_groups(), n_g);
    let before = sel.counters().photons_invalid;
    sel.converge(&world);
    assert!(sel.counters().photons_invalid > before);
    // Converged: equal to a from-scratch trace at M₃.
    let mut fresh = Selective::for_world(&world, sel.settings().clone()).unwrap();
    fresh.converge(&world);
    assert!(sel.accumulators() == fresh.accumulators());
}

#[test]
fn priority_is_v_times_p_with_v_counted_after_enough_pilots() {
    use illume_selective::groups::Priority;
    let p = Priority {
        p: 3.0,
        pilots_seen: 8,
        pilots_visible: 2,
    };
    // Not enough pilots since the camera moved: V = 1.
    assert_eq!(p.score(false, 4.0), 3.0);
    // V = 1 + 4 · 2/8 = 2.
    assert_eq!(p.score(true, 4.0), 6.0);
    // No pilots seen: V = 1; P = 0: score 0 whatever V.
    assert_eq!(
        Priority {
            p: 2.0,
            ..Default::default()
        }
        .score(true, 4.0),
        2.0
    );
    assert_eq!(
        Priority {
            p: 0.0,
            pilots_seen: 5,
            pilots_visible: 5
        }
        .score(true, 4.0),
        0.0
    );
}

/// Issue 34 goal 5: a change list that holds a camera move beside a change photons see
/// (a light change, an object move) resets every group's view counters (§5.3's V)
/// exactly as a camera move alone does.
#[test]
fn a_camera_move_beside_a_light_change_resets_the_view_counters() {
    use illume_scene::{Edit, LightId, LightKind};
    let mut world = box_scene();
    let settings = SelectiveSettings {
        pilots_per_group: 4,
        ratio: 4,
        element_count: 500,
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        warm_up: false,
        // A light change never restarts (a restart clears the priorities anyway).
        restart_fraction: 1.0,
        ..SelectiveSettings::deterministic()
    };
    let mut sel = Selective::for_world(&world, settings).unwrap();
    sel.converge(&world);
    let seen = |sel: &Selective| {
        (0..sel.layout().groups)
            .map(|g| sel.priority(g).pilots_seen + sel.priority(g).pilots_visible)
            .sum::<u64>()
    };
    assert!(seen(&sel) > 0, "the fill counted no pilots");
    let cam = world.scene.camera.world_from_camera;
    let mut changes = world
        .apply_edit(&Edit::SetCameraTransform {
            world_from_camera: Affine3A::from_translation(Vec3::new(0.5, 0.0, 0.0)) * cam,
        })
        .unwrap();
    changes.extend(
        world
            .apply_edit(&Edit::SetLightKind {
                light: LightId(0),
                kind: LightKind::Point {
                    intensity: Rgb::splat(12.0),
                },
            })
            .unwrap(),
    );
    assert_eq!(changes.len(), 2, "{changes:?}");
    sel.scene_changed(&world, &changes);
    assert_eq!(sel.counters().restarts, 0);
    assert_eq!(sel.stale_groups(), sel.layout().groups);
    assert_eq!(seen(&sel), 0, "V counters kept across a camera move");
}
