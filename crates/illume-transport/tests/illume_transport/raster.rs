//! The rasterized G-buffer agrees with the ray-cast one: same coverage, same
//! (instance, triangle) on at least 99.9 % of pixels, and the same surface data up to
//! f32 rounding wherever the two pick the same triangle (the rasterized G-buffer
//! intersects the triangle's world-space plane, the rays its object-space BVH copy).

use illume_core::{Affine3A, Quat, Vec2, Vec3};
use illume_scene::{Edit, InstanceId, Scene};
use illume_transport::{GBuffer, TextureFilter, World};

/// Agreement of one raster/ray pair.
#[derive(Debug, Default)]
struct Agreement {
    pixels: usize,
    covered: usize,
    coverage_differs: usize,
    triangle_differs: usize,
    albedo_differs: usize,
}

/// Compares `GBuffer::rasterize` with `GBuffer::render` at pixel centres; panics when a
/// pixel that agrees on (instance, triangle) differs in any surface field.
fn compare(world: &World, width: u32, height: u32, what: &str) -> Agreement {
    compare_at(world, width, height, Vec2::splat(0.5), what)
}

/// [`compare`] with both sampling each pixel at `offset` (jittered frames).
fn compare_at(world: &World, width: u32, height: u32, offset: Vec2, what: &str) -> Agreement {
    let raster = if offset == Vec2::splat(0.5) {
        GBuffer::rasterize(world, width, height)
    } else {
        let mut g = GBuffer::empty();
        g.rasterize_into_at(world, width, height, TextureFilter::Bilinear, offset);
        assert_eq!(g.offset, offset);
        g
    };
    let rays = GBuffer::render(world, width, height, offset);
    assert_eq!((raster.width, raster.height), (width, height));
    assert_eq!(raster.pixels.len(), rays.pixels.len());
    let mut a = Agreement {
        pixels: rays.pixels.len(),
        ..Agreement::default()
    };
    for (i, (r, t)) in raster.pixels.iter().zip(&rays.pixels).enumerate() {
        match (r, t) {
            (None, None) => {}
            (Some(_), None) | (None, Some(_)) => a.coverage_differs += 1,
            (Some(r), Some(t)) => {
                a.covered += 1;
                if (r.hit.instance, r.hit.triangle) != (t.hit.instance, t.hit.triangle) {
                    a.triangle_differs += 1;
                    continue;
                }
                let (x, y) = (i as u32 % width, i as u32 / width);
                // Tolerances: f32 rounding of two different but exact formulas for
                // the same point, relative to the distance (positions) or absolute
                // for unit vectors; the flags and ids must agree exactly.
                let scale = 1.0 + t.hit.t;
                let close = |a: Vec3, b: Vec3, tol: f32| (a - b).abs().max_element() <= tol;
                // A normal map's bilinear lookup magnifies the uv rounding like a
                // base-colour texture's: counted with the albedo below.
                let normal_mapped = world.scene.materials[r.hit.material.index()]
                    .normal_texture
                    .is_some();
                let same = close(r.hit.position, t.hit.position, 2e-5 * scale)
                    && close(r.hit.geometric_normal, t.hit.geometric_normal, 1e-5)
                    && (normal_mapped || close(r.hit.shading_normal, t.hit.shading_normal, 1e-4))
                    && (r.hit.uv - t.hit.uv).abs().max_element()
                        <= 1e-4 * (1.0 + t.hit.uv.abs().max_element())
                    && r.hit.emission == t.hit.emission
                    && r.hit.material == t.hit.material
                    && r.hit.front_face == t.hit.front_face
                    && r.hit.reflects == t.hit.reflects
                    && (r.hit.t - t.hit.t).abs() <= 2e-5 * scale
                    && close(r.to_camera, t.to_camera, 1e-6);
                assert!(
                    same,
                    "{what} {width}x{height} pixel ({x}, {y}): same triangle, different surface:\nraster {r:?}\nrays   {t:?}"
                );
                // Bilinear texture lookups magnify the uv rounding; a few pixels on
                // sharp texture edges may differ more: count them, bounded below.
                if !close(r.hit.albedo, t.hit.albedo, 1e-3)
                    || !close(r.hit.shading_normal, t.hit.shading_normal, 1e-3)
                {
                    a.albedo_differs += 1;
                }
            }
        }
    }
    assert!(
        a.albedo_differs as f64 <= 1e-3 * a.covered.max(1) as f64,
        "{what} {width}x{height}: albedo or shading normal differs on {} of {} same-triangle pixels",
        a.albedo_differs,
        a.covered
    );
    let bad = a.coverage_differs + a.triangle_differs;
    println!("{what} {width}x{height}: {a:?}");
    assert!(
        bad as f64 <= 1e-3 * a.pixels as f64,
        "{what} {width}x{height}: {bad} of {} pixels disagree ({a:?})",
        a.pixels
    );
    a
}

