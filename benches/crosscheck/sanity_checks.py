#!/usr/bin/env python3
"""Analytic checks that the Mitsuba set-up in mi_common.py follows DESIGN.md's conventions.

    python3 benches/crosscheck/sanity_checks.py            # all checks, ~1-2 min on 2 cores

Every check goes through the same code path as mitsuba_render.py (a flattened glTF-like
scene -> mi_common.build_scene_dict), with a camera 4 m above a Lambertian plane
(y = 0, albedo rho) looking straight down (glTF camera: local -Z -> world -Y, image up =
world -Z). For each pixel the expected radiance is computed analytically, averaged over
8x8 sub-pixel positions (box filter), and compared with the render:

 1. point light, I = intensity x colour [W/sr], off-centre:
        L = rho/pi * I cos(theta) / r^2       (pure inverse square, no `range`)
    also checks the image orientation (+X right, -Z up in this view) and yfov;
 2. same plane with its winding reversed (front face down): image must be black
    (one-sided diffuse: a back face does not reflect);
 3. spot light tilted 20 deg, inner 25 / outer 35 deg: the summed Mitsuba cone bank
    (sample_direction at 1 m) vs I * clamp((cos t - cos o)/(cos i - cos o), 0, 1)^2,
    its integrated power vs 2 pi I [(1 - cos i) + (cos i - cos o)/3], and the render vs
        L = rho/pi * I(t) cos(theta_i) / r^2;
 4. one-sided emissive quad 1 m above the plane, front face (CCW winding) down:
    render vs Lambert's exact polygon irradiance  L_e/2 sum_i Theta_i (n . g_i);
    the quad's back face, seen by the camera, must be black;
 5. same quad flipped (front face up): plane black, the quad's front face = L_e exactly.
Exit status 1 if any check fails.
"""

import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import mi_common  # noqa: E402

W, H = 160, 120
YFOV = math.radians(40.0)
CAM_H = 4.0
RHO = np.array([0.5, 0.6, 0.7])
FAILS = []
PASSES = []


def check(name, ok, detail):
    print(f"[{'PASS' if ok else 'FAIL'}] {name}: {detail}")
    (PASSES if ok else FAILS).append(name)


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def camera_world():
    m = np.eye(4)
    m[:3, :3] = rot_x(-math.pi / 2)  # local -Z -> world -Y, local +Y -> world -Z
    m[:3, 3] = [0.0, CAM_H, 0.0]
    return m


def plane(L=6.0, flip=False):
    p = np.array([[-L, 0, -L], [-L, 0, L], [L, 0, L], [L, 0, -L]], float)
    idx = np.array([[0, 1, 2], [0, 2, 3]])
    n = np.tile([0.0, 1.0, 0.0], (4, 1))
    if flip:
        idx, n = idx[:, ::-1].copy(), -n
    return {"name": "plane", "positions": p, "normals": n, "indices": idx, "material": 0}


def quad(y=1.0, half=0.25, facing_down=True):
    h = half
    p = np.array([[-h, y, -h], [h, y, -h], [h, y, h], [-h, y, h]], float)  # CCW from below
    idx = np.array([[0, 1, 2], [0, 2, 3]])
    n = np.tile([0.0, -1.0, 0.0], (4, 1))
    if not facing_down:
        idx, n = idx[:, ::-1].copy(), -n
    return {"name": "emitter", "positions": p, "normals": n, "indices": idx, "material": 1}


def mat(name, rgb, emission=(0, 0, 0)):
    return {"name": name, "base_color": np.array(rgb, float), "metallic": 0.0, "roughness": 1.0,
            "emission": np.array(emission, float), "double_sided": False}


def flat_scene(meshes, lights, materials):
    return {"meshes": meshes, "lights": lights, "materials": materials,
            "camera": {"name": "cam", "world": camera_world(), "yfov": YFOV, "aspect": None}}


def pixel_hits(ss=8):
    """World hit points on y=0 of ss x ss sub-pixel camera rays: array (H, W, ss*ss, 3)."""
    t = math.tan(YFOV / 2)
    a = W / H
    o = (np.arange(ss) + 0.5) / ss
    px = (np.arange(W)[:, None] + o[None, :]).ravel()  # W*ss
    py = (np.arange(H)[:, None] + o[None, :]).ravel()
    xs = (2 * px / W - 1) * t * a
    ys = (1 - 2 * py / H) * t
    X, Y = np.meshgrid(xs, ys)  # (H*ss, W*ss)
    dl = np.stack([X, Y, -np.ones_like(X)], -1)
    dw = dl @ camera_world()[:3, :3].T
    tt = CAM_H / -dw[..., 1]
    hit = np.array([0.0, CAM_H, 0.0]) + tt[..., None] * dw
    hit = hit.reshape(H, ss, W, ss, 3).transpose(0, 2, 1, 3, 4).reshape(H, W, ss * ss, 3)
    return hit, dw.reshape(H, ss, W, ss, 3).transpose(0, 2, 1, 3, 4).reshape(H, W, ss * ss, 3)


