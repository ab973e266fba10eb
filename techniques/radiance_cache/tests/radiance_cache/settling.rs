//! In real time (`--realtime`, the window) a still world settles: records made since the
//! world last changed do not age, so once the cache covers the view no record is
//! computed and every frame is the same image (the window then idles). A move unsettles
//! it, and the records made before the move still expire within δt_max frames of it.

use illume_core::{Affine3A, Vec3};
use illume_radiance_cache::{RadianceCache, RadianceCacheSettings, TemporalMode};
use illume_scene::{Edit, InstanceId, Timeline};
use illume_transport::{GBuffer, Technique, World};

const W: u32 = 48;
const H: u32 = 36;
/// δt_max, short so that ageing shows within a few frames.
const MAX_AGE: u32 = 4;

fn real_time() -> RadianceCacheSettings {
    RadianceCacheSettings {
        theta_strata: 8,
        phi_strata: 8,
        temporal: TemporalMode::Reuse,
        max_age_frames: MAX_AGE,
        paced_real_time: true,
        ..RadianceCacheSettings::default()
    }
}

/// Renders one frame; returns its image and whether the technique was settled after it.
fn frame(rc: &mut RadianceCache, world: &World) -> (Vec<f32>, bool) {
    let g = GBuffer::rasterize(world, W, H);
    let img = rc.indirect(world, &g);
    let bits = img.pixels().iter().flat_map(|p| p.to_array()).collect();
    (bits, rc.settled())
}

#[test]
fn a_still_world_settles_in_real_time_and_a_move_unsettles_it_until_old_records_expire() {
    let mut scene = illume_scene::builtin::load("cube-in-box").unwrap();
    scene.active_animation = None;
    let timeline = Timeline::new(scene.clone(), vec![0.0], W, H).unwrap();
    let mut world = World::new(scene);
    let mut rc = RadianceCache::new(&world, &timeline, real_time()).unwrap();
    assert!(!rc.settled(), "settled before any frame");

    // The first frame covers the view; the second computes nothing more.
    let (first, _) = frame(&mut rc, &world);
    let (second, settled) = frame(&mut rc, &world);
    assert!(settled, "still world not settled after two frames");
    assert_eq!(first, second, "the second frame of a still world differs");
    let made = rc.records_created();
    // Several lifespans of a still world: nothing expires, nothing is recomputed.
    for k in 0..3 * MAX_AGE {
        let (img, settled) = frame(&mut rc, &world);
        assert!(settled, "frame {k} of a still world is not settled");
        assert_eq!(
            img, first,
            "frame {k} of a still world differs from the first"
        );
    }
    assert_eq!(
        rc.records_created(),
        made,
        "a still world recomputed records"
    );

    // Move the cube: no longer settled, and the frames change.
    let cube = world
        .scene
        .instances
        .iter()
        .position(|i| i.name == "cube")
        .expect("the cube");
    let moved = Affine3A::from_translation(Vec3::new(0.3, 0.2, 0.2))
        * Affine3A::from_scale(Vec3::splat(0.2));
    let changes = world
        .apply_edit(&Edit::SetInstanceTransform {
            instance: InstanceId(cube as u32),
            world_from_object: moved,
        })
        .unwrap();
    rc.scene_changed(&world, &changes);
    assert!(!rc.settled(), "settled right after a move");
    let (after, _) = frame(&mut rc, &world);
    assert_ne!(after, first, "the move changed nothing");

    // The records made before the move that it did not expire age out within δt_max
    // frames of it (replaced), then the world settles again.
    // They expire spread over those frames, not all at once.
    let mut made_per_frame = Vec::new();
    let mut settled_at = None;
    for k in 1..=MAX_AGE + 2 {
        let before = rc.records_created();
        let (_, settled) = frame(&mut rc, &world);
        made_per_frame.push(rc.records_created() - before);
        if settled {
            settled_at = Some(k);
            break;
        }
    }
    let frames_with_work = made_per_frame.iter().filter(|&&n| n > 0).count();
    assert!(
        frames_with_work >= 2,
        "records made per frame after the move: {made_per_frame:?} (old records not \
         aged out, or all at once)"
    );
    let k = settled_at.expect("not settled within δt_max + 2 frames of the move");
    assert!(
        k >= MAX_AGE - 1,
        "settled {k} frames after the move: old records kept"
    );
    let made = rc.records_created();
    let (a, _) = frame(&mut rc, &world);
    let (b, settled) = frame(&mut rc, &world);
    assert!(settled && a == b && rc.records_created() == made);
}
