//! Tracer benchmarks on 2 rayon threads: build time, incoherent closest-hit rays/s
//! (origins uniform in the scene box, uniform directions) and primary camera rays/s, on
//! the built-in Cornell box and, when the loaders read them, the shared Cornell box with
//! a sphere and Dabrovic Sponza; plus our mesh BVH against `obvhs` 0.4's compressed wide
//! BVH on the same triangles and rays (group `obvhs_vs_own`).
//!
//! ```text
//! CARGO_TARGET_DIR=/work/target-accel cargo bench -p illume-accel --bench trace
//! ```
//! Throughput is reported in elements/s = rays/s.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam034 as g34;
use illume_accel::Tracer;
use illume_accel::ray_sets::{incoherent_rays, primary_rays};
use illume_core::Ray;
use illume_scene::{MASK_DEFAULT, Scene};
use rayon::prelude::*;
use std::path::Path;
use std::time::Duration;

const THREADS: usize = 2;
const INCOHERENT_RAYS: usize = 200_000;
const PRIMARY_RAYS: usize = 256 * 256;

fn scenes() -> Vec<(String, Scene)> {
    let mut out = vec![(
        "cornell-spot".to_string(),
        illume_scene::builtin::load("cornell-spot").expect("built-in scene"),
    )];
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    for rel in [
        "cornell_box/CornellBox-Sphere.obj",
        "dabrovic_sponza/sponza.obj",
    ] {
        match illume_scene::load_scene(&shared.join(rel)) {
            Ok(scene) => out.push((
                Path::new(rel)
                    .file_stem()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned(),
                scene,
            )),
            Err(e) => eprintln!("skipping {rel}: {e}"),
        }
    }
    out
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .expect("thread pool")
}

fn tracer_benches(c: &mut Criterion) {
    let pool = pool();
    for (name, scene) in scenes() {
        let mut group = c.benchmark_group(format!("tracer/{name}"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3));
        group.throughput(Throughput::Elements(scene.instanced_triangle_count() as u64));
        group.bench_function("build", |b| b.iter(|| pool.install(|| Tracer::new(&scene))));
        let tracer = pool.install(|| Tracer::new(&scene));
        for (kind, rays) in [
            ("incoherent", incoherent_rays(&scene, INCOHERENT_RAYS, 1)),
            ("primary", primary_rays(&scene, PRIMARY_RAYS)),
        ] {
            group.throughput(Throughput::Elements(rays.len() as u64));
            group.bench_function(BenchmarkId::new("closest_hit", kind), |b| {
                b.iter(|| pool.install(|| tracer.intersect_batch(&rays, MASK_DEFAULT)))
            });
            group.bench_function(BenchmarkId::new("occluded", kind), |b| {
                b.iter(|| pool.install(|| tracer.occluded_batch(&rays, MASK_DEFAULT)))
            });
        }
        group.finish();
    }
}

/// `Tracer::update` (the instance level only) after moving every instance of a scene of
/// 1000 spheres; mesh BVHs are not rebuilt.
fn update_bench(c: &mut Criterion) {
    use illume_scene::builtin::{SceneBuilder, uv_sphere};
    use illume_scene::{Edit, InstanceId, Material, Trs};
    let mut b = SceneBuilder::new();
    let mat = b.material(Material::default());
    let sphere = b.mesh(uv_sphere(0.1, 24, 12, mat, false));
    for i in 0..1000 {
        let p = illume_core::Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
        b.placed(
            &format!("sphere{i}"),
            sphere,
            Trs::from_translation(p),
            true,
        );
    }
    let mut scene = b.finish("bench:spheres");
    let mut tracer = Tracer::new(&scene);
    let mut step = 0u32;
    let mut group = c.benchmark_group("update");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    group.bench_function("move_1000_instances", |bench| {
        bench.iter_batched_ref(
            || {
                step += 1;
                for i in 0..scene.instances.len() {
                    let mut m = scene.instances[i].world_from_object;
                    m.translation.y += 0.001 * (step as f32 + i as f32).sin();
                    scene
                        .apply_edit(&Edit::SetInstanceTransform {
                            instance: InstanceId(i as u32),
                            world_from_object: m,
                        })
                        .expect("finite transform");
                }
                scene.clone()
            },
            |moved| tracer.update(moved),
            criterion::BatchSize::LargeInput,
        )
    });
    group.finish();
    eprintln!("update/move_1000_instances: {:?}", tracer.stats());
}

