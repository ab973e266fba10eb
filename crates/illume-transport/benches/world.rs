//! Cost of a second world (another time, or the scene with an object moved) against a
//! fresh one: `cargo bench -p illume-transport --bench world`.
//!
//! `new` is [`World::new`] (every mesh BVH built, textures packed), `at_time` is
//! [`World::at_time`] of a built world and `moved` is [`World::with_scene`] with the
//! first instance moved: both share the mesh BVHs and packed textures, so they cost the
//! instance level, the light set and the instance frames only.

#![expect(
    missing_docs,
    reason = "criterion_group! generates an undocumented public function"
)]

use criterion::{Criterion, criterion_group, criterion_main};
use illume_core::{Affine3A, Vec3};
use illume_scene::{Edit, InstanceId, Scene};
use illume_transport::World;
use std::time::Duration;

fn scenes() -> Vec<(&'static str, Scene)> {
    let dir = illume_scene::shared_scenes_dir();
    let load =
        |p: &str| illume_scene::load_scene(&dir.join(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    vec![
        ("sponza", load("dabrovic_sponza/sponza.obj")),
        ("cornell_dragon", load("cornell_dragon/cornell_dragon.obj")),
    ]
}

fn second_world(c: &mut Criterion) {
    let mut g = c.benchmark_group("second_world");
    g.sample_size(20);
    g.warm_up_time(Duration::from_millis(500));
    g.measurement_time(Duration::from_secs(3));
    for (name, scene) in scenes() {
        let world = World::new(scene.clone());
        let mut moved = scene.clone();
        moved
            .apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(0),
                world_from_object: Affine3A::from_translation(Vec3::new(0.01, 0.0, 0.0)),
            })
            .expect("a valid edit");
        g.bench_function(format!("{name} new"), |b| {
            b.iter(|| World::new(scene.clone()))
        });
        g.bench_function(format!("{name} at_time"), |b| b.iter(|| world.at_time(0.5)));
        g.bench_function(format!("{name} moved"), |b| {
            b.iter(|| world.with_scene(moved.clone()))
        });
    }
    g.finish();
}

criterion_group!(benches, second_world);
criterion_main!(benches);
