#!/usr/bin/env python3
"""Render an illume glTF test scene with Mitsuba 3's `path` integrator (independent
reference for illume's reference path tracer).

    python3 benches/crosscheck/mitsuba_render.py cornell_spot            # full + direct-only
    python3 benches/crosscheck/mitsuba_render.py cornell_area --spp 4096 --mode full
    python3 benches/crosscheck/mitsuba_render.py path/to/scene.gltf --time 1.0

The glTF is read by gltf_scene.py (json + numpy, no importer), node TRS flattened to world
space, and turned into a Mitsuba scene (mi_common.build_scene_dict). Outputs, in
benches/crosscheck/out/ (or --out):

    <scene>_mitsuba.exr          full global illumination (max_depth -1 = unbounded)
    <scene>_direct_mitsuba.exr   direct only (max_depth 2: emission seen + one bounce)
    <scene>_indirect_mitsuba.exr full - direct (mode both)
    <scene>_mitsuba.json         per-channel means, standard errors, spp, time, settings
    <scene>*_mitsuba.png         sRGB previews

Standard errors come from the scatter of the per-pass image means (passes use distinct
seeds, so they are independent estimates).
"""

import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
REPO = os.path.dirname(os.path.dirname(HERE))
GLTF_DIR = os.path.normpath(os.path.join(REPO, "..", "shared", "scenes", "gltf"))

import numpy as np  # noqa: E402

import mi_common  # noqa: E402
from gltf_scene import Gltf  # noqa: E402


def resolve_scene(arg):
    if os.path.exists(arg):
        return os.path.abspath(arg)
    for cand in (arg, arg + ".gltf"):
        p = os.path.join(GLTF_DIR, cand)
        if os.path.exists(p):
            return p
    raise SystemExit(f"scene {arg!r} not found (looked in {GLTF_DIR})")


def fmt(v):
    return "(" + ", ".join(f"{x:.6f}" for x in v) + ")"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", help="glTF path, or a name in ../shared/scenes/gltf (e.g. cornell_spot)")
    ap.add_argument("--mode", choices=["both", "full", "direct"], default="both")
    ap.add_argument("--spp", type=int, default=2048, help="samples per pixel (default 2048)")
    ap.add_argument("--pass-spp", type=int, default=64, help="spp per independent pass (default 64)")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--max-depth", type=int, default=-1, help="full image path depth (-1 = unbounded)")
    ap.add_argument("--rr-depth", type=int, default=5, help="Russian roulette start depth (Mitsuba default 5)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--spot-steps", type=int, default=200, help="cones in the spot-profile bank")
    ap.add_argument("--time", type=float, default=None, help="evaluate node animations at this time [s]")
    ap.add_argument("--face-normals", action="store_true", help="drop vertex normals (flat shading)")
    ap.add_argument("--variant", default="auto", help="mitsuba variant (auto: llvm_ad_rgb if usable)")
    ap.add_argument("--out", default=os.path.join(HERE, "out"))
    ap.add_argument("--tag", default="", help="suffix for output names (e.g. _seed1)")
    args = ap.parse_args()

    mi = mi_common.setup(args.variant)
    path = resolve_scene(args.scene)
    name = os.path.splitext(os.path.basename(path))[0]
    os.makedirs(args.out, exist_ok=True)
    print(f"mitsuba {mi.__version__}, variant {mi.variant()}, scene {path}")

    flat = Gltf(path).flatten(time=args.time)
    runs = []
    if args.mode in ("both", "full"):
        runs.append(("full", args.max_depth, 0))
    if args.mode in ("both", "direct"):
        runs.append(("direct", 2, 1))

    report = {
        "scene": name,
        "gltf": path,
        "mitsuba": mi.__version__,
        "variant": mi.variant(),
        "width": args.width,
        "height": args.height,
        "time": args.time,
        "face_normals": args.face_normals,
        "seed": args.seed,
        "images": {},
    }
    imgs = {}
    for kind, depth, seed_off in runs:
        sd, info = mi_common.build_scene_dict(
            flat, args.width, args.height, depth, args.rr_depth, args.spot_steps,
            face_normals=args.face_normals, verbose=(kind == runs[0][0]))
        report["lights"] = info["lights"]
        t0 = time.time()
        scene = mi.load_dict(sd)
        t_load = time.time() - t0
        # distinct seed streams for the full and direct renders -> independent estimates
        img, mean, se, secs, spp = mi_common.render_passes(
            scene, args.spp, args.pass_spp, seed=2 * args.seed + seed_off, label=kind)
        suffix = "" if kind == "full" else "_" + kind
        exr = os.path.join(args.out, f"{name}{suffix}_mitsuba{args.tag}.exr")
        mi_common.write_exr(exr, img)
        mi_common.write_png_preview(exr[:-4] + ".png", img)
        imgs[kind] = (img, mean, se)
        report["images"][kind] = {
            "exr": os.path.relpath(exr, REPO),
            "max_depth": depth,
            "rr_depth": args.rr_depth,
            "spp": spp,
            "pass_spp": args.pass_spp,
            "seconds": round(secs, 2),
            "load_seconds": round(t_load, 2),
            "mean_rgb": mean.tolist(),
            "stderr_rgb": se.tolist(),
        }
        rel = se / np.maximum(mean, 1e-30)
        print(f"{name} {kind:8s} max_depth={depth:3d} spp={spp} time={secs:.1f}s  mean RGB {fmt(mean)}  "
              f"std.err {fmt(se)} (rel {fmt(rel)})", flush=True)

    if "full" in imgs and "direct" in imgs:
        (fi, fm, fs), (di, dm, ds) = imgs["full"], imgs["direct"]
        ind = fi - di
        im = fm - dm
        iseb = np.sqrt(fs ** 2 + ds ** 2)
        exr = os.path.join(args.out, f"{name}_indirect_mitsuba{args.tag}.exr")
        mi_common.write_exr(exr, ind)
        mi_common.write_png_preview(exr[:-4] + ".png", np.maximum(ind, 0) * 4.0)
        report["images"]["indirect"] = {
            "exr": os.path.relpath(exr, REPO),
            "definition": "full - direct (independent seeds)",
            "mean_rgb": im.tolist(),
            "stderr_rgb": iseb.tolist(),
            "indirect_fraction_rgb": (im / fm).tolist(),
        }
        print(f"{name} indirect (full-direct)              mean RGB {fmt(im)}  std.err {fmt(iseb)}  "
              f"fraction of full {fmt(im / fm)}")

    js = os.path.join(args.out, f"{name}_mitsuba{args.tag}.json")
    if args.mode != "both":
        js = os.path.join(args.out, f"{name}_{args.mode}_mitsuba{args.tag}.json")
    with open(js, "w") as f:
        json.dump(report, f, indent=2)
    print(json.dumps({k: {kk: v[kk] for kk in ("mean_rgb", "stderr_rgb") if kk in v}
                      for k, v in report["images"].items()}, indent=1))
    print(f"wrote {js}")


if __name__ == "__main__":
    main()
