#!/usr/bin/env python3
"""Compare the per-channel means of two linear EXR images (e.g. illume vs Mitsuba).

    python3 benches/crosscheck/compare_means.py A.exr B.exr [--tol 0.01] [--json B.json]

Prints each image's per-channel (R, G, B) mean and the relative difference (A - B) / B.
Exit status 0 if every |rel. diff| <= --tol (default 1 %, DESIGN.md's requirement), 1 if
not, 2 on unreadable/mismatched input. With --json (the report mitsuba_render.py wrote for
B) the difference is also expressed in units of B's standard error.

Reads EXR with Mitsuba's mi.Bitmap (scalar_rgb variant, no LLVM needed); falls back to the
`OpenEXR` or `imageio` Python packages when Mitsuba is not installed.
"""

import argparse
import json
import math
import sys

import numpy as np


def read_exr(path):
    try:
        import mitsuba as mi

        mi.set_variant("scalar_rgb")
        bmp = mi.Bitmap(path)
        names = None
        try:
            names = [bmp.struct_()[i].name for i in range(bmp.channel_count())]
        except Exception:
            pass
        arr = np.array(bmp, dtype=np.float64)
        if arr.ndim == 2:
            arr = arr[..., None]
        return arr, names
    except ImportError:
        pass
    try:
        import OpenEXR
        import Imath

        f = OpenEXR.InputFile(path)
        dw = f.header()["dataWindow"]
        w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
        chans = [c for c in ("R", "G", "B") if c in f.header()["channels"]]
        pt = Imath.PixelType(Imath.PixelType.FLOAT)
        arr = np.stack([np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in chans], -1)
        return arr.astype(np.float64), chans
    except ImportError:
        pass
    import imageio.v3 as iio  # needs an EXR plugin (freeimage or opencv)

    arr = np.asarray(iio.imread(path), dtype=np.float64)
    if arr.ndim == 2:
        arr = arr[..., None]
    return arr, None


def rgb(arr, names):
    if names:
        up = [n.upper() for n in names]
        if all(c in up for c in ("R", "G", "B")):
            return arr[..., [up.index("R"), up.index("G"), up.index("B")]]
    if arr.shape[-1] >= 3:
        return arr[..., :3]
    return np.repeat(arr[..., :1], 3, axis=-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a", help="image under test (e.g. illume's EXR)")
    ap.add_argument("b", help="reference image (e.g. out/cornell_spot_mitsuba.exr)")
    ap.add_argument("--tol", type=float, default=0.01, help="max |relative difference| per channel")
    ap.add_argument("--json", help="mitsuba_render.py report of B, for its standard error")
    ap.add_argument("--kind", default="full", help="which image of the JSON report B is (full/direct/indirect)")
    args = ap.parse_args()

    try:
        a, an = read_exr(args.a)
        b, bn = read_exr(args.b)
    except Exception as e:  # noqa: BLE001
        print(f"error reading images: {e}")
        sys.exit(2)
    a, b = rgb(a, an), rgb(b, bn)
    if a.shape != b.shape:
        print(f"warning: sizes differ {a.shape[:2]} vs {b.shape[:2]}; comparing means anyway")
    for name, img in (("A", a), ("B", b)):
        bad = ~np.isfinite(img)
        if bad.any():
            print(f"error: {name} has {bad.sum()} non-finite values")
            sys.exit(2)
    ma = a.reshape(-1, 3).mean(0)
    mb = b.reshape(-1, 3).mean(0)
    rel = (ma - mb) / np.where(mb != 0, mb, np.nan)
    se = None
    if args.json:
        with open(args.json) as f:
            se = np.array(json.load(f)["images"][args.kind]["stderr_rgb"])
    print(f"A: {args.a}  ({a.shape[1]}x{a.shape[0]})")
    print(f"B: {args.b}  ({b.shape[1]}x{b.shape[0]})")
    print(f"{'channel':8s} {'mean A':>12s} {'mean B':>12s} {'rel (A-B)/B':>12s}" + ("  (A-B)/se(B)" if se is not None else ""))
    ok = True
    for i, c in enumerate("RGB"):
        line = f"{c:8s} {ma[i]:12.6f} {mb[i]:12.6f} {rel[i]:+12.4%}"
        if se is not None:
            line += f"  {(ma[i] - mb[i]) / se[i]:+10.1f}"
        if not (math.isfinite(rel[i]) and abs(rel[i]) <= args.tol):
            ok = False
            line += "   <-- exceeds tolerance"
        print(line)
    lum_a, lum_b = ma.mean(), mb.mean()
    print(f"{'avg':8s} {lum_a:12.6f} {lum_b:12.6f} {(lum_a - lum_b) / lum_b:+12.4%}")
    print(f"{'OK' if ok else 'MISMATCH'}: tolerance {args.tol:.2%} per channel")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
