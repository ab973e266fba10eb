//! Texture masking (§5.3) against hand-computed cases: the threshold elevation T_e of
//! flat textures and checkerboards per MIP level (Daly's masking function of the band
//! contrast, frequencies finer than an element removed), the MIP level from distance and
//! angle, and the pilot increment Δp/T_e a textured moved object gives its groups.

use crate::common;

use illume_core::{Affine3A, Quat, Ray, Rgb, Vec2, Vec3};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{
    InstanceId, LightKind, MASK_DEFAULT, Material, Mesh, Texture, TextureId, Trs, WrapMode,
};
use illume_selective::elements::Elements;
use illume_selective::masking::{
    DELTA_P, MIN_COS, MaskingView, TextureMasking, elevation_per_level, mip_level,
    threshold_elevation,
};
use illume_selective::{GroupOrder, Selective, SelectiveSettings};
use illume_transport::{Technique, World};

/// Daly's masking function, written out: T_e = (1 + (k₁(k₂m)^s)^b)^(1/b), k₁ = 0.0153,
/// k₂ = 392.498, s = 0.7, b = 4.
fn daly(m: f64) -> f64 {
    (1.0 + (0.0153 * (392.498 * m).powf(0.7)).powi(4)).powf(0.25)
}

fn grey_texture(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Texture {
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| Rgb::splat(f(x, y)))
        .collect();
    Texture {
        name: "test".into(),
        width: w,
        height: h,
        texels,
        wrap_u: WrapMode::Repeat,
        wrap_v: WrapMode::Repeat,
        alpha: Vec::new(),
    }
}

/// Squares of `side` texels alternating mean·(1 ± c): Michelson contrast c.
fn checker(n: u32, side: u32, c: f32) -> Texture {
    grey_texture(n, n, |x, y| {
        let s = if (x / side + y / side).is_multiple_of(2) {
            1.0
        } else {
            -1.0
        };
        0.5 * (1.0 + c * s)
    })
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-12)
}

#[test]
fn masking_function_is_dalys() {
    assert_eq!(threshold_elevation(0.0), 1.0);
    assert_eq!(threshold_elevation(f32::NAN), 1.0);
    assert_eq!(threshold_elevation(-3.0), 1.0);
    for m in [0.1f32, 1.0, 5.0, 30.0, 80.0] {
        let got = threshold_elevation(m) as f64;
        assert!(close(got, daly(m as f64), 1e-5), "m = {m}: {got}");
    }
    // At threshold (m = 1) masking just starts; well above it T_e ≈ k₁(k₂m)^0.7.
    assert!((1.1..1.3).contains(&threshold_elevation(1.0)));
    assert!(threshold_elevation(30.0) > 10.0);
}

#[test]
fn flat_texture_elevates_nothing_at_any_level() {
    // 64×48: 64→32→16→8→4→2→1 and 48→24→12→6→3→2→1, six reductions, seven levels.
    let flat = grey_texture(64, 48, |_, _| 0.4);
    for element in [0.5f32, 1.0, 3.0, 40.0] {
        let te = elevation_per_level(&flat, element, 0.01);
        assert_eq!(te.len(), 7, "element {element}");
        for (l, t) in te.iter().enumerate() {
            assert!((t - 1.0).abs() < 1e-6, "element {element}, level {l}: {t}");
        }
    }
    // Odd sides and a black texture: still no contrast.
    let odd = grey_texture(37, 5, |_, _| 0.9);
    assert!(
        elevation_per_level(&odd, 1.0, 0.01)
            .iter()
            .all(|t| (t - 1.0).abs() < 1e-6)
    );
    let black = grey_texture(16, 16, |_, _| 0.0);
    assert!(
        elevation_per_level(&black, 1.0, 0.01)
            .iter()
            .all(|&t| t == 1.0)
    );
}