def render(flat, spp, max_depth=-1, spot_steps=200):
    mi = mi_common.mi_()
    sd, _ = mi_common.build_scene_dict(flat, W, H, max_depth, 5, spot_steps, verbose=False)
    scene = mi.load_dict(sd)
    img, mean, se, secs, _ = mi_common.render_passes(scene, spp, min(spp, 64), seed=7, progress=False)
    return scene, img


def compare(name, img, expected, tol_mean, tol_px, mask=None, block=1):
    """Image-mean relative difference, and relative differences of `block` x `block` pixel
    averages (blocks fully inside `mask`, expected > 5 % of the peak): 99th percentile."""
    if mask is None:
        mask = np.ones(img.shape[:2], bool)
    e, r = expected[mask], img[mask]
    mean_rel = r.mean(0) / e.mean(0) - 1
    hb, wb = img.shape[0] // block, img.shape[1] // block

    def blocks(a):
        return a[:hb * block, :wb * block].reshape(hb, block, wb, block, -1).mean((1, 3))

    mb = blocks(mask[..., None].astype(float))[..., 0] == 1.0
    eb, rb = blocks(expected)[mb], blocks(img)[mb]
    big = eb.max(1) > 0.05 * expected.max()
    px_rel = np.abs(rb[big] - eb[big]) / eb[big]
    what = "pixels" if block == 1 else f"{block}x{block} blocks"
    detail = (f"image mean rel. diff {np.array2string(mean_rel, precision=5)}; {what} >5% of peak: "
              f"median |rel| {np.median(px_rel):.2e}, 99th pct {np.percentile(px_rel, 99):.2e}")
    check(name, np.all(np.abs(mean_rel) < tol_mean) and np.percentile(px_rel, 99) < tol_px, detail)


