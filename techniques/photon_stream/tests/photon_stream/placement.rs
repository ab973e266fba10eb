//! VSL placement (§0.4.2, Algorithm 1).

use illume_core::Vec3;
use illume_photon_stream::placement::{PlacementSettings, VslSet, remove_closest};
use illume_scene::InstanceId;

#[test]
fn algorithm1_removes_the_closest_pair_member_with_the_closer_second_neighbour() {
    // On a line: 0, 1, 2, 2.1, 5. Closest pair (2, 2.1): d_min1 = 0.1 for both;
    // d_min2(2) = 1 (to 1) < d_min2(2.1) = 1.1 (to 1) ⇒ point 2 (at x = 2) goes first.
    // Then (0, 1) is the closest pair (d = 1) beside 2.1's d_min1 = 1.1:
    // d_min2(0) = 2.1 > d_min2(1) = 1.1 ⇒ point 1 (at x = 1) goes.
    let xs = [0.0, 1.0, 2.0, 2.1, 5.0];
    let pts: Vec<Vec3> = xs.iter().map(|&x| Vec3::new(x, 0.0, 0.0)).collect();
    let r = remove_closest(&pts, &[0; 5], 3);
    assert_eq!(r.order, vec![2, 1]);
    assert_eq!(r.keep, vec![true, false, false, true, true]);
    // One more removal: remaining 0, 2.1, 5 → closest pair (0, 2.1), d = 2.1;
    // d_min2(0) = 5 < d_min2(2.1) = 2.9? No: d_min2(2.1) = 2.9 < 5 ⇒ 2.1 (index 3) goes.
    let r = remove_closest(&pts, &[0; 5], 2);
    assert_eq!(r.order, vec![2, 1, 3]);
}

#[test]
fn algorithm1_on_a_grid_with_a_cluster_removes_exactly_the_cluster() {
    // A 4×4 grid of spacing 1 plus 3 extra points hugging grid point (1, 1): removing 3
    // points must remove points of the cluster (the 4 points within 0.1 of each other),
    // leaving exactly one of them, and never a plain grid point.
    let mut pts: Vec<Vec3> = (0..16)
        .map(|i| Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0))
        .collect();
    pts.push(Vec3::new(1.05, 1.0, 0.0));
    pts.push(Vec3::new(1.0, 1.06, 0.0));
    pts.push(Vec3::new(0.96, 0.97, 0.0));
    let cluster = [5usize, 16, 17, 18];
    let r = remove_closest(&pts, &vec![0; pts.len()], 16);
    assert_eq!(r.order.len(), 3);
    assert!(
        r.order.iter().all(|i| cluster.contains(i)),
        "removed {:?}",
        r.order
    );
    assert_eq!(cluster.iter().filter(|&&i| r.keep[i]).count(), 1);
}

#[test]
fn algorithm1_never_removes_the_last_vsl_of_an_object() {
    // Object 1 has a single point sitting on top of object 0's points: it is the
    // closest of all, yet must survive; object 0 keeps at least one too.
    let mut pts: Vec<Vec3> = (0..10)
        .map(|i| Vec3::new(i as f32 * 0.01, 0.0, 0.0))
        .collect();
    let mut objects = vec![0u32; 10];
    pts.push(Vec3::new(0.0, 0.001, 0.0));
    objects.push(1);
    let r = remove_closest(&pts, &objects, 1);
    assert!(r.keep[10], "the only point of object 1 was removed");
    assert_eq!(
        r.keep[..10].iter().filter(|&&k| k).count(),
        1,
        "object 0 keeps exactly one"
    );
    assert_eq!(r.order.len(), 9);
}

#[test]
fn placement_on_cornell_spot_honours_count_objects_edges_and_area() {
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    for n in [3u32, 10, 50, 100, 200] {
        let set = VslSet::place(
            &scene,
            &PlacementSettings {
                vsl_count: n,
                oversampling: 0.1,
                triangle_scale: 0.8,
                seed: 1,
                oriented_cells: true,
            },
        );
        assert_eq!(set.len(), n.max(3) as usize, "N_v = {n}");
        for i in 0..scene.instances.len() {
            assert!(
                set.count_on(InstanceId(i as u32)) >= 1,
                "N_v = {n}: instance {i} has no VSL"
            );
        }
        // A_s partitions each object's area (Voronoi cells of uniform samples).
        for (i, inst) in scene.instances.iter().enumerate() {
            let mesh = &scene.meshes[inst.mesh.index()];
            let area: f32 = (0..mesh.triangle_count())
                .map(|t| {
                    let [a, b, c] = mesh
                        .triangle(t)
                        .map(|p| inst.world_from_object.transform_point3(p));
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            let sum: f32 = set
                .vsls()
                .iter()
                .filter(|v| v.instance.index() == i)
                .map(|v| v.area_m2)
                .sum();
            assert!(
                (sum - area).abs() < 0.02 * area,
                "N_v = {n}, instance {i}: ΣA_s = {sum}, area = {area}"
            );
        }
    }
    // Points stay off edges: on the walls (axis-aligned quads of side 2 made of two
    // triangles) a VSL shrunk by 0.8 about its triangle's centroid is ≥ 0.2·inradius
    // from every edge of its triangle, in particular from the quad's border: ≥ 0.05 m
    // from the walls' outer edges (|coordinate| ≤ 0.95 on the wall plane's axes).
    let set = VslSet::place(
        &scene,
        &PlacementSettings {
            vsl_count: 200,
            oversampling: 0.1,
            triangle_scale: 0.8,
            seed: 2,
            oriented_cells: true,
        },
    );
    let walls = set.vsls().iter().filter(|v| v.instance.index() == 0);
    for v in walls {
        let p = v.position_object;
        let border = [1.0 - p.x.abs(), 1.0 - p.z.abs(), p.y.min(2.0 - p.y)];
        let in_plane: Vec<f32> = border.iter().copied().filter(|d| *d > 1e-4).collect();
        assert!(
            in_plane.iter().all(|&d| d > 0.05),
            "wall VSL {p} too close to an edge"
        );
    }
}

#[test]
fn photons_go_to_the_nearest_vsl_of_their_own_object() {
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    let set = crate::common::sixty_vsls(&scene, true);
    let mut rng = illume_core::sampling::Pcg32::new(1, 2);
    use illume_core::sampling::SampleStream;
    for _ in 0..5000 {
        let inst = InstanceId(rng.next_below(scene.instances.len() as u32));
        let q = Vec3::new(
            rng.next_1d() * 2.0 - 1.0,
            rng.next_1d() * 2.0,
            rng.next_1d() * 2.0 - 1.0,
        );
        let g = set.nearest(inst, q).unwrap() as usize;
        assert_eq!(set.vsls()[g].instance, inst);
        let best = set
            .vsls()
            .iter()
            .filter(|v| v.instance == inst)
            .map(|v| v.position_object.distance_squared(q))
            .fold(f32::INFINITY, f32::min);
        assert_eq!(set.vsls()[g].position_object.distance_squared(q), best);
    }
}
