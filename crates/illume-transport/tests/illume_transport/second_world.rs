//! A second world at another time shares every mesh BVH and packed texture with the
//! live one and answers every query like a world built from scratch.

use illume_accel::ray_sets::incoherent_rays;
use illume_core::sampling::Pcg32;
use illume_scene::{MASK_DEFAULT, MeshId};
use illume_transport::World;

#[test]
fn a_world_at_another_time_shares_mesh_bvhs_and_matches_a_fresh_build() {
    let live = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
    let later = live.at_time(1.5);
    let mut scene = live.scene.clone();
    scene.set_time(1.5);
    let fresh = World::new(scene);
    // The live world is untouched.
    assert_eq!(live.scene.time, 0.0);
    assert_eq!(later.scene.time, 1.5);
    for m in 0..live.scene.meshes.len() {
        let id = MeshId(m as u32);
        assert!(later.tracer.shares_mesh_bvh(&live.tracer, id), "mesh {m}");
        assert_eq!(
            later.tracer.mesh_bvh_address(id),
            live.tracer.mesh_bvh_address(id)
        );
        assert!(std::sync::Arc::ptr_eq(
            &later.scene.meshes[m],
            &live.scene.meshes[m]
        ));
    }
    // No mesh BVH was built for the second world.
    assert_eq!(
        later.tracer.stats().mesh_builds,
        live.tracer.stats().mesh_builds
    );
    later.tracer.validate().unwrap();
    // Instance level and lights equal to a fresh build's: same sizes, same hits, same
    // surfaces, same light samples.
    let (a, b) = (later.tracer.stats(), fresh.tracer.stats());
    assert_eq!(
        (a.instances, a.instance_nodes, a.triangles),
        (b.instances, b.instance_nodes, b.triangles)
    );
    let mut moved = 0;
    for ray in incoherent_rays(&fresh.scene, 2000, 3) {
        let (h, f) = (
            later.trace(&ray, MASK_DEFAULT),
            fresh.trace(&ray, MASK_DEFAULT),
        );
        assert_eq!(
            h.map(|h| (h.instance, h.triangle, h.t.to_bits())),
            f.map(|f| (f.instance, f.triangle, f.t.to_bits()))
        );
        assert_eq!(h.map(|h| h.albedo), f.map(|f| f.albedo));
        let l = live.trace(&ray, MASK_DEFAULT);
        moved += usize::from(l.map(|l| l.t.to_bits()) != h.map(|h| h.t.to_bits()));
        if let Some(h) = h {
            let (mut s1, mut s2) = (Pcg32::new(9, 0), Pcg32::new(9, 0));
            let (x, y) = (
                later.lights.sample_incident(h.position, &mut s1),
                fresh.lights.sample_incident(h.position, &mut s2),
            );
            assert_eq!(x.map(|x| x.wi), y.map(|y| y.wi));
        }
    }
    assert!(moved > 0, "the sphere and light move between 0 and 1.5 s");
}