def main():
    mi = mi_common.setup(os.environ.get("MI_VARIANT", "auto"))
    print(f"mitsuba {mi.__version__} variant {mi.variant()}, {W}x{H}")
    t0 = time.time()
    hits, _ = pixel_hits()
    mats = [mat("plane", RHO), mat("emitter", [0, 0, 0], [2.0, 3.0, 4.0])]

    # 1. point light
    lp = np.array([0.3, 1.0, -0.2])
    I = 5.0 * np.array([1.0, 0.8, 0.6])
    light = {"name": "pt", "type": "point", "position": lp, "direction": np.array([0, 0, -1.0]),
             "intensity": 5.0, "color": np.array([1.0, 0.8, 0.6]), "range": None}
    _, img = render(flat_scene([plane()], [light], mats[:1]), 64)
    dv = lp[None, None, None, :] - hits
    r2 = (dv ** 2).sum(-1)
    cos = dv[..., 1] / np.sqrt(r2)
    exp = (RHO / math.pi)[None, None, :] * I[None, None, :] * (cos / r2).mean(-1)[..., None]
    compare("point light: L = rho/pi I cos/r^2", img, exp, 2e-3, 5e-3)
    iy, ix = np.unravel_index(np.argmax(img[..., 0]), img.shape[:2])
    eyx = np.unravel_index(np.argmax(exp[..., 0]), exp.shape[:2])
    check("orientation (brightest pixel at the light's foot, +X right / -Z up)",
          abs(iy - eyx[0]) <= 1 and abs(ix - eyx[1]) <= 1 and ix > W / 2 and iy < H / 2,
          f"rendered ({ix},{iy}) expected ({eyx[1]},{eyx[0]})")

    # 2. back face of a one-sided diffuse surface
    _, img = render(flat_scene([plane(flip=True)], [light], mats[:1]), 4)
    check("one-sided diffuse: back face lit by a point light is black", float(np.abs(img).max()) == 0.0,
          f"max pixel {np.abs(img).max():.3g}")

    # 3. spot light, tilted
    tilt = math.radians(20.0)
    sdir = rot_x(0) @ np.array([math.sin(tilt), -math.cos(tilt), 0.0])
    spot = {"name": "spot", "type": "spot", "position": np.array([0.0, 1.0, 0.0]), "direction": sdir,
            "intensity": 10.0, "color": np.array([1.0, 0.9, 0.8]), "range": None,
            "inner": math.radians(25.0), "outer": math.radians(35.0)}
    for steps in (200, 400):
        scene, img = render(flat_scene([plane()], [spot], mats[:1]), 1024, spot_steps=steps)
        th, meas, expp, power = mi_common.measure_spot_profile(scene, spot)
        prof_err = np.abs(meas - expp).max() / (spot["intensity"] * spot["color"].max())
        pa = mi_common.spot_power_analytic(spot["intensity"], spot["inner"], spot["outer"]) * spot["color"]
        check(f"spot bank ({steps} steps) profile vs glTF falloff",
              prof_err < 2.5 / steps, f"max |bank - profile| / I = {prof_err:.2e} (staircase bound ~2/steps)")
        check(f"spot bank ({steps} steps) power",
              np.all(np.abs(power / pa - 1) < 5e-4),
              f"integrated from Mitsuba's emitters {np.array2string(power, precision=6)} W vs analytic "
              f"{np.array2string(pa, precision=6)} W (rel {np.array2string(power / pa - 1, precision=2)})")
        dv = spot["position"][None, None, None, :] - hits
        r = np.sqrt((dv ** 2).sum(-1))
        cos_i = dv[..., 1] / r
        cos_t = (-dv / r[..., None]) @ sdir
        prof = mi_common.spot_profile(cos_t, math.cos(spot["inner"]), math.cos(spot["outer"]))
        exp = (RHO / math.pi * spot["intensity"] * spot["color"])[None, None, :] * \
            (prof * cos_i / r ** 2).mean(-1)[..., None]
        compare(f"spot light render ({steps} steps, 1024 spp): L = rho/pi I(t) cos/r^2", img, exp, 1e-3, 0.06,
                block=8)
        if steps == 200:
            ring = []
            tpix = np.degrees(np.arccos(np.clip((-dv / r[..., None]) @ sdir, -1, 1))).mean(-1)
            for lo in range(0, 36, 5):
                m = (tpix >= lo) & (tpix < lo + 5)
                if m.any():
                    ring.append(f"{lo}-{lo + 5}deg {img[m].mean(0)[0] / exp[m].mean(0)[0] - 1:+.4f} "
                                f"(share {exp[m][:, 0].sum() / exp[..., 0].sum():.4f})")
            print("      per-ring (angle from spot axis) rel. diff, red, and the ring's share of the image sum: "
                  + ", ".join(ring))

    # 4. one-sided emissive quad facing down
    le = mats[1]["emission"]
    q = quad(facing_down=True)
    _, img = render(flat_scene([plane(), q], [], mats), 1024, max_depth=2)
    poly = q["positions"]
    E = np.zeros(hits.shape[:3])
    for i in range(4):
        a = poly[i][None, None, None, :] - hits
        b = poly[(i + 1) % 4][None, None, None, :] - hits
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        b /= np.linalg.norm(b, axis=-1, keepdims=True)
        g = np.cross(a, b)
        ang = np.arccos(np.clip((a * b).sum(-1), -1, 1))
        E += ang * g[..., 1] / np.linalg.norm(g, axis=-1)
    E = np.abs(E) / 2.0  # irradiance per unit radiance (Lambert's polygon formula)
    exp = (RHO / math.pi)[None, None, :] * le[None, None, :] * E.mean(-1)[..., None]
    # pixels whose camera rays pass through the quad (seen from behind) are masked out
    _, dws = pixel_hits()
    tq = (1.0 - CAM_H) / dws[..., 1]
    pq = np.array([0.0, CAM_H, 0.0]) + tq[..., None] * dws
    inq = (np.abs(pq[..., 0]) <= 0.25) & (np.abs(pq[..., 2]) <= 0.25)
    cover_any, cover_all = inq.any(-1), inq.all(-1)
    compare("area light (one-sided quad, front down): Lambert polygon formula", img, exp, 2e-3, 5e-3,
            mask=~cover_any, block=8)
    check("area light: back face of the emitter (seen from above) is black",
          float(np.abs(img[cover_all]).max()) == 0.0, f"max over {cover_all.sum()} pixels "
          f"{np.abs(img[cover_all]).max():.3g}")

    # 5. flipped quad
    _, img = render(flat_scene([plane(), quad(facing_down=False)], [], mats), 16, max_depth=2)
    check("flipped emitter (front face up): plane receives nothing",
          float(np.abs(img[~cover_any]).max()) == 0.0, f"max {np.abs(img[~cover_any]).max():.3g}")
    seen = img[cover_all]
    check("flipped emitter: its front face seen by the camera has radiance = emissive x strength",
          np.allclose(seen, le[None, :], rtol=1e-5), f"mean {np.array2string(seen.mean(0), precision=6)} vs "
          f"{le}")

    print(f"total {time.time() - t0:.0f} s")
    print(f"{len(PASSES)} passed, {len(FAILS)} failed")
    sys.exit(1 if FAILS else 0)


if __name__ == "__main__":
    main()