fn builtin(name: &str) -> World {
    World::new(illume_scene::builtin::load(name).expect("built-in scene"))
}

fn file(relative: &str) -> World {
    let path = illume_scene::shared_scenes_dir().join(relative);
    World::new(
        illume_scene::load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
}

const SIZES: [(u32, u32); 3] = [(160, 120), (331, 207), (800, 600)];

/// Moves every instance and then the camera, comparing after each edit.
fn compare_while_moving(world: &mut World, what: &str) {
    for (w, h) in SIZES {
        compare(world, w, h, what);
    }
    let n = world.scene.instances.len();
    for i in 0..n {
        let old = world.scene.instances[i].world_from_object;
        let nudge = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(0.3 + i as f32 * 0.1),
            Vec3::new(0.05, 0.02 * i as f32, -0.04),
        );
        world
            .apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(i as u32),
                world_from_object: old * nudge,
            })
            .expect("edit applies");
    }
    compare(world, 320, 240, &format!("{what} (instances moved)"));
    let cam = world.scene.camera.world_from_camera;
    world
        .apply_edit(&Edit::SetCameraTransform {
            world_from_camera: cam
                * Affine3A::from_rotation_translation(
                    Quat::from_euler(glam::EulerRot::YXZ, 0.4, -0.2, 0.1),
                    Vec3::new(0.1, -0.05, 0.15),
                ),
        })
        .expect("edit applies");
    compare(world, 320, 240, &format!("{what} (camera moved)"));
}

#[test]
fn cornell_spot() {
    compare_while_moving(&mut builtin("cornell-spot"), "cornell-spot");
}

#[test]
fn cube_in_box_clips_the_walls_behind_the_camera() {
    let mut world = builtin("cube-in-box");
    let a = compare(&world, 320, 240, "cube-in-box");
    assert_eq!(a.covered, a.pixels, "a closed box covers every pixel");
    compare_while_moving(&mut world, "cube-in-box");
}

#[test]
fn furnace_everything_clips() {
    let world = builtin("furnace");
    for (w, h) in SIZES {
        let a = compare(&world, w, h, "furnace");
        // The tessellated sphere leaves a few pixels open to rays too (coverage agrees).
        assert!(a.covered as f64 >= 0.999 * a.pixels as f64, "{a:?}");
    }
}

#[test]
fn gltf_cornell_spot() {
    compare_while_moving(&mut file("gltf/cornell_spot.gltf"), "cornell_spot.gltf");
}

#[test]
fn sponza() {
    compare_while_moving(&mut file("dabrovic_sponza/sponza.obj"), "sponza");
}

