#!/usr/bin/env python3
"""Mitsuba-free check of the glTF -> scene conversion: direct light from the punctual
lights of a glTF scene, computed with a brute-force numpy ray caster.

    python3 benches/crosscheck/direct_check.py cornell_spot [--ss 3] [--json out/cornell_spot_mitsuba.json]

For each pixel, ss x ss stratified sub-pixel camera rays (box filter) are cast from the
glTF camera (local -Z forward, +Y up, +X right, yfov vertical, aspect = width/height);
at the first hit (one-sided: a back face gives 0) the direct radiance
    L = rho/pi * sum_lights I * colour * falloff(theta) * max(0, cos_i) / r^2 * V
is evaluated with a shadow ray (V), with the glTF spot falloff of DESIGN.md. The cosine and
the side test use the interpolated vertex normal, as Mitsuba does. No emitters are seen, so
this equals Mitsuba's max_depth = 2 image for scenes lit by point/spot lights only. It
validates the parts sanity_checks.py does not: the glTF camera node, light node
orientation (quaternions, local -Z), and the mesh node transforms, independently of
Mitsuba. Prints the per-channel means and, with --json, the relative difference to
mitsuba_render.py's direct-only means.
"""

import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

from gltf_scene import Gltf  # noqa: E402
from mitsuba_render import resolve_scene  # noqa: E402  (no mitsuba import at module level)


def spot_profile(cos_t, ci, co):
    u = np.clip((cos_t - co) / (ci - co), 0.0, 1.0)
    return u * u


