#!/usr/bin/env python3
"""Error on the edges of a frame, for anti-aliasing (the window's still refinement).

Usage: python3 benches/edge_error.py REFERENCE.exr CENTRE.exr REFINED.exr

CENTRE is a frame sampled at pixel centres, REFINED the same view averaged over jittered
offsets (`cargo run --release -p illume-engine --example still_refinement`), REFERENCE a
converged path-traced image (box-filtered pixels). The edge pixels are those where
refinement changed the luminance by more than 10 % (silhouettes, shadow and spot
edges: chosen from the two frames, not from the reference). Prints, on them and over
the whole image, the mean absolute luminance error relative to the reference's mean.
Needs numpy and OpenEXR (pip install numpy OpenEXR).
"""

import sys

import Imath
import numpy as np
import OpenEXR


def load(path):
    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in "RGB"], -1)


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    ref, centre, refined = (load(p) for p in sys.argv[1:4])
    lum = lambda x: x @ np.array([0.2126, 0.7152, 0.0722])
    change = np.abs(lum(refined) - lum(centre))
    edges = change > 0.1 * np.maximum(lum(refined), 1e-3)
    everywhere = np.ones_like(edges)

    def err(x, m):
        return np.abs(lum(x) - lum(ref))[m].mean() / lum(ref)[m].mean()

    print(
        f"edge pixels {edges.sum()} of {edges.size}; relative mean abs luminance error "
        f"on them: centre {err(centre, edges):.4f}, refined {err(refined, edges):.4f}; "
        f"whole image: centre {err(centre, everywhere):.4f}, refined {err(refined, everywhere):.4f}"
    )


if __name__ == "__main__":
    main()
