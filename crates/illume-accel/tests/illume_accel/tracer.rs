//! The two-level BVH against the brute-force oracle: closest hits, occlusion and masks on
//! built-in scenes, random triangle soups and (when the loaders can read them) the shared
//! scenes, before and after instances move; plus `validate()` and "update never rebuilds
//! a mesh BVH". Every query check runs in every traversal kernel this CPU has (the
//! portable one and, where present, AVX2), and one test asserts that all kernels give
//! bit-identical hits on random rays.

use illume_accel::brute_force::BruteForce;
use illume_accel::{Hit, Tracer, TraversalKernel};
use illume_core::sampling::Pcg32;
use illume_core::{Aabb, Affine3A, Quat, Ray, Vec2, Vec3};
use illume_scene::builtin::SceneBuilder;
use illume_scene::{Edit, InstanceId, MASK_DEFAULT, Material, Mesh, MeshId, Scene, Trs};
use rayon::prelude::*;
use std::path::PathBuf;

fn uniform(rng: &mut Pcg32) -> f32 {
    rng.next_f64() as f32
}

fn random_dir(rng: &mut Pcg32) -> Vec3 {
    let z = 1.0 - 2.0 * uniform(rng);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * uniform(rng);
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` rays with origins uniform in `bounds` (grown by 10 %) and uniform directions; every
/// 16th ray is axis-aligned (zero direction components), every 8th has a finite `t_max`,
/// every 32nd is not unit length.
fn random_rays(bounds: Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::new(seed, 7);
    let grow = bounds.extent() * 0.1;
    let (lo, size) = (bounds.min - grow, bounds.extent() + 2.0 * grow);
    (0..n)
        .map(|i| {
            let o = lo + size * Vec3::new(uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
            let mut d = random_dir(&mut rng);
            if i % 16 == 0 {
                let axis = rng.next_below(3) as usize;
                let mut a = Vec3::ZERO;
                a[axis] = if uniform(&mut rng) < 0.5 { -1.0 } else { 1.0 };
                d = a;
            }
            if i % 32 == 1 {
                d *= 0.25 + 3.0 * uniform(&mut rng);
            }
            let mut ray = Ray::new(o, d);
            if i % 8 == 3 {
                ray.t_max = uniform(&mut rng) * size.length() * 0.5;
            }
            ray
        })
        .collect()
}

/// Distance of barycentrics from the triangle's boundary.
fn edge_distance(b: Vec2) -> f32 {
    b.x.min(b.y).min(1.0 - b.x - b.y)
}

/// Relative tolerance on `t`.
const T_TOLERANCE: f32 = 1e-4;
/// Absolute tolerance on hit positions, relative to the scene's size: world-space and
/// object-space arithmetic round differently at the level of a few ulps of the
/// coordinates, which dominates `t`'s error for hits very near the origin.
const POSITION_TOLERANCE: f32 = 1e-5;
const EDGE: f32 = 1e-4;

/// Compares the tracer's closest hits with the oracle's; returns the number of rays whose
/// answers differ only because a hit grazes a triangle edge (where world-space and
/// object-space rounding may disagree), and panics on any other difference.
fn compare_closest(
    scene_name: &str,
    tracer: &Tracer,
    oracle: &BruteForce,
    rays: &[Ray],
    mask: u32,
    scene_size: f32,
) -> usize {
    let ours = tracer.intersect_batch(rays, mask);
    let theirs: Vec<Option<Hit>> = rays.par_iter().map(|r| oracle.intersect(r, mask)).collect();
    let mut grazes = 0;
    for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        let ok = match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let slack = POSITION_TOLERANCE * scene_size / rays[i].dir.length();
                let tie = (a.t - b.t).abs() <= T_TOLERANCE * a.t.abs().max(b.t.abs()) + slack;
                let same = a.instance == b.instance && a.triangle == b.triangle;
                if same {
                    assert!(
                        tie,
                        "{scene_name} ray {i}: same triangle, t {} vs oracle {}",
                        a.t, b.t
                    );
                    assert!(
                        (a.barycentrics - b.barycentrics).abs().max_element() < 1e-3,
                        "{scene_name} ray {i}: barycentrics {a:?} vs {b:?}"
                    );
                }
                if tie {
                    true
                } else {
                    grazes += 1;
                    edge_distance(a.barycentrics) < EDGE || edge_distance(b.barycentrics) < EDGE
                }
            }
            (Some(h), None) | (None, Some(h)) => {
                grazes += 1;
                edge_distance(h.barycentrics) < EDGE
            }
        };
        assert!(
            ok,
            "{scene_name} ray {i} {:?} mask {mask}: BVH {a:?}, brute force {b:?}",
            rays[i]
        );
    }
    assert!(
        grazes * 10_000 <= rays.len().max(10_000),
        "{scene_name}: {grazes} edge disagreements in {} rays",
        rays.len()
    );
    grazes
}

fn compare_occluded(
    scene_name: &str,
    tracer: &Tracer,
    oracle: &BruteForce,
    rays: &[Ray],
    mask: u32,
) {
    let ours = tracer.occluded_batch(rays, mask);
    let mut disagreements = 0;
    for (i, (ray, &a)) in rays.iter().zip(&ours).enumerate() {
        assert_eq!(
            a,
            tracer.occluded(ray, mask),
            "{scene_name} ray {i}: batch and single occlusion differ"
        );
        let b = oracle.occluded(ray, mask);
        if a != b {
            disagreements += 1;
            // Only a grazing hit or one at the very end of the segment may differ.
            let near = oracle
                .intersect(
                    &Ray {
                        t_max: ray.t_max * (1.0 + 1e-3),
                        ..*ray
                    },
                    mask,
                )
                .or_else(|| tracer.intersect(ray, mask));
            let justified = near.is_some_and(|h| {
                edge_distance(h.barycentrics) < EDGE || (h.t - ray.t_max).abs() <= 1e-3 * ray.t_max
            });
            assert!(
                justified,
                "{scene_name} ray {i} {ray:?}: occluded {a}, brute force {b}, hit {near:?}"
            );
        }
    }
    assert!(
        disagreements * 10_000 <= rays.len().max(10_000),
        "{scene_name}: {disagreements} occlusion disagreements"
    );
}

/// Largest absolute coordinate of the scene's bounds (the scale of rounding errors).
fn size(scene: &Scene) -> f32 {
    let b = scene.bounds();
    b.min.abs().max(b.max.abs()).max_element()
}

/// `tracer` switched to each kernel this CPU can run, with the kernel's name.
fn in_every_kernel(tracer: &Tracer) -> Vec<(String, Tracer)> {
    let kernels = TraversalKernel::available();
    assert!(kernels.contains(&TraversalKernel::Portable));
    kernels
        .into_iter()
        .map(|k| {
            let mut t = tracer.clone();
            t.set_kernel(k).unwrap();
            assert_eq!(t.kernel(), k);
            (k.name().to_string(), t)
        })
        .collect()
}

fn check(scene_name: &str, scene: &Scene, n: usize, seed: u64) {
    let tracer = Tracer::new(scene);
    tracer
        .validate()
        .unwrap_or_else(|e| panic!("{scene_name}: {e}"));
    let oracle = BruteForce::new(scene);
    let rays = random_rays(scene.bounds(), n, seed);
    for (kernel, tracer) in in_every_kernel(&tracer) {
        let name = format!("{scene_name} ({kernel})");
        compare_closest(&name, &tracer, &oracle, &rays, MASK_DEFAULT, size(scene));
        compare_occluded(&name, &tracer, &oracle, &rays[..n / 4], MASK_DEFAULT);
    }
}

fn builtin(name: &str) -> Scene {
    illume_scene::builtin::load(name).unwrap()
}

#[test]
fn builtin_scenes_validate_and_agree_with_brute_force() {
    check("cornell-spot", &builtin("cornell-spot"), 100_000, 1);
    check("cube-in-box", &builtin("cube-in-box"), 20_000, 2);
    check("furnace", &builtin("furnace"), 20_000, 3);
}

#[test]
fn cornell_hits_are_real() {
    // A ray straight down from the box centre hits the floor (instance 0) at t = 1.
    let scene = builtin("cornell-spot");
    let tracer = Tracer::new(&scene);
    let hit = tracer
        .intersect(
            &Ray::new(Vec3::new(0.3, 1.0, 0.5), Vec3::NEG_Y),
            MASK_DEFAULT,
        )
        .unwrap();
    assert_eq!(hit.instance, InstanceId(0));
    assert!((hit.t - 1.0).abs() < 1e-6, "t = {}", hit.t);
    // A non-unit direction halves t: t is in units of the ray's direction.
    let hit2 = tracer
        .intersect(
            &Ray::new(Vec3::new(0.3, 1.0, 0.5), Vec3::NEG_Y * 2.0),
            MASK_DEFAULT,
        )
        .unwrap();
    assert!((hit2.t - 0.5).abs() < 1e-6, "t = {}", hit2.t);
    // The segment stops short of the floor: no hit, not occluded.
    let short = Ray::segment(Vec3::new(0.3, 1.0, 0.5), Vec3::NEG_Y, 0.99);
    assert_eq!(tracer.intersect(&short, MASK_DEFAULT), None);
    assert!(!tracer.occluded(&short, MASK_DEFAULT));
    assert!(tracer.occluded(
        &Ray::segment(Vec3::new(0.3, 1.0, 0.5), Vec3::NEG_Y, 1.01),
        MASK_DEFAULT
    ));
    // Out of the open side (+z): nothing.
    assert_eq!(
        tracer.intersect(&Ray::new(Vec3::new(0.0, 1.0, 0.5), Vec3::Z), MASK_DEFAULT),
        None
    );
}

/// A scene of random triangle soups and a finely tessellated grid, several instances of
/// each, with rotation and non-uniform scale.
fn soup_scene(seed: u64) -> Scene {
    let mut rng = Pcg32::new(seed, 3);
    let mut b = SceneBuilder::new();
    let mat = b.material(Material::default());
    let mut soup = Mesh {
        name: "soup".into(),
        ..Default::default()
    };
    for t in 0..1500u32 {
        let c = Vec3::new(uniform(&mut rng), uniform(&mut rng), uniform(&mut rng)) * 2.0 - 1.0;
        let size = 0.02 + 0.2 * uniform(&mut rng).powi(3);
        for _ in 0..3 {
            soup.positions.push(c + random_dir(&mut rng) * size);
        }
        soup.indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        soup.triangle_materials.push(mat);
    }
    let soup = b.mesh(soup);
    let mut grid = Mesh {
        name: "grid".into(),
        ..Default::default()
    };
    let n = 24u32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                i as f32 / n as f32 * 2.0 - 1.0,
                j as f32 / n as f32 * 2.0 - 1.0,
            );
            grid.positions
                .push(Vec3::new(x, 0.1 * (3.0 * x).sin() * (2.0 * z).cos(), z));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            grid.indices.push([v, v + n + 1, v + 1]);
            grid.indices.push([v + 1, v + n + 1, v + n + 2]);
            grid.triangle_materials.extend([mat, mat]);
        }
    }
    let grid = b.mesh(grid);
    let empty = b.mesh(Mesh {
        name: "empty".into(),
        ..Default::default()
    });
    b.placed("soup_a", soup, Trs::IDENTITY, true);
    b.placed(
        "soup_b",
        soup,
        Trs {
            translation: Vec3::new(2.5, 0.0, 0.0),
            rotation: Quat::from_rotation_z(0.7),
            scale: Vec3::new(1.0, 0.5, 2.0),
        },
        true,
    );
    b.placed(
        "grid_a",
        grid,
        Trs::from_translation(Vec3::new(0.0, -1.5, 0.0)),
        true,
    );
    b.placed(
        "grid_b",
        grid,
        Trs {
            translation: Vec3::new(1.0, 1.5, 0.5),
            rotation: Quat::from_rotation_x(2.5),
            scale: Vec3::splat(1.5),
        },
        true,
    );
    b.placed("nothing", empty, Trs::IDENTITY, false);
    b.finish("test:soup")
}

#[test]
fn triangle_soups_validate_and_agree_with_brute_force() {
    let cut = cut_soup(13);
    cut.validate().unwrap();
    check("soup with a cut-out grid", &cut, 30_000, 14);
    let rays = random_rays(cut.bounds(), 10_000, 15);
    let (with_holes, without) = (
        Tracer::new(&cut).intersect_batch(&rays, MASK_DEFAULT),
        Tracer::new(&soup_scene(13)).intersect_batch(&rays, MASK_DEFAULT),
    );
    let through = with_holes
        .iter()
        .zip(&without)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        through > 100,
        "only {through} rays pass through the grid's holes"
    );
    let scene = soup_scene(11);
    scene.validate().unwrap();
    check("soup", &scene, 30_000, 12);
    let stats = Tracer::new(&scene).stats();
    assert_eq!(stats.mesh_bvhs, 3);
    assert_eq!(stats.triangles, 1500 + 2 * 24 * 24);
    assert_eq!(stats.instances, 4, "the empty mesh's instance is left out");
    assert!(
        stats.mesh_nodes > 0
            && stats.instance_nodes > 0
            && stats.memory_bytes > stats.triangles * 36
    );
}

/// Moves, rotates and scales every instance through `Edit::SetInstanceTransform`.
fn move_everything(scene: &mut Scene, step: u32) {
    for i in 0..scene.instances.len() {
        let f = step as f32 + i as f32 * 0.37;
        let current = scene.instances[i].world_from_object;
        let motion = Affine3A::from_scale_rotation_translation(
            Vec3::new(
                1.0 + 0.1 * f.sin(),
                1.0 - 0.05 * f.cos(),
                1.0 + 0.2 * (0.5 * f).sin(),
            ),
            Quat::from_euler(glam::EulerRot::YXZ, 0.3 * f, 0.1 * f.sin(), 0.05),
            Vec3::new(0.1 * f.cos(), 0.05 * f.sin(), -0.1),
        );
        scene
            .apply_edit(&Edit::SetInstanceTransform {
                instance: InstanceId(i as u32),
                world_from_object: motion * current,
            })
            .unwrap();
    }
}

#[test]
fn moved_instances_agree_after_update_without_mesh_rebuilds() {
    for (name, mut scene, n) in [
        ("cornell-spot", builtin("cornell-spot"), 100_000),
        ("soup", soup_scene(5), 20_000),
    ] {
        let mut tracer = Tracer::new(&scene);
        let before = tracer.stats();
        assert_eq!(before.mesh_builds, scene.meshes.len() as u64);
        let addresses: Vec<_> = (0..scene.meshes.len())
            .map(|m| tracer.mesh_bvh_address(MeshId(m as u32)).unwrap())
            .collect();
        for step in 1..=2 {
            move_everything(&mut scene, step);
            tracer.update(&scene);
            tracer
                .validate()
                .unwrap_or_else(|e| panic!("{name} step {step}: {e}"));
            let oracle = BruteForce::new(&scene);
            let rays = random_rays(scene.bounds(), n / 2, 100 + step as u64);
            for (kernel, tracer) in in_every_kernel(&tracer) {
                let name = format!("{name} ({kernel})");
                compare_closest(&name, &tracer, &oracle, &rays, MASK_DEFAULT, size(&scene));
                compare_occluded(&name, &tracer, &oracle, &rays[..n / 8], MASK_DEFAULT);
            }
        }
        let after = tracer.stats();
        assert_eq!(
            after.mesh_builds, before.mesh_builds,
            "{name}: update rebuilt a mesh BVH"
        );
        assert_eq!(after.mesh_nodes, before.mesh_nodes);
        for (m, a) in addresses.iter().enumerate() {
            assert_eq!(
                tracer.mesh_bvh_address(MeshId(m as u32)),
                Some(*a),
                "{name}: mesh {m}'s BVH storage moved"
            );
        }
    }
}

#[test]
fn animation_time_steps_agree() {
    let mut scene = builtin("cornell-spot");
    let mut tracer = Tracer::new(&scene);
    for (k, t) in [0.5, 1.0, 1.7].into_iter().enumerate() {
        scene.set_time(t);
        tracer.update(&scene);
        tracer.validate().unwrap();
        let rays = random_rays(scene.bounds(), 10_000, 200 + k as u64);
        for (kernel, tracer) in in_every_kernel(&tracer) {
            compare_closest(
                &format!("cornell-spot animated ({kernel})"),
                &tracer,
                &BruteForce::new(&scene),
                &rays,
                MASK_DEFAULT,
                size(&scene),
            );
        }
    }
    assert_eq!(tracer.stats().mesh_builds, scene.meshes.len() as u64);
}

#[test]
fn masks_hide_instances() {
    let mut scene = builtin("cornell-spot");
    let sphere = scene
        .instances
        .iter()
        .position(|i| i.name == "sphere")
        .unwrap();
    scene.instances[sphere].mask = 2;
    for (kernel, tracer) in in_every_kernel(&Tracer::new(&scene)) {
        masks_hide_instances_in(&scene, sphere, &tracer, &kernel);
    }
}

fn masks_hide_instances_in(scene: &Scene, sphere: usize, tracer: &Tracer, kernel: &str) {
    let name = format!("cornell-spot masked ({kernel})");
    tracer.validate().unwrap();
    let oracle = BruteForce::new(scene);
    let rays = random_rays(scene.bounds(), 40_000, 9);
    for mask in [1u32, 2, 3] {
        compare_closest(&name, tracer, &oracle, &rays, mask, size(scene));
        compare_occluded(&name, tracer, &oracle, &rays[..10_000], mask);
    }
    let hits1 = tracer.intersect_batch(&rays, 1);
    let hits2 = tracer.intersect_batch(&rays, 2);
    assert!(
        hits1.iter().flatten().all(|h| h.instance.index() != sphere),
        "mask-1 rays see the mask-2 sphere"
    );
    assert!(
        hits2.iter().flatten().all(|h| h.instance.index() == sphere),
        "mask-2 rays see mask-1 instances"
    );
    assert!(
        hits2.iter().flatten().count() > 100,
        "mask-2 rays must hit the sphere"
    );
    // A ray aimed at the sphere's centre: hidden for mask 1 (hits the floor), seen by mask 2.
    let centre = Vec3::from(scene.instances[sphere].world_from_object.translation);
    let down = Ray::new(centre + Vec3::Y * 1.0, Vec3::NEG_Y);
    assert_eq!(tracer.intersect(&down, 1).unwrap().instance, InstanceId(0));
    assert_eq!(tracer.intersect(&down, 2).unwrap().instance.index(), sphere);
    assert_eq!(tracer.intersect(&down, 0), None);
}

fn shared_scene(rel: &str) -> Scene {
    let path: PathBuf = illume_scene::shared_scenes_dir().join(rel);
    illume_scene::load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn shared_scenes_validate_and_agree() {
    for (rel, rays) in [
        ("cornell_box/CornellBox-Sphere.obj", 20_000),
        ("cornell_box/CornellBox-Original.obj", 20_000),
        ("gltf/cornell_spot.gltf", 20_000),
        ("dabrovic_sponza/sponza.obj", 400),
    ] {
        let scene = shared_scene(rel);
        check(rel, &scene, rays, 77);
        println!("{rel}: validated, {rays} rays agree with brute force");
    }
}

/// Alpha masks: rays and shadow rays pass through the holes of a cut-out (the tracer
/// agrees with the brute-force oracle, which tests the same mask), and only there.
#[test]
fn cut_outs_let_rays_through_their_holes_only() {
    let mut scene = illume_scene::builtin::lit_plane(
        illume_scene::LightKind::Point {
            intensity: illume_core::Rgb::ONE,
        },
        Trs::from_translation(Vec3::Y),
        0.5,
        true,
    );
    illume_scene::builtin::cut_half_of_occluder(&mut scene);
    check("cut-out occluder", &scene, 50_000, 11);
    for (kernel, tracer) in in_every_kernel(&Tracer::new(&scene)) {
        cut_outs_in(&tracer, &kernel);
    }
}

fn cut_outs_in(tracer: &Tracer, kernel: &str) {
    // Straight down through the occluder's square (x, z ∈ [−0.2, 0.2] at y = 0.5): its
    // half z ≥ 0 remains (bilinear alpha crosses ½ at z = 0).
    let mut seen = [0; 2];
    for i in 0..40 {
        for k in 0..40 {
            let (x, z) = (-0.195 + 0.01 * i as f32, -0.195 + 0.01 * k as f32);
            let ray = Ray::new(Vec3::new(x, 1.0, z), -Vec3::Y);
            let hit = tracer
                .intersect(&ray, MASK_DEFAULT)
                .expect("the plane is below");
            let expect = if z > 0.0 { 1 } else { 0 };
            assert_eq!(
                hit.instance,
                InstanceId(expect),
                "{kernel}: ray down at ({x}, {z})"
            );
            seen[expect as usize] += 1;
            let to_occluder = Ray { t_max: 0.6, ..ray };
            assert_eq!(tracer.occluded(&to_occluder, MASK_DEFAULT), z > 0.0);
        }
    }
    assert_eq!(seen, [800, 800]);
}

/// `soup_scene(seed)` with its grid cut out in a checker pattern: alpha-mask holes in a
/// mesh whose leaves hold several triangle packets.
fn cut_soup(seed: u64) -> Scene {
    use illume_scene::{MaterialId, Texture, TextureId, WrapMode};
    let mut scene = soup_scene(seed);
    scene.textures.push(std::sync::Arc::new(Texture {
        name: "checker".into(),
        width: 4,
        height: 4,
        texels: vec![illume_core::Rgb::ONE; 16],
        wrap_u: WrapMode::Repeat,
        wrap_v: WrapMode::Repeat,
        alpha: (0..16)
            .map(|i| if (i + i / 4) % 2 == 0 { 0 } else { 255 })
            .collect(),
    }));
    let texture = TextureId(scene.textures.len() as u32 - 1);
    let grid = scene.meshes.iter().position(|m| m.name == "grid").unwrap();
    let mut material = scene.materials[scene.meshes[grid].triangle_materials[0].index()].clone();
    material.name = "checker cut-out".into();
    material.alpha_texture = Some(texture);
    material.alpha_cutoff = Some(0.5);
    scene.materials.push(material);
    let id = MaterialId(scene.materials.len() as u32 - 1);
    let mut mesh = (*scene.meshes[grid]).clone();
    mesh.uvs = mesh
        .positions
        .iter()
        .map(|p| Vec2::new(p.x, p.z) * 1.7)
        .collect();
    mesh.triangle_materials.fill(id);
    scene.meshes[grid] = std::sync::Arc::new(mesh);
    scene
}

/// The bits of a hit, so that equality is bit-for-bit (and -0.0 differs from 0.0).
fn hit_bits(h: &Option<Hit>) -> Option<(u32, u32, u32, u32, u32)> {
    h.map(|h| {
        (
            h.t.to_bits(),
            h.instance.0,
            h.triangle,
            h.barycentrics.x.to_bits(),
            h.barycentrics.y.to_bits(),
        )
    })
}

/// The same random rays through every kernel this CPU has: identical closest hits (bit
/// for bit, including the hit geometry), occlusion and masked queries, on scenes with
/// instances (rotated, scaled, masked), triangle soups, alpha cut-outs and Sponza.
#[test]
fn every_kernel_gives_identical_hits() {
    let mut masked = builtin("cornell-spot");
    masked.instances[1].mask = 2;
    let mut moved = soup_scene(21);
    move_everything(&mut moved, 1);
    let mut cut = illume_scene::builtin::lit_plane(
        illume_scene::LightKind::Point {
            intensity: illume_core::Rgb::ONE,
        },
        Trs::from_translation(Vec3::Y),
        0.5,
        true,
    );
    illume_scene::builtin::cut_half_of_occluder(&mut cut);
    let kernels = TraversalKernel::available();
    println!("kernels on this CPU: {kernels:?}");
    for (name, scene, n) in [
        ("cornell-spot masked", masked, 50_000),
        ("soup moved", moved, 50_000),
        ("cut-out", cut, 20_000),
        ("soup with a cut-out grid", cut_soup(23), 50_000),
        ("sponza", shared_scene("dabrovic_sponza/sponza.obj"), 20_000),
    ] {
        let tracers = in_every_kernel(&Tracer::new(&scene));
        let (reference_kernel, reference) = &tracers[0];
        let rays = random_rays(scene.bounds(), n, 31);
        for mask in [MASK_DEFAULT, 1, 2] {
            let want = reference.intersect_batch(&rays, mask);
            let want_occluded = reference.occluded_batch(&rays, mask);
            let hits = want.iter().flatten().count();
            assert!(
                mask != MASK_DEFAULT || hits > n / 10,
                "{name}: only {hits} hits"
            );
            for (kernel, tracer) in &tracers[1..] {
                let got = tracer.intersect_batch(&rays, mask);
                let got_occluded = tracer.occluded_batch(&rays, mask);
                for (i, ray) in rays.iter().enumerate() {
                    assert_eq!(
                        hit_bits(&got[i]),
                        hit_bits(&want[i]),
                        "{name} mask {mask} ray {i} {ray:?}: {kernel} {:?}, {reference_kernel} {:?}",
                        got[i],
                        want[i]
                    );
                    assert_eq!(
                        got_occluded[i], want_occluded[i],
                        "{name} mask {mask} ray {i} {ray:?}: occlusion, {kernel} vs {reference_kernel}"
                    );
                }
                for ray in rays.iter().step_by(7) {
                    let (a, b) = (
                        tracer.intersect_geometry(ray, mask),
                        reference.intersect_geometry(ray, mask),
                    );
                    assert_eq!(hit_bits(&a.map(|g| g.0)), hit_bits(&b.map(|g| g.0)));
                    assert_eq!(
                        a.map(|g| g.1),
                        b.map(|g| g.1),
                        "{name}: geometry of {ray:?}"
                    );
                }
            }
        }
    }
}

/// Long thin triangles crossing a box in every direction (the shape pre-splitting is
/// for), among small ones.
fn sliver_scene(seed: u64) -> Scene {
    let mut rng = Pcg32::new(seed, 5);
    let mut b = SceneBuilder::new();
    let mat = b.material(Material::default());
    let mut mesh = Mesh {
        name: "slivers".into(),
        ..Default::default()
    };
    let point = |rng: &mut Pcg32| Vec3::new(uniform(rng), uniform(rng), uniform(rng)) * 2.0 - 1.0;
    for t in 0..600u32 {
        let a = point(&mut rng);
        let (c, d) = if t % 3 == 0 {
            // A sliver from one side of the box to another.
            let c = point(&mut rng);
            (c, c + random_dir(&mut rng) * 0.02)
        } else {
            (
                a + random_dir(&mut rng) * 0.05,
                a + random_dir(&mut rng) * 0.05,
            )
        };
        mesh.positions.extend([a, c, d]);
        mesh.indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        mesh.triangle_materials.push(mat);
    }
    let mesh = b.mesh(mesh);
    b.placed("slivers", mesh, Trs::IDENTITY, true);
    b.finish("test:slivers")
}

/// Pre-splitting: where the surface area heuristic prefers the split tree (slivers,
/// Sponza) it is kept, and it validates and agrees with the brute-force oracle in every
/// kernel; where it does not (the Cornell box's walls around its spheres), the tree is
/// the one built without splitting; a zero budget never splits.
#[test]
fn pre_split_trees_agree_with_brute_force_and_are_kept_only_when_cheaper() {
    use illume_accel::BvhSettings;
    let slivers = sliver_scene(3);
    let stats = Tracer::new(&slivers).stats();
    assert!(
        stats.stored_triangles > stats.triangles + stats.triangles / 10,
        "slivers: {} triangles stored {} times",
        stats.triangles,
        stats.stored_triangles
    );
    check("slivers", &slivers, 40_000, 41);
    let plain = Tracer::with_settings(
        &slivers,
        BvhSettings {
            split_budget: 0.0,
            ..Default::default()
        },
    );
    plain.validate().unwrap();
    assert_eq!(plain.stats().stored_triangles, plain.stats().triangles);
    // Same closest hits (the same triangle at the same distance) with and without
    // splitting, up to which of two triangles at exactly the same `t` wins.
    let rays = random_rays(slivers.bounds(), 20_000, 42);
    let split = Tracer::new(&slivers);
    for (i, (a, b)) in split
        .intersect_batch(&rays, MASK_DEFAULT)
        .iter()
        .zip(&plain.intersect_batch(&rays, MASK_DEFAULT))
        .enumerate()
    {
        assert_eq!(
            a.map(|h| h.t.to_bits()),
            b.map(|h| h.t.to_bits()),
            "ray {i}"
        );
    }
    let cornell = Tracer::new(&shared_scene("cornell_box/CornellBox-Sphere.obj")).stats();
    assert_eq!(
        cornell.stored_triangles, cornell.triangles,
        "Cornell box split"
    );
    let sponza = Tracer::new(&shared_scene("dabrovic_sponza/sponza.obj")).stats();
    assert!(
        sponza.stored_triangles > sponza.triangles,
        "Sponza not split: {} triangles",
        sponza.triangles
    );
}

/// The build splits large ranges between threads: the tree (split or not) must not depend
/// on how many threads there are.
#[test]
fn the_tree_is_the_same_whatever_the_thread_count() {
    let scene = shared_scene("dabrovic_sponza/sponza.obj");
    let build = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| Tracer::new(&scene))
    };
    let (one, four) = (build(1), build(4));
    let (a, b) = (one.stats(), four.stats());
    assert_eq!(
        (a.mesh_nodes, a.stored_triangles, a.memory_bytes),
        (b.mesh_nodes, b.stored_triangles, b.memory_bytes)
    );
    assert!(a.stored_triangles > a.triangles, "Sponza is built split");
    let rays = random_rays(scene.bounds(), 20_000, 51);
    let (ha, hb) = (
        one.intersect_batch(&rays, MASK_DEFAULT),
        four.intersect_batch(&rays, MASK_DEFAULT),
    );
    for (i, (x, y)) in ha.iter().zip(&hb).enumerate() {
        assert_eq!(hit_bits(x), hit_bits(y), "ray {i}");
    }
    four.validate().unwrap();
}