#[test]
fn checkerboard_finer_than_an_element_is_filtered_out() {
    // Squares of 2 texels, luminance 0.1 / 0.9: Michelson contrast 0.8, all of it in
    // band 1 (level 1 is a one-texel checkerboard; a 2×2 block of it has mean 0.5 and
    // RMS deviation 0.4).
    let fine = checker(64, 2, 0.8);
    // Elements of one texel keep it: level 1 shows T_e = Daly(0.8 / 0.01).
    let kept = elevation_per_level(&fine, 1.0, 0.01);
    assert!(
        close(kept[1] as f64, daly(80.0), 1e-3),
        "{} vs {}",
        kept[1],
        daly(80.0)
    );
    assert!(kept[1] > 20.0);
    // Elements of 8 texels (level 3) remove it: T_e ≈ 1 at every level.
    let removed = elevation_per_level(&fine, 8.0, 0.01);
    for (l, t) in removed.iter().enumerate() {
        assert!((t - 1.0).abs() < 1e-3, "level {l}: {t}");
    }
}

#[test]
fn checkerboard_coarser_than_an_element_masks_and_more_with_contrast() {
    // Squares of 16 texels on 128 texels: all contrast in band 4. Elements of 4 texels
    // (l_e = 2) keep it: level 4 shows Daly(c / threshold), every other level 1.
    let mut previous = 1.0;
    for c in [0.05f32, 0.2, 0.8] {
        let te = elevation_per_level(&checker(128, 16, c), 4.0, 0.01);
        assert_eq!(te.len(), 8);
        let want = daly(c as f64 / 0.01);
        assert!(
            close(te[4] as f64, want, 1e-3),
            "c = {c}: {} vs {want}",
            te[4]
        );
        assert!(te[4] > 3.0, "c = {c}: T_e = {} is not well above 1", te[4]);
        assert!(te[4] > previous, "T_e does not rise with contrast");
        previous = te[4];
        for (l, t) in te.iter().enumerate().filter(|&(l, _)| l != 4) {
            assert!((t - 1.0).abs() < 1e-3, "c = {c}, level {l}: {t}");
        }
        // A higher contrast threshold (a less sensitive observer) masks less.
        let dull = elevation_per_level(&checker(128, 16, c), 4.0, 0.05);
        assert!(close(dull[4] as f64, daly(c as f64 / 0.05), 1e-3));
        assert!(dull[4] < te[4]);
    }
    // Elements of 16·√2 texels (l_e = 4.5) sit between bands 4 and 5: levels up to 4
    // see half of band 4's elevation and half of band 5's (none).
    let te = elevation_per_level(&checker(128, 16, 0.8), 16.0 * 2f32.sqrt(), 0.01);
    let half = 0.5 * (daly(80.0) + 1.0);
    for (l, t) in te.iter().enumerate().take(5) {
        assert!(close(*t as f64, half, 1e-3), "level {l}: {t} vs {half}");
    }
}

#[test]
fn mip_level_grows_with_distance_and_grazing_angle() {
    // 1 mrad pixels, 100 texels/m: at 10 m head-on a pixel covers 1 texel (level 0).
    assert!(mip_level(10.0, 1.0, 1e-3, 100.0).abs() < 1e-5);
    assert_eq!(mip_level(5.0, 1.0, 1e-3, 100.0), 0.0);
    assert!((mip_level(40.0, 1.0, 1e-3, 100.0) - 2.0).abs() < 1e-5);
    assert!((mip_level(80.0, 1.0, 1e-3, 100.0) - 3.0).abs() < 1e-5);
    // 60° from the normal: the footprint stretches by 1/cos = 2, one level.
    assert!((mip_level(40.0, 0.5, 1e-3, 100.0) - 3.0).abs() < 1e-5);
    // Either side of the surface alike; grazing views stop at MIN_COS.
    assert_eq!(
        mip_level(40.0, -0.5, 1e-3, 100.0),
        mip_level(40.0, 0.5, 1e-3, 100.0)
    );
    let grazing = 2.0 + (1.0 / MIN_COS).log2();
    assert!((mip_level(40.0, 0.0, 1e-3, 100.0) - grazing).abs() < 1e-5);
    let mut last = -1.0;
    for d in [1.0f32, 5.0, 20.0, 100.0, 500.0] {
        let l = mip_level(d, 1.0, 1e-3, 100.0);
        assert!(l >= last, "level falls with distance at {d} m");
        last = l;
    }
    let mut last = -1.0;
    for cos in [1.0f32, 0.8, 0.5, 0.2, 0.07] {
        let l = mip_level(300.0, cos, 1e-3, 100.0);
        assert!(l > last, "level does not grow towards grazing at cos {cos}");
        last = l;
    }
    // No footprint: level 0.
    assert_eq!(mip_level(f32::NAN, 1.0, 1e-3, 100.0), 0.0);
    assert_eq!(mip_level(10.0, 1.0, 0.0, 100.0), 0.0);
}

