//! Objects added and removed through the scene-change path (`Engine::apply_edit`) reach
//! every technique: none panics, the added object shows where it stands, and once it is
//! removed the image there goes back to what it was.

use illume_core::image::RgbImage;
use illume_core::{Affine3A, Rgb, Vec3};
use illume_engine::{Config, Engine, TechniqueKind};
use illume_scene::{Edit, InstanceId, SceneChange};

fn config(kind: TechniqueKind) -> Config {
    let mut c = Config {
        technique: kind,
        ..Default::default()
    };
    c.render.width = 48;
    c.render.height = 36;
    c.photon_stream = illume_photon_stream::PhotonStreamSettings {
        vsl_count: 40,
        photons_per_frame: 5000,
        ..illume_photon_stream::PhotonStreamSettings::deterministic()
    };
    c.reference.spp_per_frame = 2;
    c
}

/// Mean of `img` over the pixels where `mask` is true.
fn mean_over(img: &RgbImage, mask: &[bool]) -> Rgb {
    let (sum, n) = img
        .pixels()
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((Rgb::ZERO, 0u32), |(s, n), (p, _)| (s + *p, n + 1));
    sum / n.max(1) as f32
}

#[test]
fn every_technique_follows_an_object_added_then_removed() {
    // precomputed needs a scene with a sun path and does not follow added objects by
    // design (Bahnsen et al. §2: dynamic objects leave indirect light unchanged).
    for &kind in TechniqueKind::ALL
        .iter()
        .filter(|k| **k != TechniqueKind::Precomputed)
    {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let sphere = scene
            .instances
            .iter()
            .find(|i| i.name.to_lowercase().contains("sphere"))
            .expect("cornell-spot has a sphere");
        let mesh = sphere.mesh;
        let mut engine = Engine::new(scene, &config(kind)).unwrap();
        let before = engine.step(0.0).unwrap();
        // A second sphere, large and near the camera on the left of the floor.
        let place = Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.6),
            Default::default(),
            Vec3::new(-0.45, 0.45, 0.3),
        );
        let changes = engine
            .apply_edit(&Edit::AddInstance {
                name: "added".into(),
                mesh,
                world_from_object: place,
            })
            .unwrap();
        let added = match changes[0] {
            SceneChange::InstanceAdded { instance } => instance,
            ref c => panic!("{}: first change is {c:?}", kind.name()),
        };
        let with = engine.step(0.0).unwrap();
        let covered: Vec<bool> = with
            .frame
            .gbuffer
            .pixels
            .iter()
            .map(|p| p.is_some_and(|p| p.hit.instance == added))
            .collect();
        let n = covered.iter().filter(|c| **c).count();
        assert!(
            n > 60,
            "{}: the added sphere covers {n} pixels",
            kind.name()
        );
        let (a, b) = (
            mean_over(&before.frame.full, &covered),
            mean_over(&with.frame.full, &covered),
        );
        assert!(
            (a - b).abs().max_element() > 0.05 * a.max_element().max(b.max_element()),
            "{}: the image does not change where the object stands ({a} → {b})",
            kind.name()
        );
        drop(with);
        let changes = engine
            .apply_edit(&Edit::RemoveInstance { instance: added })
            .unwrap();
        assert!(matches!(
            changes[..],
            [SceneChange::InstanceRemoved { instance, .. }] if instance == added
        ));
        // Removing it twice is refused and changes nothing.
        assert!(
            engine
                .apply_edit(&Edit::RemoveInstance { instance: added })
                .is_err()
        );
        // Give streaming techniques time to age the removed object's light out.
        let mut after = engine.step(0.0).unwrap();
        for _ in 0..4 {
            after = engine.step(0.0).unwrap();
        }
        assert!(
            after
                .frame
                .gbuffer
                .pixels
                .iter()
                .all(|p| p.is_none_or(|p| p.hit.instance != added)),
            "{}: a removed object is still seen",
            kind.name()
        );
        let c = mean_over(&after.frame.full, &covered);
        eprintln!(
            "{}: {n} pixels, before {a}, with {b}, after {c}",
            kind.name()
        );
        assert!(
            (c - a).abs().max_element() < 0.25 * a.max_element(),
            "{}: where the object stood, the image does not return ({a} before, {c} after)",
            kind.name()
        );
        // Ids of other instances did not shift.
        assert_ne!(added, InstanceId(0));
    }
}

/// Every step reports how its analytic lights were shadowed: the reference (not
/// interactive) shades cornell-spot's one spot light with rays; photon_stream with
/// `shadows = "maps"` with a map, rendered on the first frame and kept while nothing
/// moves.
#[test]
fn each_step_reports_the_shadows_of_its_lights() {
    let get = |out: &illume_engine::StepOutput, k: &str| {
        out.stats.get(k).unwrap_or_else(|| panic!("no counter {k}"))
    };
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    let mut engine = Engine::new(scene.clone(), &config(TechniqueKind::Reference)).unwrap();
    let out = engine.step(0.0).unwrap();
    assert_eq!(get(&out, "render.shadow_lights_rays"), 1.0);
    assert_eq!(get(&out, "render.shadow_lights_maps"), 0.0);
    assert_eq!(get(&out, "render.shadow_maps_rendered"), 0.0);

    let mut c = config(TechniqueKind::PhotonStream);
    c.render.shadows = illume_render::ShadowMode::Maps;
    let mut engine = Engine::new(scene, &c).unwrap();
    let first = engine.step(0.0).unwrap();
    assert_eq!(get(&first, "render.shadow_lights_maps"), 1.0);
    assert_eq!(get(&first, "render.shadow_lights_rays"), 0.0);
    assert!(get(&first, "render.shadow_maps_rendered") >= 1.0);
    let second = engine.step(0.0).unwrap();
    assert_eq!(get(&second, "render.shadow_lights_maps"), 1.0);
    assert_eq!(get(&second, "render.shadow_maps_rendered"), 0.0);
}
