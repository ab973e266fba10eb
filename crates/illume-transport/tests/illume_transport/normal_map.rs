//! A tangent-space normal map turns the shading normal toward the tangent frame's +x
//! (the direction of increasing u), by the texel's angle; direct light follows.

use illume_core::{Affine3A, Quat, Rgb, Vec2, Vec3, Vec4};
use illume_scene::builtin::SceneBuilder;
use illume_scene::{Material, Mesh, Texture, Trs, WrapMode};
use illume_transport::World;

/// A 2 m square facing +y whose u runs along +x (tangents (1, 0, 0, +1)), placed by
/// `world_from_object`, with a one-texel normal map tilting the normal by `tilt_deg`
/// toward +u.
fn plane(tilt_deg: f32, world_from_object: Trs) -> World {
    let mut b = SceneBuilder::new();
    let (s, c) = tilt_deg.to_radians().sin_cos();
    let tex = b.texture(Texture {
        name: "n".into(),
        width: 1,
        height: 1,
        texels: vec![Rgb::new(0.5 * s + 0.5, 0.5, 0.5 * c + 0.5)],
        wrap_u: WrapMode::Repeat,
        wrap_v: WrapMode::Repeat,
        alpha: vec![],
    });
    let m = b.material(Material {
        base_color: Rgb::splat(0.5),
        normal_texture: Some(tex),
        ..Default::default()
    });
    let mesh = b.mesh(Mesh {
        name: "plane".into(),
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ],
        tangents: vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 4],
        indices: vec![[0, 2, 1], [0, 3, 2]],
        triangle_materials: vec![m, m],
    });
    b.placed("plane", mesh, world_from_object, false);
    b.camera_looking_down(3.0, 40f32.to_radians());
    let scene = b.finish("test:normal-map");
    scene.validate().unwrap();
    World::new(scene)
}

fn shading_normal(world: &World, from: Vec3) -> Vec3 {
    let ray = illume_core::Ray::new(from, (Vec3::new(0.1, 0.0, 0.2) - from).normalize());
    world
        .trace(&ray, illume_scene::MASK_DEFAULT)
        .expect("the plane")
        .shading_normal
}

#[test]
fn the_normal_map_tilts_toward_plus_u() {
    let flat = shading_normal(&plane(0.0, Trs::IDENTITY), Vec3::new(0.0, 2.0, 0.0));
    assert!((flat - Vec3::Y).length() < 1e-3, "{flat}");
    let n = shading_normal(&plane(30.0, Trs::IDENTITY), Vec3::new(0.0, 2.0, 0.0));
    let expected = Vec3::new(30f32.to_radians().sin(), 30f32.to_radians().cos(), 0.0);
    assert!((n - expected).length() < 0.01, "{n} vs {expected}");
    // The tangent frame turns with the object: rotated 90° about +y, +u points to −z.
    let turned = Trs {
        rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
        ..Trs::IDENTITY
    };
    let n = shading_normal(&plane(30.0, turned), Vec3::new(0.0, 2.0, 0.0));
    let expected = Affine3A::from_quat(turned.rotation).transform_vector3(expected);
    assert!((n - expected).length() < 0.01, "{n} vs {expected}");
}

/// The rasterized G-buffer shades normal-mapped pixels exactly as rays do.
#[test]
fn rasterized_pixels_carry_the_mapped_normal() {
    let world = plane(30.0, Trs::IDENTITY);
    let raster = illume_transport::GBuffer::rasterize(&world, 32, 24);
    let rays = illume_transport::GBuffer::render(&world, 32, 24, Vec2::splat(0.5));
    let mut seen = 0;
    for (a, b) in raster.pixels.iter().zip(&rays.pixels) {
        if let (Some(a), Some(b)) = (a, b) {
            assert!((a.hit.shading_normal - b.hit.shading_normal).length() < 1e-4);
            assert!(a.hit.shading_normal.x > 0.45, "{}", a.hit.shading_normal);
            seen += 1;
        }
    }
    assert!(seen > 100, "{seen} pixels");
}