/// A 1 m × 1 m quad in the plane z = 0 facing +z, UVs over [0, 1]², with `material`.
fn quad_scene(material: Material, texture: Option<Texture>, uvs: bool) -> World {
    let mut b = SceneBuilder::new();
    let mut material = material;
    if let Some(t) = texture {
        material.base_color_texture = Some(b.texture(t));
    }
    let m = b.material(material);
    let mut mesh = quad(Vec3::ZERO, Vec3::X * 0.5, Vec3::Y * 0.5, m);
    if !uvs {
        mesh.uvs.clear();
    }
    let q = b.mesh(mesh);
    b.placed("quad", q, Trs::IDENTITY, false);
    let ln = b.node("light", None, Trs::from_translation(Vec3::Z * 2.0));
    b.light(
        "light",
        LightKind::Point {
            intensity: Rgb::splat(1.0),
        },
        ln,
    );
    let cam = b.node("camera", None, Trs::from_translation(Vec3::Z * 2.0));
    b.camera("camera", 50f32.to_radians(), cam);
    let mut scene = b.finish("test:quad");
    scene.set_time(0.0);
    World::new(scene)
}

/// A point inside one of the quad's triangles (off its diagonal).
const TARGET: Vec3 = Vec3::new(0.1, 0.2, 0.0);

/// The increment of a hit at [`TARGET`] seen from `TARGET + offset` with `pixel_rad`.
fn increment_at(world: &World, masking: &TextureMasking, offset: Vec3, pixel_rad: f32) -> f32 {
    let eye = TARGET + offset;
    let ray = Ray::new(eye, -offset.normalize());
    let hit = world
        .tracer
        .intersect(&ray, MASK_DEFAULT)
        .expect("the ray aims at the quad");
    let hit = world.photon_hit(&ray, &hit);
    masking.increment(&world.scene, &hit, &MaskingView { eye, pixel_rad })
}

#[test]
fn increment_is_delta_p_over_te_at_the_level_the_camera_sees() {
    // 128 texels over 1 m; squares of 16 texels (band 4) at contrast 0.8; elements
    // well under a texel, so nothing is filtered out.
    let world = quad_scene(Material::default(), Some(checker(128, 16, 0.8)), true);
    let elements = Elements::new(&world.scene, 40_000, 45.0);
    let masking = TextureMasking::new(&world.scene, &elements, 0.01);
    let te = masking
        .levels(TextureId(0))
        .expect("the quad maps the texture");
    assert!(close(te[4] as f64, daly(80.0), 1e-3));
    let masked = (1.0 / daly(80.0)) as f32;
    // Head-on from 2 m: a pixel of 1/16 rad covers 2 m · 1/16 · 128 = 16 texels: level 4.
    let head_on = Vec3::Z * 2.0;
    let level4 = 1.0 / 16.0;
    assert!((increment_at(&world, &masking, head_on, level4) - masked).abs() < 1e-4);
    // Sixteen times closer in angle: level 0, where band 4 is not the finest shown.
    assert!((increment_at(&world, &masking, head_on, level4 / 16.0) - DELTA_P).abs() < 1e-4);
    // Twice as far in angle: level 5, the checkerboard averages out.
    assert!((increment_at(&world, &masking, head_on, level4 * 2.0) - DELTA_P).abs() < 1e-4);
    // Level 2 when head-on, but 60° from the normal stretches the footprint ×2 and the
    // distance ×2 more: level 4 again.
    let oblique = Quat::from_rotation_y(60f32.to_radians()) * (Vec3::Z * 4.0);
    assert!((increment_at(&world, &masking, oblique, level4 / 4.0) - masked).abs() < 1e-3);
    assert!((increment_at(&world, &masking, head_on, level4 / 4.0) - DELTA_P).abs() < 1e-4);
}

