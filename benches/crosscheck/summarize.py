#!/usr/bin/env python3
"""Combine mitsuba_render.py reports of independent seeds into one Markdown table.

    python3 benches/crosscheck/summarize.py [out/cornell_spot_mitsuba.json out/cornell_spot_mitsuba_seed1.json ...]

Default: every out/*_mitsuba*.json. Reports of the same scene (and settings) are grouped;
for each image kind it prints each seed's mean, the combined mean (average), the standard
error from the per-pass scatter (combined), and the one from the scatter between seeds
(|m1 - m2| / 2 for two seeds, i.e. the s.e. of their average estimated from two samples).
"""

import glob
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    files = sys.argv[1:] or sorted(glob.glob(os.path.join(HERE, "out", "*_mitsuba*.json")))
    groups = {}
    for f in files:
        with open(f) as fh:
            r = json.load(fh)
        key = (r["scene"], r.get("width"), r.get("height"), r.get("time"), r.get("face_normals"))
        groups.setdefault(key, []).append((f, r))
    print("| scene | image | spp (total) | mean R | mean G | mean B | s.e. R | s.e. G | s.e. B | seeds' spread R,G,B |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for key, reps in groups.items():
        kinds = [k for k in ("full", "direct", "indirect") if all(k in r["images"] for _, r in reps)]
        for k in kinds:
            ms = np.array([r["images"][k]["mean_rgb"] for _, r in reps])
            ses = np.array([r["images"][k]["stderr_rgb"] for _, r in reps])
            spp = sum(r["images"][k].get("spp", r["images"].get("full", {}).get("spp", 0)) for _, r in reps)
            m = ms.mean(0)
            se = np.sqrt((ses ** 2).sum(0)) / len(reps)
            spread = ""
            if len(reps) > 1:
                sb = ms.std(0, ddof=1) / math.sqrt(len(reps))
                spread = ", ".join(f"{x:.6f}" for x in sb)
            print(f"| {key[0]} | {k} | {spp} | {m[0]:.6f} | {m[1]:.6f} | {m[2]:.6f} | "
                  f"{se[0]:.6f} | {se[1]:.6f} | {se[2]:.6f} | {spread} |")
    print()
    print("inputs: " + ", ".join(os.path.relpath(f, HERE) for f in files))


if __name__ == "__main__":
    main()
