//! A mirrored (negative-scale) instance keeps its front face, as glTF's winding rule
//! says (the determinant's sign defines the winding): seen from where its unmirrored
//! twin is seen from the front, it is front-facing too — for rays, the rasterized
//! G-buffer, photon hits and emitters (issue 14, defect 3).

use illume_core::{Ray, Rgb, Vec2, Vec3};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Trs};
use illume_transport::{GBuffer, World};

/// A one-sided emissive quad facing +z at the origin, scaled by `scale`, seen from +z.
fn world(scale: Vec3) -> World {
    let mut b = SceneBuilder::new();
    let m = b.material(Material {
        base_color: Rgb::splat(0.5),
        emission: Rgb::ONE,
        double_sided: false,
        ..Default::default()
    });
    let mesh = b.mesh(quad(Vec3::ZERO, Vec3::X, Vec3::Y, m)); // faces +z
    b.placed(
        "quad",
        mesh,
        Trs {
            scale,
            ..Trs::IDENTITY
        },
        false,
    );
    let cam = b.node(
        "camera",
        None,
        Trs::from_translation(Vec3::new(0.0, 0.0, 3.0)),
    );
    b.camera("camera", 40f32.to_radians(), cam);
    let scene = b.finish("test:mirror");
    scene.validate().unwrap();
    World::new(scene)
}

#[test]
fn mirrored_instances_keep_their_front_face() {
    for scale in [
        Vec3::ONE,
        Vec3::new(-1.0, 1.0, 1.0),
        Vec3::new(-1.0, 2.0, 1.0),
    ] {
        let w = world(scale);
        let ray = Ray::new(Vec3::new(0.1, 0.2, 3.0), -Vec3::Z);
        let hit = w.trace(&ray, illume_scene::MASK_DEFAULT).expect("the quad");
        assert!(
            hit.front_face && hit.reflects,
            "scale {scale}: seen from behind"
        );
        assert!(
            hit.geometric_normal.z > 0.99,
            "scale {scale}: {}",
            hit.geometric_normal
        );
        assert_eq!(hit.emission, Rgb::ONE, "scale {scale}");
        let photon = w.photon_hit(
            &ray,
            &w.tracer
                .intersect(&ray, illume_scene::MASK_DEFAULT)
                .unwrap(),
        );
        assert!(photon.front_face, "scale {scale}: photon hit from behind");
        let g = GBuffer::rasterize(&w, 16, 12);
        let centre = g.pixels[(6 * 16 + 8) as usize].expect("the quad covers the centre");
        assert!(
            centre.hit.front_face,
            "scale {scale}: rasterized from behind"
        );
        let rays = GBuffer::render(&w, 16, 12, Vec2::splat(0.5));
        assert_eq!(
            rays.pixels[(6 * 16 + 8) as usize].map(|p| p.hit.front_face),
            Some(true)
        );
        // The emitter faces +z: a point in front of it receives its light.
        let mut rng = illume_core::sampling::Pcg32::new(1, 0);
        let s = w
            .lights
            .sample_incident(Vec3::new(0.0, 0.0, 1.0), &mut rng)
            .expect("lit from the front");
        assert!(s.weight.x > 0.0);
    }
}