class Caster:
    def __init__(self, flat):
        p0, e1, e2, n0, n1, n2, rho = [], [], [], [], [], [], []
        for m in flat["meshes"]:
            mat = flat["materials"][m["material"]]
            if np.any(mat["emission"] > 0):
                raise SystemExit("scene has emissive surfaces: direct_check handles punctual lights only")
            P, I = m["positions"], m["indices"]
            N = m["normals"]
            fn = np.cross(P[I[:, 1]] - P[I[:, 0]], P[I[:, 2]] - P[I[:, 0]])
            fn /= np.linalg.norm(fn, axis=1, keepdims=True)
            p0.append(P[I[:, 0]])
            e1.append(P[I[:, 1]] - P[I[:, 0]])
            e2.append(P[I[:, 2]] - P[I[:, 0]])
            for k, dst in enumerate((n0, n1, n2)):
                dst.append(N[I[:, k]] if N is not None else fn)
            rho.append(np.tile(mat["base_color"], (len(I), 1)))
        cat = lambda xs: np.concatenate(xs).astype(np.float64)  # noqa: E731
        self.p0, self.e1, self.e2 = cat(p0), cat(e1), cat(e2)
        self.n0, self.n1, self.n2 = cat(n0), cat(n1), cat(n2)
        self.rho = cat(rho)

    def intersect(self, o, d, tmax=None, chunk=1024):
        """Closest hit (Moller-Trumbore, both sides). Returns t (inf if none), tri, u, v."""
        n = len(o)
        t_best = np.full(n, np.inf) if tmax is None else tmax.copy()
        tri = np.full(n, -1)
        ub = np.zeros(n)
        vb = np.zeros(n)
        e1, e2, p0 = self.e1, self.e2, self.p0
        for s in range(0, n, chunk):
            oo, dd = o[s:s + chunk, None, :], d[s:s + chunk, None, :]
            pv = np.cross(dd, e2[None])
            det = (e1[None] * pv).sum(-1)
            inv = 1.0 / np.where(np.abs(det) < 1e-14, np.nan, det)
            tv = oo - p0[None]
            u = (tv * pv).sum(-1) * inv
            qv = np.cross(tv, e1[None])
            v = (dd * qv).sum(-1) * inv
            t = (e2[None] * qv).sum(-1) * inv
            ok = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6)
            t = np.where(ok, t, np.inf)
            k = np.argmin(t, axis=1)
            tk = t[np.arange(len(k)), k]
            better = tk < t_best[s:s + chunk]
            idx = np.arange(s, min(s + chunk, n))[better]
            t_best[idx] = tk[better]
            tri[idx] = k[better]
            ub[idx] = u[np.arange(len(k)), k][better]
            vb[idx] = v[np.arange(len(k)), k][better]
        return t_best, tri, ub, vb


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene")
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--ss", type=int, default=3, help="ss x ss stratified sub-pixel rays per pixel")
    ap.add_argument("--json", help="mitsuba_render.py report to compare with (its 'direct' image)")
    args = ap.parse_args()

    path = resolve_scene(args.scene)
    flat = Gltf(path).flatten()
    cas = Caster(flat)
    cam = flat["camera"]
    W, H, ss = args.width, args.height, args.ss
    tan = math.tan(cam["yfov"] / 2)
    R = cam["world"][:3, :3]
    org = cam["world"][:3, 3]
    acc = np.zeros((H * W, 3))
    t0 = time.time()
    py, px = np.mgrid[0:H, 0:W]
    px, py = px.ravel().astype(float), py.ravel().astype(float)
    for sy in range(ss):
        for sx in range(ss):
            x = (2 * (px + (sx + 0.5) / ss) / W - 1) * tan * W / H
            y = (1 - 2 * (py + (sy + 0.5) / ss) / H) * tan
            d = np.stack([x, y, -np.ones_like(x)], -1) @ R.T
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            o = np.tile(org, (len(d), 1))
            t, tri, u, v = cas.intersect(o, d)
            hit = tri >= 0
            k = tri[hit]
            p = o[hit] + t[hit, None] * d[hit]
            w0 = 1 - u[hit] - v[hit]
            ns = w0[:, None] * cas.n0[k] + u[hit, None] * cas.n1[k] + v[hit, None] * cas.n2[k]
            ns /= np.linalg.norm(ns, axis=1, keepdims=True)
            front = (ns * -d[hit]).sum(1) > 0
            L = np.zeros((len(k), 3))
            for light in flat["lights"]:
                lv = light["position"][None] - p
                dist = np.linalg.norm(lv, axis=1)
                wl = lv / dist[:, None]
                cos_i = np.maximum((ns * wl).sum(1), 0.0)
                if light["type"] == "spot":
                    fall = spot_profile((-wl) @ light["direction"], math.cos(light["inner"]), math.cos(light["outer"]))
                elif light["type"] == "point":
                    fall = np.ones(len(k))
                else:
                    raise SystemExit(f"light type {light['type']} not handled here")
                need = front & (cos_i > 0) & (fall > 0)
                vis = np.zeros(len(k), bool)
                if need.any():
                    _, blk, _, _ = cas.intersect(p[need] + 1e-5 * wl[need], wl[need], tmax=dist[need] * (1 - 1e-5))
                    vis[np.flatnonzero(need)] = blk < 0  # nothing between the point and the light
                e = light["intensity"] * fall * cos_i / dist ** 2 * vis
                L += (cas.rho[k] / math.pi) * e[:, None] * light["color"][None]
            acc[np.flatnonzero(hit)] += L
            print(f"  sub-pixel {sy * ss + sx + 1}/{ss * ss}, {time.time() - t0:.0f} s", flush=True)
    img = acc / (ss * ss)
    mean = img.mean(0)
    print(f"{os.path.basename(path)} direct light (numpy caster, {ss}x{ss} rays/pixel): mean RGB "
          f"({mean[0]:.6f}, {mean[1]:.6f}, {mean[2]:.6f})")
    if args.json:
        with open(args.json) as f:
            ref = json.load(f)["images"]["direct"]
        m = np.array(ref["mean_rgb"])
        print(f"mitsuba direct ({ref['spp']} spp): ({m[0]:.6f}, {m[1]:.6f}, {m[2]:.6f}); "
              f"rel. diff numpy/mitsuba - 1 = ({', '.join(f'{x:+.5f}' for x in mean / m - 1)})")


if __name__ == "__main__":
    main()
