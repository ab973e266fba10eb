//! The ambient term's one test binary: its indirect light against the hand-computed
//! `ρ(x)·L_a` on a real G-buffer, its settings check, and its answer to scene changes.
//! (Its run through the engine, where it is exact in the furnace, is the engine's own
//! unit test: the engine registers it only there.)

use illume_ambient::{Ambient, AmbientSettings};
use illume_core::{Rgb, Vec2};
use illume_transport::{ChangeResponse, GBuffer, Technique, TechniqueSettings, World};

fn furnace() -> World {
    World::new(illume_scene::builtin::load("furnace").expect("the built-in furnace"))
}

/// Every pixel's indirect light is its albedo times the ambient radiance; pixels that see
/// nothing get none.
#[test]
fn indirect_light_is_the_albedo_times_the_ambient_radiance() {
    let world = furnace();
    let g = GBuffer::render(&world, 24, 18, Vec2::splat(0.5));
    let radiance = 2.5;
    let mut ambient = Ambient::new(AmbientSettings { radiance }).unwrap();
    let image = ambient.indirect(&world, &g);
    assert_eq!((image.width(), image.height()), (24, 18));
    let mut lit = 0;
    for (i, px) in g.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % 24, i as u32 / 24);
        let expected = px.as_ref().map_or(Rgb::ZERO, |p| p.hit.albedo * radiance);
        let got = *image.get(x, y);
        assert!(
            (got - expected).abs().max_element() < 1e-6,
            "pixel {x},{y}: {got:?} against {expected:?}"
        );
        lit += usize::from(px.is_some());
    }
    // Inside the closed furnace every pixel sees its wall (albedo 0.5): 1.25 everywhere.
    assert_eq!(lit, 24 * 18);
    assert!((image.get(12, 9).x - 1.25).abs() < 1e-6);
}

/// A negative or non-finite radiance is refused, naming the field.
#[test]
fn settings_out_of_range_are_refused_by_name() {
    for radiance in [-1.0, f32::NAN, f32::INFINITY] {
        let e = AmbientSettings { radiance }
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("radiance"), "{radiance}: {e}");
        assert!(Ambient::new(AmbientSettings { radiance }).is_err());
    }
    assert!(AmbientSettings { radiance: 0.0 }.check().is_ok());
}

/// Stateless: any change is followed at once, never a rebuild.
#[test]
fn scene_changes_never_rebuild() {
    let world = furnace();
    let mut ambient = Ambient::new(AmbientSettings::default()).unwrap();
    let to = glam::Affine3A::from_translation(glam::Vec3::X);
    let changes = [illume_scene::SceneChange::CameraMoved {
        from: glam::Affine3A::IDENTITY,
        to,
    }];
    assert!(matches!(
        ambient.scene_changed(&world, &changes),
        ChangeResponse::Updated
    ));
    assert!(ambient.settled());
}
