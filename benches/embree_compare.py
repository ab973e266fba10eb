#!/usr/bin/env python3
"""Embree 4 yardstick for illume's tracer (crates/illume-accel).

For each scene and ray kind, runs illume's `dump_rays` example, which writes the scene's
world-space triangle soup and the exact ray set to files and times illume's closest-hit
`intersect_batch` on them; then times Embree (through the `embreex` Python binding) on
the same triangles and rays, checks that both find the same hit distances, and prints
rays/s and the illume/Embree ratio.

Embree is a yardstick only; the project does not need it:  pip install embreex numpy

embreex's `run` traces one ray at a time (rtcIntersect1) in a loop that holds the GIL, so
Embree's two-thread figure comes from two processes, each with its own copy of the scene,
each tracing half of the rays at the same time (the time of a repeat is the slower half).

Usage (from the repository root):
  python3 benches/embree_compare.py [--rays N] [--threads T] [--scenes S ...] [--kinds K ...]
                                    [--illume-exe PATH]

--illume-exe runs a given build of the `dump_rays` example instead of `cargo run` (to
measure an older illume against the same Embree, e.g. before and after a change).
"""

import argparse
import json
import multiprocessing as mp
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(os.path.abspath(__file__)).parent.parent
SHARED = ROOT.parent / "shared" / "scenes"
DEFAULT_SCENES = [
    "builtin:cornell-spot",
    str(SHARED / "cornell_box" / "CornellBox-Sphere.obj"),
    str(SHARED / "dabrovic_sponza" / "sponza.obj"),
]
REPEATS = 7


def load(out_dir):
    tris = np.fromfile(out_dir / "triangles.f32", dtype="<f4").reshape(-1, 3, 3)
    rays = np.fromfile(out_dir / "rays.f32", dtype="<f4").reshape(-1, 6)
    origins = np.ascontiguousarray(rays[:, :3])
    dirs = np.ascontiguousarray(rays[:, 3:])
    return tris, origins, dirs


def embree_scene(tris):
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, tris)
    start = time.perf_counter()
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32), query="DISTANCE")  # commits (builds)
    return scene, (time.perf_counter() - start) * 1e3


def embree_worker(out_dir, part, parts, barrier, results):
    tris, origins, dirs = load(Path(out_dir))
    lo = len(origins) * part // parts
    hi = len(origins) * (part + 1) // parts
    o, d = origins[lo:hi], dirs[lo:hi]
    scene, _ = embree_scene(tris)
    scene.run(o[:1000], d[:1000], query="INTERSECT", output=1)  # warm up
    times = []
    for _ in range(REPEATS):
        barrier.wait()
        start = time.perf_counter()
        scene.run(o, d, query="INTERSECT", output=1)
        times.append(time.perf_counter() - start)
    results.put((part, times))


def time_embree(out_dir, threads):
    tris, origins, dirs = load(out_dir)
    n = len(origins)
    scene, build_ms = embree_scene(tris)
    scene.run(origins[:1000], dirs[:1000], query="INTERSECT", output=1)
    single = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        hits = scene.run(origins, dirs, query="INTERSECT", output=1)
        single.append(time.perf_counter() - start)
    t_embree = np.where(hits["geomID"] >= 0, hits["tfar"], np.inf).astype(np.float32)
    # CPU time of this (single-threaded) process: insensitive to other processes
    # time-slicing the machine; the illume side measures its thread's CPU time alike.
    cpu = []
    for _ in range(REPEATS):
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        scene.run(origins, dirs, query="INTERSECT", output=1)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append((r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime))
    multi = None
    if threads > 1:
        ctx = mp.get_context("fork")
        barrier = ctx.Barrier(threads)
        results = ctx.Queue()
        procs = [ctx.Process(target=embree_worker, args=(str(out_dir), p, threads, barrier, results)) for p in range(threads)]
        for p in procs:
            p.start()
        per_part = dict(results.get() for _ in procs)
        for p in procs:
            p.join()
        multi = float(np.median([max(per_part[p][k] for p in per_part) for k in range(REPEATS)]))
    return {
        "build_ms": build_ms,
        "rays_per_s_1": n / float(np.median(single)),
        "rays_per_s_n": n / multi if multi else None,
        "cpu_rays_per_s_1": n / float(np.median(cpu)),
        "t": t_embree,
    }


def run_illume(scene, kind, rays, threads, out_dir, exe=None):
    env = dict(os.environ)
    prefix = [exe] if exe else ["cargo", "run", "--release", "-q", "-p", "illume-accel", "--example", "dump_rays", "--"]
    cmd = prefix + [scene, kind, str(rays), str(threads), str(out_dir)]
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    line = [l for l in proc.stdout.splitlines() if l.startswith("ILLUME ")][-1]
    return json.loads(line[len("ILLUME "):])


