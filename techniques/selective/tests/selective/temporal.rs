//! No boiling (issue 34, goal 7): while the sphere of `builtin:cornell-spot` moves and
//! groups are re-traced a part per frame, the static back wall's indirect light changes
//! from frame to frame far less with the temporal filter than without it; once nothing
//! is stale, frames show the solution itself, bit for bit.

use illume_core::{Affine3A, Vec2, Vec3};
use illume_scene::{Edit, InstanceId};
use illume_selective::{Selective, SelectiveSettings};
use illume_transport::{Budget, GBuffer, Technique, World};

fn settings(temporal_alpha: f32) -> SelectiveSettings {
    SelectiveSettings {
        pilots_per_group: 16,
        ratio: 8,
        element_count: 1500,
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        temporal_alpha,
        ..SelectiveSettings::deterministic()
    }
}

/// Mean relative change of the back wall's indirect light between consecutive frames
/// while the sphere moves 2 cm per frame (a third of the pool re-traced per frame), and
/// the technique after the motion.
fn back_wall_change(temporal_alpha: f32) -> (f64, Selective, World) {
    let mut world = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let mut sel = Selective::for_world(&world, settings(temporal_alpha)).unwrap();
    let per_frame = sel.layout().pool() / 3;
    let sphere = InstanceId(
        world
            .scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .unwrap() as u32,
    );
    let (w, h) = (48, 36);
    // The back wall (z = −1) above the tall box: rows 2–8, columns 12–35 at 48×36.
    let wall: Vec<usize> = (2..9)
        .flat_map(|y| (12..36).map(move |x| y * w + x))
        .collect();
    let budget = Budget {
        work: Some(per_frame),
        time_ms: None,
    };
    let mut frames: Vec<Vec<f32>> = Vec::new();
    for f in 0..14 {
        if f > 0 {
            let to = Affine3A::from_translation(Vec3::new(0.02, 0.0, 0.0))
                * world.scene.instances[sphere.index()].world_from_object;
            let changes = world
                .apply_edit(&Edit::SetInstanceTransform {
                    instance: sphere,
                    world_from_object: to,
                })
                .unwrap();
            sel.scene_changed(&world, &changes);
        }
        sel.advance(&world, &budget);
        let g = GBuffer::render(&world, w as u32, h as u32, Vec2::splat(0.5));
        for &p in &wall {
            let px = g.pixels[p].as_ref().expect("the back wall is there");
            assert_eq!(px.hit.instance.index(), 0, "pixel {p} is not the room");
            assert!(
                px.hit.geometric_normal.z > 0.99,
                "pixel {p} is not the back wall"
            );
        }
        let img = sel.indirect(&world, &g);
        frames.push(
            wall.iter()
                .map(|&p| illume_core::luminance(img.pixels()[p]))
                .collect(),
        );
    }
    // From the fourth frame on: every frame a part of the groups is stale.
    let mean: f64 = frames[3..].iter().flatten().map(|&y| y as f64).sum::<f64>()
        / (frames.len() - 3) as f64
        / wall.len() as f64;
    let change: f64 = frames[3..]
        .windows(2)
        .map(|p| {
            p[0].iter()
                .zip(&p[1])
                .map(|(a, b)| (a - b).abs() as f64)
                .sum::<f64>()
                / wall.len() as f64
        })
        .sum::<f64>()
        / (frames.len() - 4) as f64;
    (change / mean, sel, world)
}

#[test]
fn the_static_back_wall_boils_less_and_the_settled_frame_is_the_solution() {
    let (off, _, _) = back_wall_change(1.0);
    let (on, mut sel, world) = back_wall_change(SelectiveSettings::default().temporal_alpha);
    // Measured (2026-11-28, the defaults 0.1 and 16 σ): 0.0136 without the filter,
    // 0.0021 with it.
    assert!(
        on < 0.3 * off,
        "relative frame-to-frame change of the back wall: {on:.4} with the filter, {off:.4} without"
    );
    // Settled: the frame shows the accumulators' own display.
    sel.converge(&world);
    let shown = sel.frame_display(&world);
    let exact = sel.display(&world);
    assert!(
        shown
            .irradiance
            .iter()
            .zip(&exact.irradiance)
            .all(|(a, b)| a == b),
        "a settled frame differs from the solution"
    );
}

#[test]
fn counts_of_a_retraced_pool_equal_a_fresh_trace() {
    let (_, mut sel, world) = back_wall_change(0.2);
    sel.converge(&world);
    let mut fresh = Selective::for_world(&world, settings(0.2)).unwrap();
    fresh.converge(&world);
    assert_eq!(sel.accumulators(), fresh.accumulators());
    assert_eq!(sel.counts(), fresh.counts());
    assert!(sel.counts().iter().any(|c| c[0] > 0));
}
