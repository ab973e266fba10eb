//! Writes a scene's world-space triangle soup and a ray set to files, then times illume's
//! closest-hit queries on exactly those rays; `benches/embree_compare.py` runs this and
//! times Embree on the same files.
//!
//! ```text
//! cargo run --release -p illume-accel --example dump_rays -- SCENE KIND RAYS THREADS OUT_DIR
//!   SCENE    builtin:NAME or a scene file (OBJ, glTF, PLY)
//!   KIND     incoherent (origins uniform in the scene box, uniform directions) | primary
//!   RAYS     number of rays (primary: a square image of about that many pixels)
//!   THREADS  rayon threads for the timed run
//! ```
//!
//! Files (little-endian f32): `triangles.f32` (9 per triangle), `rays.f32` (origin and
//! direction, 6 per ray), `illume_t.f32` (illume's hit distance per ray, +∞ for a miss).
//! The last line printed is `ILLUME {json}` with the timings and the traversal kernel
//! (`ILLUME_ACCEL_KERNEL=portable|avx2` forces one; `ILLUME_SPLIT_BUDGET=x` sets
//! [`BvhSettings::split_budget`](illume_accel::BvhSettings::split_budget)) and, on Linux,
//! how much of the process's memory the kernel backs with transparent huge pages
//! (`anon_huge_kb`, from `smaps_rollup`; `-1` elsewhere).