/// obvhs's triangles (glam 0.34) for every instanced triangle of `scene`, world space.
fn obvhs_triangles(scene: &Scene) -> Vec<obvhs::triangle::Triangle> {
    let mut tris = Vec::new();
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh.index()];
        for t in 0..mesh.triangle_count() {
            let [v0, v1, v2] = mesh.triangle(t).map(|p| {
                let w = inst.world_from_object.transform_point3(p);
                g34::Vec3A::new(w.x, w.y, w.z)
            });
            tris.push(obvhs::triangle::Triangle { v0, v1, v2 });
        }
    }
    tris
}

fn obvhs_closest(
    bvh: &obvhs::cwbvh::CwBvh,
    tris: &[obvhs::triangle::Triangle],
    rays: &[Ray],
) -> Vec<f32> {
    let mut out = vec![f32::INFINITY; rays.len()];
    out.par_chunks_mut(256)
        .zip(rays.par_chunks(256))
        .for_each(|(out, rays)| {
            for (o, r) in out.iter_mut().zip(rays) {
                let ray = obvhs::ray::Ray::new(
                    g34::Vec3A::from_array(r.origin.to_array()),
                    g34::Vec3A::from_array(r.dir.to_array()),
                    r.t_min,
                    r.t_max,
                );
                let mut hit = obvhs::ray::RayHit::none();
                if bvh.ray_traverse(ray, &mut hit, |ray, id| tris[id].intersect(ray)) {
                    *o = hit.t;
                }
            }
        });
    out
}

/// Our mesh BVH against obvhs's CWBVH (its medium preset: PLOC + reinsertion), on the
/// largest scene; both trace the same world-space triangles (illume through its one
/// identity instance) on 2 threads.
fn obvhs_vs_own(c: &mut Criterion) {
    let pool = pool();
    let Some((name, scene)) = scenes()
        .into_iter()
        .max_by_key(|(_, s)| s.instanced_triangle_count())
    else {
        return;
    };
    let tris = obvhs_triangles(&scene);
    let build_obvhs = || {
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            obvhs::BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        // Triangles in leaf order, as obvhs's examples do, so a leaf reads them in a row.
        let ordered: Vec<_> = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        (bvh, ordered)
    };
    let mut group = c.benchmark_group(format!("obvhs_vs_own/{name}"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("build/obvhs_cwbvh_medium", |b| {
        b.iter(|| pool.install(build_obvhs))
    });
    group.bench_function("build/own", |b| {
        b.iter(|| pool.install(|| Tracer::new(&scene)))
    });
    let (bvh, ordered) = pool.install(build_obvhs);
    let tracer = pool.install(|| Tracer::new(&scene));
    for (kind, rays) in [
        ("incoherent", incoherent_rays(&scene, INCOHERENT_RAYS, 1)),
        ("primary", primary_rays(&scene, PRIMARY_RAYS)),
    ] {
        // Both must find the same hits before their speeds mean anything.
        let theirs = pool.install(|| obvhs_closest(&bvh, &ordered, &rays));
        let ours = pool.install(|| tracer.intersect_batch(&rays, MASK_DEFAULT));
        let agree = ours
            .iter()
            .zip(&theirs)
            .filter(|(a, b)| {
                a.map_or(f32::INFINITY, |h| h.t) == **b
                    || a.is_some_and(|h| (h.t - **b).abs() <= 1e-4 * b.abs().max(1e-2))
            })
            .count();
        eprintln!(
            "obvhs_vs_own/{name}/{kind}: {agree} of {} hit distances agree",
            rays.len()
        );
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(BenchmarkId::new("obvhs_cwbvh", kind), |b| {
            b.iter(|| pool.install(|| obvhs_closest(&bvh, &ordered, &rays)))
        });
        group.bench_function(BenchmarkId::new("own", kind), |b| {
            b.iter(|| pool.install(|| tracer.intersect_batch(&rays, MASK_DEFAULT)))
        });
    }
    group.finish();
}

/// Criterion's generated entry points (private, so they need no docs).
mod entry {
    use super::*;
    criterion_group!(benches, tracer_benches, update_bench, obvhs_vs_own);
}
criterion_main!(entry::benches);