#[test]
fn untextured_and_degenerate_inputs_give_delta_p() {
    let offset = Vec3::Z * 2.0;
    // Untextured material.
    let plain = quad_scene(Material::default(), None, true);
    let m = TextureMasking::new(&plain.scene, &Elements::new(&plain.scene, 100, 45.0), 0.01);
    assert_eq!(increment_at(&plain, &m, offset, 1.0 / 16.0), DELTA_P);
    // A textured material on a mesh without UVs: the texture reads one texel, no table.
    let no_uv = quad_scene(Material::default(), Some(checker(128, 16, 0.8)), false);
    let m = TextureMasking::new(&no_uv.scene, &Elements::new(&no_uv.scene, 100, 45.0), 0.01);
    assert!(m.levels(TextureId(0)).is_none());
    assert_eq!(increment_at(&no_uv, &m, offset, 1.0 / 16.0), DELTA_P);
    // Empty, one-texel, short and non-finite textures: no panic, T_e = 1 or finite ≥ 1.
    let empty = grey_texture(0, 0, |_, _| 0.0);
    assert_eq!(elevation_per_level(&empty, 4.0, 0.01), vec![1.0]);
    let short = Texture {
        texels: vec![Rgb::ONE; 3],
        ..grey_texture(4, 4, |_, _| 1.0)
    };
    assert_eq!(elevation_per_level(&short, 4.0, 0.01), vec![1.0]);
    assert_eq!(
        elevation_per_level(&grey_texture(1, 1, |_, _| 0.7), 4.0, 0.01),
        vec![1.0]
    );
    let wild = grey_texture(8, 8, |x, _| match x {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => -1.0,
        _ => 0.5,
    });
    for element in [f32::NAN, -1.0, 0.0, f32::INFINITY, 2.0] {
        let te = elevation_per_level(&wild, element, 0.01);
        assert!(te.iter().all(|t| t.is_finite() && *t >= 1.0), "{te:?}");
    }
    // Zero-area UVs on a textured mesh: no table.
    let mut degenerate = no_uv.scene.clone();
    let mut mesh: Mesh = (*degenerate.meshes[0]).clone();
    mesh.uvs = vec![Vec2::splat(0.5); mesh.positions.len()];
    degenerate.meshes[0] = std::sync::Arc::new(mesh);
    let m = TextureMasking::new(&degenerate, &Elements::new(&degenerate, 100, 45.0), 0.01);
    assert!(m.levels(TextureId(0)).is_none());
    // Disabled: Δp whatever the surface.
    let textured = quad_scene(Material::default(), Some(checker(128, 16, 0.8)), true);
    assert_eq!(
        increment_at(&textured, &TextureMasking::disabled(), offset, 1.0 / 16.0),
        DELTA_P
    );
}

/// Π over bands b = 0…5 of (1 + c·(±1 checkerboard of 2^b-texel squares)), 64×64: every
/// 2×2 block of every level has band contrast exactly c, so T_e = Daly(c / threshold)
/// at every level but the last whatever the element size up to 32 texels.
fn cascade(c: f32) -> Texture {
    grey_texture(64, 64, |x, y| {
        (0..6)
            .map(|b| {
                if ((x >> b) + (y >> b)).is_multiple_of(2) {
                    1.0 + c
                } else {
                    1.0 - c
                }
            })
            .product()
    })
}