use illume_accel::ray_sets::{incoherent_rays, primary_rays};
use illume_accel::{BvhSettings, Tracer};
use illume_scene::{MASK_DEFAULT, Scene};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The allocator of the `illume` binary (apps/illume/src/main.rs), so the timed batch
/// runs as it does in the app: the system allocator returns each run's result vector
/// (24 MB for 10⁶ rays) to the kernel, and the next run pays a page fault per 4 KiB
/// writing it again.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // mimalloc asks for transparent huge pages on its arena (MADV_HUGEPAGE); where the
    // kernel compacts memory on such faults (`defrag = madvise`, this project's machines),
    // a fault can stall for milliseconds, and a timed build then takes 55–82 ms instead of
    // 41–50 (Sponza, BENCHMARKS.md "Issue 16, third pass"). The measurement should not
    // depend on how fragmented the machine's memory is: huge pages off for this process.
    // They do not change the tracing rate measurably (≤ 2 %, docs/benchmarks/tracer.md
    // "Huge pages checked"), only the build's time.
    #[cfg(target_os = "linux")]
    #[allow(unsafe_code)]
    // SAFETY: PR_SET_THP_DISABLE takes integer arguments only and touches no memory of ours.
    unsafe {
        libc::prctl(libc::PR_SET_THP_DISABLE, 1, 0, 0, 0);
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene_arg, kind, rays_arg, threads_arg, out] = args.as_slice() else {
        return Err("usage: dump_rays SCENE incoherent|primary RAYS THREADS OUT_DIR".into());
    };
    let scene = illume_scene::load_scene(Path::new(scene_arg))?;
    let n: usize = rays_arg.parse()?;
    let threads: usize = threads_arg.parse()?;
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out)?;

    let rays = match kind.as_str() {
        "incoherent" => incoherent_rays(&scene, n, 1),
        "primary" => primary_rays(&scene, n),
        other => return Err(format!("unknown ray kind '{other}'").into()),
    };
    write_f32(
        &out.join("triangles.f32"),
        world_triangles(&scene).into_iter().flatten(),
    )?;
    write_f32(
        &out.join("rays.f32"),
        rays.iter().flat_map(|r| {
            [
                r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z,
            ]
        }),
    )?;

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let start = Instant::now();
    let mut settings = BvhSettings::default();
    if let Ok(v) = std::env::var("ILLUME_SPLIT_BUDGET") {
        settings.split_budget = v
            .parse()
            .map_err(|e| format!("ILLUME_SPLIT_BUDGET={v}: {e}"))?;
    }
    let tracer = pool.install(|| Tracer::with_settings(&scene, settings));
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut times = Vec::new();
    let mut hits = Vec::new();
    for _ in 0..7 {
        let start = Instant::now();
        hits = pool.install(|| tracer.intersect_batch(&rays, MASK_DEFAULT));
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    write_f32(
        &out.join("illume_t.f32"),
        hits.iter().map(|h| h.map_or(f32::INFINITY, |h| h.t)),
    )?;
    // CPU time of one thread tracing alone: insensitive to other processes time-slicing
    // the machine (Linux only; -1 elsewhere). Repeats until half a second of CPU time.
    // It runs on a worker of the pool, as the app's tracing does: on the main thread the
    // same binary traced Sponza's primary rays at 16–18 M rays/s in most processes and at
    // 12 in one of four to twelve, by where the environment's size and address
    // randomisation put the main thread's stack (`setarch -R` with a padded environment
    // makes it the same every run); a worker's stack is mapped at a page boundary, the same
    // in every process (docs/benchmarks/tracer.md, "The main thread's stack").
    let one_thread = || match thread_cpu_seconds() {
        Some(start) => {
            let mut traced = 0usize;
            let mut spent = 0.0;
            while spent < 0.5 {
                for r in &rays {
                    std::hint::black_box(tracer.intersect(r, MASK_DEFAULT));
                }
                traced += rays.len();
                spent = thread_cpu_seconds().unwrap_or(f64::INFINITY) - start;
            }
            traced as f64 / spent
        }
        None => -1.0,
    };
    let cpu_rays_per_s = pool.install(one_thread);
    let stats = tracer.stats();
    let hit_count = hits.iter().flatten().count();
    println!(
        "ILLUME {{\"scene\": \"{scene_arg}\", \"kind\": \"{kind}\", \"rays\": {}, \"threads\": {threads}, \"triangles\": {}, \"build_ms\": {build_ms:.2}, \
         \"median_s\": {median:.6}, \"rays_per_s\": {:.0}, \"hits\": {hit_count}, \"nodes\": {}, \"memory_bytes\": {}, \"stored_triangles\": {}, \"cpu_rays_per_s_1thread\": {cpu_rays_per_s:.0}, \"kernel\": \"{}\", \"anon_huge_kb\": {}}}",
        rays.len(),
        scene.instanced_triangle_count(),
        rays.len() as f64 / median,
        stats.mesh_nodes + stats.instance_nodes,
        stats.memory_bytes,
        stats.stored_triangles,
        tracer.kernel().name(),
        anon_huge_kb().unwrap_or(-1)
    );
    Ok(())
}

/// Every instance's triangles in world space, 9 floats each.
fn world_triangles(scene: &Scene) -> Vec<[f32; 9]> {
    let mut out = Vec::with_capacity(scene.instanced_triangle_count());
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh.index()];
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh
                .triangle(t)
                .map(|p| inst.world_from_object.transform_point3(p));
            out.push([a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z]);
        }
    }
    out
}

/// CPU time of the calling thread in seconds, to the nanosecond (`/proc`'s clock ticks
/// of 10 ms made the half-second measurement move in steps of 2 %).
#[cfg(target_os = "linux")]
fn thread_cpu_seconds() -> Option<f64> {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    #[allow(unsafe_code)]
    // SAFETY: `ts` is a valid, writable timespec for the duration of the call.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

#[cfg(not(target_os = "linux"))]
fn thread_cpu_seconds() -> Option<f64> {
    None
}

/// The process's anonymous memory in transparent huge pages [KiB] (Linux).
fn anon_huge_kb() -> Option<i64> {
    let rollup = std::fs::read_to_string("/proc/self/smaps_rollup").ok()?;
    let line = rollup.lines().find(|l| l.starts_with("AnonHugePages:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn write_f32(path: &Path, values: impl Iterator<Item = f32>) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    for v in values {
        w.write_all(&v.to_le_bytes())?;
    }
    w.flush()
}
