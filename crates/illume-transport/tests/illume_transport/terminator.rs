//! The shared shadow ray at a shadow terminator (`World::shadow_ray`): light from below
//! a facet that the shading normal faces leaves from the smooth surface the vertex
//! normals describe on a curved mesh, and is hidden on a flat one (no light through a
//! wall whose normals only a normal map tilts).

use illume_core::{Ray, Rgb, Vec3};
use illume_scene::builtin::{SceneBuilder, quad, uv_sphere};
use illume_scene::{Material, MeshId, Trs};
use illume_transport::{LightSample, World};

fn world_of(mesh: impl FnOnce(&mut SceneBuilder) -> MeshId) -> World {
    let mut b = SceneBuilder::new();
    let id = mesh(&mut b);
    b.placed("object", id, Trs::IDENTITY, false);
    b.camera_looking_down(3.0, 1.0);
    World::new(b.finish("test:terminator"))
}

fn white(b: &mut SceneBuilder) -> illume_scene::MaterialId {
    b.material(Material {
        base_color: Rgb::splat(0.5),
        ..Default::default()
    })
}

/// A sun sample towards `wi`.
fn sun(wi: Vec3) -> LightSample {
    LightSample {
        wi: wi.normalize(),
        distance: f32::INFINITY,
        weight: Rgb::ONE,
        pdf: 0.0,
    }
}

#[test]
fn light_from_below_a_flat_facet_is_hidden() {
    let world = world_of(|b| {
        let m = white(b);
        b.mesh(quad(Vec3::ZERO, Vec3::Z, Vec3::X, m)) // faces +y
    });
    let hit = world
        .trace(&Ray::new(Vec3::new(0.2, 1.0, 0.1), -Vec3::Y), u32::MAX)
        .expect("the quad");
    assert_eq!(hit.smooth_point(&world.scene), hit.position);
    assert!(
        world
            .shadow_ray(&hit, &sun(Vec3::new(1.0, -0.05, 0.0)))
            .is_none()
    );
    assert!(!world.unoccluded(&hit, &sun(Vec3::new(1.0, -0.05, 0.0))));
    // From above, the usual ray just off the surface, and nothing in its way.
    let above = world
        .shadow_ray(&hit, &sun(Vec3::new(1.0, 0.05, 0.0)))
        .unwrap();
    assert!(above.origin.y > 0.0);
    assert!(world.unoccluded(&hit, &sun(Vec3::new(1.0, 0.05, 0.0))));
}

#[test]
fn light_from_below_a_curved_facet_leaves_from_the_smooth_surface() {
    let world = world_of(|b| {
        let m = white(b);
        b.mesh(uv_sphere(1.0, 16, 8, m, false))
    });
    let (mut lifted, mut lit) = (0, 0);
    // Hits across the equator's facets, each lit by a sun its facet turns from by 1°
    // while its shading normal faces it.
    for k in 0..64 {
        let phi = k as f32 * std::f32::consts::TAU / 64.0 + 0.01;
        let out = Vec3::new(phi.cos(), 0.05, phi.sin());
        let Some(hit) = world.trace(&Ray::new(out * 3.0, -out.normalize()), u32::MAX) else {
            continue;
        };
        let (n, ng) = (hit.facing_normal(), hit.facing_geometric_normal());
        let smooth = hit.smooth_point(&world.scene);
        // Never pulled into the object, never past the unit sphere by more than the
        // sag of a 16×8 facet (1 − cos 22.5° ≈ 0.076).
        assert!((smooth - hit.position).dot(ng) >= 0.0);
        assert!(smooth.length() < 1.0 + 0.08, "{smooth}");
        // A direction 1° below the facet, turned towards the shading normal.
        let tangent = (n - ng * n.dot(ng)).normalize_or_zero();
        if tangent == Vec3::ZERO {
            continue; // the facet's centre line: shading and facet normals agree
        }
        let wi = (tangent * 1f32.to_radians().cos() - ng * 1f32.to_radians().sin()).normalize();
        if n.dot(wi) <= 0.0 {
            continue;
        }
        lit += 1;
        if let Some(ray) = world.shadow_ray(&hit, &sun(wi)) {
            lifted += 1;
            assert!((ray.origin - hit.position).dot(ng) > 0.0);
            assert!(
                world.unoccluded(&hit, &sun(wi)),
                "the smooth sphere's point at {} sees the sun along {wi}",
                hit.position
            );
        }
    }
    assert!(lit >= 40, "only {lit} hits checked");
    assert!(lifted * 10 >= lit * 9, "{lifted} of {lit} lifted");
}
