//! Scenes shared by the selective tests.

use illume_core::{Quat, Rgb, Vec3};
use illume_scene::builtin::{SceneBuilder, quad, unit_box};
use illume_scene::{LightKind, Material, MaterialId, Trs};
use illume_transport::World;
use illume_transport::flux::Quanta;

/// A grey floor (albedo 0.6), a half-metre box 0.6 m above it (dynamic, named "box") with
/// the material `box_material` makes, a 10 W/sr point light at (0.3, 2.5, 0.2) and a
/// camera looking down at the box.
pub fn box_scene(box_material: impl FnOnce(&mut SceneBuilder) -> MaterialId) -> World {
    let mut b = SceneBuilder::new();
    let floor_m = b.material(Material {
        base_color: Rgb::splat(0.6),
        ..Default::default()
    });
    let box_m = box_material(&mut b);
    let floor = b.mesh(quad(Vec3::ZERO, Vec3::Z * 4.0, Vec3::X * 4.0, floor_m));
    b.placed("floor", floor, Trs::IDENTITY, false);
    let cube = b.mesh(unit_box(box_m, false));
    b.placed(
        "box",
        cube,
        Trs {
            scale: Vec3::splat(0.5),
            ..Trs::from_translation(Vec3::new(0.0, 0.6, 0.0))
        },
        true,
    );
    let ln = b.node(
        "light",
        None,
        Trs::from_translation(Vec3::new(0.3, 2.5, 0.2)),
    );
    b.light(
        "light",
        LightKind::Point {
            intensity: Rgb::splat(10.0),
        },
        ln,
    );
    let cam = b.node(
        "camera",
        None,
        Trs {
            rotation: Quat::from_rotation_x(-0.6),
            ..Trs::from_translation(Vec3::new(0.0, 3.0, 4.0))
        },
    );
    b.camera("camera", 50f32.to_radians(), cam);
    let mut scene = b.finish("test:box");
    scene.set_time(0.0);
    World::new(scene)
}

/// A scene of `mesh` alone (every triangle of the material `m` of `b`), placed static
/// at the origin as `name` and set to time 0.
pub fn one_mesh_scene(
    mut b: SceneBuilder,
    m: MaterialId,
    mut mesh: illume_scene::Mesh,
    name: &str,
) -> illume_scene::Scene {
    mesh.triangle_materials = vec![m; mesh.indices.len()];
    let id = b.mesh(mesh);
    b.placed(name, id, Trs::IDENTITY, false);
    let mut scene = b.finish(&format!("test:{name}"));
    scene.set_time(0.0);
    scene
}

/// Asserts that `ours` equals a from-scratch trace's accumulators `fresh`, element for
/// element, naming how many differ.
pub fn assert_same_accumulators(ours: &[[Quanta; 2]], fresh: &[[Quanta; 2]]) {
    assert_eq!(ours.len(), fresh.len(), "element counts differ");
    let differing = ours.iter().zip(fresh).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing, 0,
        "{differing} elements differ from a from-scratch trace"
    );
}