/// A floor, a box above it (textured with `cascade(0.3)` or plain, albedo 0.15 on
/// average either way) and a point light; the camera looks down at the box.
fn box_scene(textured: bool) -> World {
    common::box_scene(|b| {
        let texture = textured.then(|| b.texture(cascade(0.3)));
        b.material(Material {
            base_color: Rgb::splat(0.15),
            base_color_texture: texture,
            ..Default::default()
        })
    })
}

const ELEMENTS: u32 = 500;

/// P of every group after the box moves and the first `steps` groups (index order) are
/// re-traced: their pilots raise the groups they point at.
fn priorities_after_move(mut world: World, texture_masking: bool, steps: usize) -> Vec<f64> {
    let settings = SelectiveSettings {
        pilots_per_group: 100,
        ratio: 4,
        element_count: ELEMENTS,
        min_photons_per_element: 0,
        min_impacts_per_element: 0,
        warm_up: false,
        order: GroupOrder::Index,
        texture_masking,
        ..SelectiveSettings::deterministic()
    };
    let mut sel = Selective::for_world(&world, settings).unwrap();
    sel.converge(&world);
    let to = Affine3A::from_translation(Vec3::new(0.7, 0.0, -0.3))
        * world.scene.instances[1].world_from_object;
    let changes = world
        .apply_edit(&illume_scene::Edit::SetInstanceTransform {
            instance: InstanceId(1),
            world_from_object: to,
        })
        .unwrap();
    sel.scene_changed(&world, &changes);
    for _ in 0..steps {
        sel.step(&world);
    }
    (0..sel.layout().groups)
        .map(|g| sel.priority(g).p)
        .collect()
}

#[test]
fn pilot_hits_on_a_textured_moved_object_raise_p_by_delta_p_over_te() {
    // The texture's T_e is Daly(0.3 / 0.01) at every level the camera can see the box
    // at (the box spans 64 texels a metre; from ≈ 4.5 m even a grazing pixel covers
    // fewer than 32 texels, below the last level).
    let textured = box_scene(true);
    let masking = TextureMasking::new(
        &textured.scene,
        &Elements::new(&textured.scene, ELEMENTS, 45.0),
        0.01,
    );
    let te = masking
        .levels(TextureId(0))
        .expect("the box maps the texture");
    let want = daly(30.0);
    for (l, t) in te.iter().enumerate().take(te.len() - 1) {
        assert!(close(*t as f64, want, 1e-3), "level {l}: {t} vs {want}");
    }
    // Pilot paths up to the first changed segment cross only the (plain) floor, so the
    // same pilots meet the box in both scenes: P counts hits (Δp = 1 each) on the plain
    // box and hits/T_e on the textured one, group by group.
    let steps = 12;
    let plain = priorities_after_move(box_scene(false), true, steps);
    let masked = priorities_after_move(box_scene(true), true, steps);
    let unmasked = priorities_after_move(box_scene(true), false, steps);
    let raised = plain.iter().filter(|&&p| p > 0.0).count();
    assert!(raised >= 5, "only {raised} groups raised");
    for (g, (&p, &q)) in plain.iter().zip(&masked).enumerate() {
        assert_eq!(p, p.round(), "group {g}: P = {p} is not a hit count");
        if p == 0.0 {
            assert_eq!(q, 0.0, "group {g}");
        } else {
            assert!(
                close(p / q, want, 1e-3),
                "group {g}: plain P = {p}, textured P = {q}, ratio {} vs T_e {want}",
                p / q
            );
        }
    }
    // Masking off: every hit counts Δp = 1 on the textured box too.
    assert_eq!(plain, unmasked);
}