/// Jittered frames: the rasterizer's shifted projection samples each pixel where a ray
/// through the same offset does, over the whole pixel (corners included), on a box and
/// on Sponza (textured, normal-mapped, alpha-masked).
#[test]
fn offsets_in_the_pixel_match_rays_through_them() {
    for (name, world) in [
        ("cornell-spot", builtin("cornell-spot")),
        ("sponza", file("dabrovic_sponza/sponza.obj")),
    ] {
        let centre = GBuffer::rasterize(&world, 160, 120);
        for offset in [(0.1, 0.9), (0.83, 0.27), (0.0, 0.0), (0.999, 0.5)] {
            let offset = Vec2::from(offset);
            compare_at(&world, 160, 120, offset, &format!("{name} at {offset}"));
            // The samples moved: positions differ from the centre's on most covered pixels.
            let mut g = GBuffer::empty();
            g.rasterize_into_at(&world, 160, 120, TextureFilter::Bilinear, offset);
            let both: Vec<_> = g
                .pixels
                .iter()
                .zip(&centre.pixels)
                .filter_map(|(a, b)| Some((a.as_ref()?, b.as_ref()?)))
                .collect();
            let moved = both
                .iter()
                .filter(|(a, b)| a.hit.position != b.hit.position)
                .count();
            assert!(
                moved > both.len() * 9 / 10,
                "{name} at {offset}: {moved} of {} moved",
                both.len()
            );
        }
    }
}

#[test]
fn exact_triangle_query_equals_the_bvh_bit_for_bit() {
    let world = builtin("cornell-spot");
    let scene: &Scene = &world.scene;
    let cam = illume_transport::CameraRays::new(&scene.camera, 97, 61);
    let mut checked = 0;
    for y in 0..61 {
        for x in 0..97 {
            let ray = cam.ray(x, y, Vec2::new(0.3, 0.7));
            let Some(hit) = world.tracer.intersect(&ray, illume_scene::MASK_DEFAULT) else {
                continue;
            };
            let mesh = &scene.meshes[scene.instances[hit.instance.index()].mesh.index()];
            let again = world.tracer.intersect_instance_triangle(
                &ray,
                hit.instance,
                hit.triangle,
                mesh.triangle(hit.triangle as usize),
            );
            assert_eq!(again, Some(hit), "pixel ({x}, {y})");
            checked += 1;
        }
    }
    assert!(checked > 97 * 61 / 2, "{checked} hits checked");
}

/// An incrementally rebuilt G-buffer (pixels of static triangles kept) is bit-identical
/// to a fresh one through an animation, a camera move and a material edit, and keeps
/// most pixels when only a small object moves.
#[test]
fn incremental_rebuild_equals_fresh_build() {
    let mut world = builtin("cornell-spot");
    let (w, h) = (200, 150);
    let mut g = GBuffer::rasterize(&world, w, h);
    assert_eq!(g.reused_pixels, 0, "nothing to reuse in a new G-buffer");
    let same = |a: &GBuffer, b: &GBuffer| {
        a.pixels.iter().zip(&b.pixels).all(|(p, q)| match (p, q) {
            (None, None) => true,
            (Some(p), Some(q)) => format!("{p:?}") == format!("{q:?}"),
            _ => false,
        })
    };
    g.rasterize_into(&world, w, h);
    assert_eq!(
        g.reused_pixels,
        (w * h) as u64,
        "nothing changed: the whole G-buffer is kept"
    );
    for k in 1..=6 {
        world.set_time(k as f64 * 0.25); // the sphere and the light move
        g.rasterize_into(&world, w, h);
        let fresh = GBuffer::rasterize(&world, w, h);
        assert!(same(&g, &fresh), "frame {k}: incremental build differs");
        assert!(
            g.reused_pixels > (w * h) as u64 / 2 && g.reused_pixels < (w * h) as u64,
            "frame {k}: {} pixels reused",
            g.reused_pixels
        );
    }
    let cam = world.scene.camera.world_from_camera;
    world
        .apply_edit(&Edit::SetCameraTransform {
            world_from_camera: cam * Affine3A::from_translation(Vec3::new(0.05, 0.0, 0.0)),
        })
        .expect("edit applies");
    g.rasterize_into(&world, w, h);
    assert_eq!(g.reused_pixels, 0, "a camera move rebuilds everything");
    assert!(same(&g, &GBuffer::rasterize(&world, w, h)));
    let mut material = world.scene.materials[0].clone();
    material.base_color *= 0.5;
    world
        .apply_edit(&Edit::SetMaterial {
            material: illume_scene::MaterialId(0),
            value: material,
        })
        .expect("edit applies");
    g.rasterize_into(&world, w, h);
    assert_eq!(g.reused_pixels, 0, "a material edit rebuilds everything");
    assert!(same(&g, &GBuffer::rasterize(&world, w, h)));
}