def agreement(t_illume, t_embree):
    both_miss = np.isinf(t_illume) & np.isinf(t_embree)
    with np.errstate(invalid="ignore"):
        close = np.abs(t_illume - t_embree) <= 1e-4 * np.maximum(np.abs(t_embree), 1e-2)
    return float(np.mean(both_miss | close))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--scenes", nargs="*", default=DEFAULT_SCENES)
    ap.add_argument("--kinds", nargs="*", default=["incoherent", "primary"])
    ap.add_argument("--rounds", type=int, default=3, help="alternating illume/Embree rounds (medians are reported)")
    ap.add_argument("--illume-exe", default=None, help="a built dump_rays example to run instead of `cargo run`")
    args = ap.parse_args()
    try:
        import embreex  # noqa: F401
    except ImportError:
        sys.exit("embreex is not installed: pip install embreex numpy")
    rows = []
    for scene in args.scenes:
        if not scene.startswith("builtin:") and not Path(scene).exists():
            print(f"skipping {scene}: not found")
            continue
        for kind in args.kinds:
            # Alternate the two sides over several rounds so that load from other
            # processes on the machine hits both alike; report medians.
            rounds = []
            for _ in range(args.rounds):
                with tempfile.TemporaryDirectory(prefix="illume-embree-") as tmp:
                    out = Path(tmp)
                    ill = run_illume(scene, kind, args.rays, args.threads, out, args.illume_exe)
                    emb = time_embree(out, args.threads)
                    t_illume = np.fromfile(out / "illume_t.f32", dtype="<f4")
                    agree = agreement(t_illume, emb["t"])
                rounds.append((ill, emb, agree))
            med = lambda xs: float(np.median(xs))
            ill = rounds[0][0]
            ill_rps = med([r[0]["rays_per_s"] for r in rounds])
            emb_1 = med([r[1]["rays_per_s_1"] for r in rounds])
            emb_n = med([r[1]["rays_per_s_n"] or r[1]["rays_per_s_1"] for r in rounds])
            name = Path(scene).name if not scene.startswith("builtin:") else scene
            row = {
                "scene": name, "kind": kind, "rays": ill["rays"], "triangles": ill["triangles"],
                "illume_build_ms": med([r[0]["build_ms"] for r in rounds]),
                "illume_memory_bytes": ill["memory_bytes"],
                "illume_kernel": ill.get("kernel", "portable"),
                "embree_build_ms": round(med([r[1]["build_ms"] for r in rounds]), 2),
                "illume_rays_per_s": round(ill_rps),
                "embree_rays_per_s_1thread": round(emb_1),
                f"embree_rays_per_s_{args.threads}proc": round(emb_n),
                "ratio_illume_over_embree": round(med([r[0]["rays_per_s"] / (r[1]["rays_per_s_n"] or r[1]["rays_per_s_1"]) for r in rounds]), 3),
                "illume_cpu_rays_per_s_1thread": round(med([r[0]["cpu_rays_per_s_1thread"] for r in rounds])),
                "embree_cpu_rays_per_s_1thread": round(med([r[1]["cpu_rays_per_s_1"] for r in rounds])),
                "cpu_ratio_illume_over_embree": round(med([r[0]["cpu_rays_per_s_1thread"] / r[1]["cpu_rays_per_s_1"] for r in rounds]), 3),
                "same_t_fraction": round(min(r[2] for r in rounds), 5),
            }
            rows.append(row)
            print(json.dumps(row), flush=True)
    print()
    print(f"{'':48} {'wall clock, ' + str(args.threads) + ' threads':^38}   {'CPU time, 1 thread':^38}")
    print(f"{'scene':28} {'kind':11} {'tris':>7} {'illume Mrays/s':>15} {'Embree Mrays/s':>15} {'ratio':>6}"
          f" {'illume Mrays/s':>15} {'Embree Mrays/s':>15} {'ratio':>6} {'same t':>7}")
    for r in rows:
        emb_n = r[f"embree_rays_per_s_{args.threads}proc"]
        print(f"{r['scene']:28} {r['kind']:11} {r['triangles']:>7} {r['illume_rays_per_s'] / 1e6:>15.2f} "
              f"{emb_n / 1e6:>15.2f} {r['ratio_illume_over_embree']:>6.2f} "
              f"{r['illume_cpu_rays_per_s_1thread'] / 1e6:>15.2f} {r['embree_cpu_rays_per_s_1thread'] / 1e6:>15.2f} "
              f"{r['cpu_ratio_illume_over_embree']:>6.2f} {r['same_t_fraction']:>7.4f}")
    print(f"(illume: {args.threads} rayon threads; Embree: {args.threads} processes, rtcIntersect1 per ray; "
          f"medians of {args.rounds} alternating rounds, each the median of {REPEATS} runs; ratio = median of per-round ratios)")


if __name__ == "__main__":
    main()