/// Surface records carry what finds mesh elements and texels without re-intersecting: the
/// mesh id and the barycentrics, the same from the rasterizer and from rays, and they
/// rebuild the hit point from the mesh's corners.
#[test]
fn barycentrics_and_mesh_ids_rebuild_the_hit_point() {
    let world = builtin("cornell-spot");
    let (w, h) = (64, 48);
    let raster = GBuffer::rasterize(&world, w, h);
    let rays = GBuffer::render(&world, w, h, Vec2::splat(0.5));
    let mut checked = 0;
    for (a, b) in raster.pixels.iter().zip(&rays.pixels) {
        let (Some(a), Some(b)) = (a, b) else { continue };
        for hit in [&a.hit, &b.hit] {
            let inst = &world.scene.instances[hit.instance.index()];
            assert_eq!(hit.mesh, inst.mesh);
            let mesh = &world.scene.meshes[hit.mesh.index()];
            let [p0, p1, p2] = mesh
                .triangle(hit.triangle as usize)
                .map(|p| inst.world_from_object.transform_point3(p));
            let (b1, b2) = (hit.barycentrics.x, hit.barycentrics.y);
            assert!(
                b1 >= -1e-4 && b2 >= -1e-4 && b1 + b2 <= 1.0 + 1e-4,
                "{b1} {b2}"
            );
            let p = p0 * (1.0 - b1 - b2) + p1 * b1 + p2 * b2;
            assert!(
                (p - hit.position).length() < 1e-4,
                "{p} vs {}",
                hit.position
            );
        }
        if (a.hit.instance, a.hit.triangle) == (b.hit.instance, b.hit.triangle) {
            assert!((a.hit.barycentrics - b.hit.barycentrics).length() < 1e-4);
            checked += 1;
        }
    }
    assert!(checked > (w * h / 2) as usize, "{checked} pixels compared");
}

/// An alpha-masked occluder: rasterization and rays see the plane through the same half
/// of it (the rasterizer tests each covered pixel centre as the tracer tests hits), and
/// its opaque half covers as many pixels as its area says.
#[test]
fn cut_outs_match_rays() {
    let mut scene = illume_scene::builtin::lit_plane(
        illume_scene::LightKind::Point {
            intensity: illume_core::Rgb::ONE,
        },
        illume_scene::Trs::from_translation(Vec3::Y),
        0.5,
        true,
    );
    // Off the plane's axis, so that no pixel centre lies exactly on the diagonal its two
    // triangles share (a tie either side may win).
    illume_scene::builtin::look_from(
        &mut scene,
        Vec3::new(0.13, 3.0, 0.07),
        Vec3::new(0.01, 0.0, 0.02),
    )
    .expect("a valid view");
    let opaque = World::new(scene.clone());
    illume_scene::builtin::cut_half_of_occluder(&mut scene);
    let world = World::new(scene);
    let occluder_pixels = |g: &GBuffer| {
        g.pixels
            .iter()
            .filter(|p| p.as_ref().is_some_and(|p| p.hit.instance == InstanceId(1)))
            .count()
    };
    for (w, h) in SIZES {
        compare(&world, w, h, "cut-out occluder");
        let full = occluder_pixels(&GBuffer::rasterize(&opaque, w, h));
        let half = occluder_pixels(&GBuffer::rasterize(&world, w, h));
        let ratio = half as f64 / full as f64;
        assert!(
            (ratio - 0.5).abs() < 0.02,
            "{w}x{h}: the cut-out keeps {half} of {full} pixels"
        );
    }
}
