"""Shared Mitsuba 3 helpers for the cross-check scripts (variant set-up, spot-light bank,
scene building, pass-wise rendering with standard errors, EXR I/O).

Conventions reproduced (../../../shared/DESIGN.md, "Conventions"):
  * glTF numbers radiometric, factor 1: point/spot intensity x colour = W/sr per channel,
    pure inverse square (`range` ignored); emissiveFactor x emissive_strength = radiance,
    one-sided (front = counter-clockwise winding side);
  * spot falloff clamp((cos t - cos outer)/(cos inner - cos outer), 0, 1)^2;
  * doubleSided false: back faces neither reflect nor emit (Mitsuba's `diffuse` and `area`
    are one-sided; checked by sanity_checks.py);
  * camera looks down its local -Z, +Y up, yfov vertical, box pixel filter, pixels = radiance.
"""

import glob
import math
import os
import time

import numpy as np

_MI = None


def find_libllvm():
    """A libLLVM >= 16 (Dr.Jit's LLVM backend fails on LLVM 15's missing `fminimum`)."""
    cands = []
    for d in ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib", "/usr/local/lib"):
        for p in glob.glob(os.path.join(d, "libLLVM*.so*")):
            base = os.path.basename(p)
            digits = "".join(c if c.isdigit() else " " for c in base).split()
            if digits and int(digits[0]) >= 16:
                cands.append((int(digits[0]), p))
    cands.sort(reverse=True)
    return cands[0][1] if cands else None


def setup(variant="auto"):
    """Import mitsuba and pick a variant. 'auto' = llvm_ad_rgb when a usable libLLVM exists,
    else scalar_rgb. Must run before anything else imports mitsuba."""
    global _MI
    if variant == "auto":
        lib = os.environ.get("DRJIT_LIBLLVM_PATH") or find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
            variant = "llvm_ad_rgb"
        else:
            variant = "scalar_rgb"
    elif variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import mitsuba as mi

    if variant not in mi.variants():
        raise SystemExit(f"variant {variant} not available; have {mi.variants()}")
    mi.set_variant(variant)
    _MI = mi
    return mi


def mi_():
    if _MI is None:
        raise RuntimeError("call mi_common.setup() first")
    return _MI


# --------------------------------------------------------------------------- spot bank
def spot_profile(cos_t, cos_inner, cos_outer):
    """glTF's reference spot falloff (KHR_lights_punctual), per DESIGN.md."""
    u = np.clip((np.asarray(cos_t, float) - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0)
    return u * u


def spot_bank(inner, outer, steps):
    """Decompose the glTF spot profile into `steps`+1 nested step-function cones.

    Cone k covers cos t > mu_k with mu_k = cos_outer + k (cos_inner - cos_outer)/steps,
    k = 0..steps (mu_steps = cos inner). Its weight is the increment of the staircase whose
    value on each bin [mu_k, mu_k+1] is the *average* of the profile over that bin (in cos t,
    i.e. per unit solid angle), so the bank's total power equals the analytic power exactly
    and the point-wise error alternates in sign inside each bin (max ~ 2/steps at the rim).
    Returns list of (cutoff angle [rad], weight); sum of weights = 1.
    """
    ci, co = math.cos(inner), math.cos(outer)
    n = steps
    # average of u^2 over u in [j/n, (j+1)/n]
    avg = [(3 * j * j + 3 * j + 1) / (3.0 * n * n) for j in range(n)]
    cones = []
    prev = 0.0
    for k in range(n + 1):
        level = avg[k] if k < n else 1.0
        mu = co + k * (ci - co) / n
        cones.append((math.acos(min(1.0, mu)), level - prev))
        prev = level
    return cones


def spot_power_analytic(intensity, inner, outer):
    ci, co = math.cos(inner), math.cos(outer)
    return 2 * math.pi * intensity * ((1 - ci) + (ci - co) / 3.0)


def spot_bank_power(intensity, cones, transition):
    """Exact power of the bank as Mitsuba renders it: each cone is 1 inside beam_width,
    linear in angle down to 0 at cutoff_angle (transition width `transition` rad, centred
    on the staircase edge)."""
    total = 0.0
    for th, w in cones:
        b, c = th - transition / 2, th + transition / 2
        # integral of sin t over [0,b] + integral of (c-t)/(c-b) sin t over [b,c]
        lin = ((c - b) * math.cos(b) - (math.sin(c) - math.sin(b))) / (c - b)
        total += w * 2 * math.pi * ((1 - math.cos(b)) + lin)
    return intensity * total


SPOT_TRANSITION = math.radians(1e-3)  # width of Mitsuba's linear falloff of each cone


def spot_emitters(light, steps):
    """Mitsuba `spot` dicts reproducing the glTF spot profile (see spot_bank)."""
    mi = mi_()
    cones = spot_bank(light["inner"], light["outer"], steps)
    pos = light["position"]
    d = light["direction"]
    up = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    to_world = mi.ScalarTransform4f().look_at(origin=pos.tolist(), target=(pos + d).tolist(), up=up.tolist())
    out = {}
    for k, (th, w) in enumerate(cones):
        if w <= 0:
            continue
        rgb = (light["intensity"] * w * light["color"]).tolist()
        out[f"{light['name']}_cone{k:04d}"] = {
            "type": "spot",
            "to_world": to_world,
            "intensity": {"type": "rgb", "value": rgb},
            "cutoff_angle": math.degrees(th + SPOT_TRANSITION / 2),
            "beam_width": math.degrees(th - SPOT_TRANSITION / 2),
            # pick cones in proportion to their weight: the estimator of the summed
            # profile is then I * [inside picked cone], bounded by I
            "sampling_weight": float(w),
        }
    lum = float(np.mean(light["color"]))
    info = {
        "steps": steps,
        "cones": len(out),
        "transition_deg": math.degrees(SPOT_TRANSITION),
        "power_analytic_W_per_unit_colour": spot_power_analytic(light["intensity"], light["inner"], light["outer"]),
        "power_bank_W_per_unit_colour": spot_bank_power(light["intensity"], cones, SPOT_TRANSITION),
        "mean_colour": lum,
    }
    info["power_rel_error"] = info["power_bank_W_per_unit_colour"] / info["power_analytic_W_per_unit_colour"] - 1
    return out, info


def measure_spot_profile(scene, light, n_angles=None):
    """Sum every emitter's sample_direction() contribution at unit distance along angles
    0..outer+2deg from the spot axis; returns (theta, measured[3], expected[3]) plus the
    power integrated from the measured profile."""
    mi = mi_()
    import drjit as dr

    pos = light["position"]
    d = light["direction"]
    a = np.cross(d, [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    if n_angles is None:
        n_angles = 601 if mi.variant().startswith("scalar") else 4001
    th = np.linspace(0.0, light["outer"] + math.radians(2.0), n_angles)
    dirs = np.cos(th)[:, None] * d[None, :] + np.sin(th)[:, None] * a[None, :]
    pts = pos[None, :] + dirs
    total = np.zeros((n_angles, 3))
    ems = scene.emitters()
    if mi.variant().startswith("scalar"):  # one Python call per (emitter, angle)
        for i in range(n_angles):
            it = dr.zeros(mi.Interaction3f)
            it.p = mi.Point3f(*pts[i])
            for em in ems:
                _, spec = em.sample_direction(it, mi.Point2f(0.5, 0.5), True)
                total[i] += np.array([spec[0], spec[1], spec[2]], dtype=np.float64)
    else:
        it = dr.zeros(mi.Interaction3f, n_angles)
        it.p = mi.Point3f(pts[:, 0], pts[:, 1], pts[:, 2])
        sample = mi.Point2f(np.full(n_angles, 0.5), np.full(n_angles, 0.5))
        for em in ems:
            _, spec = em.sample_direction(it, sample, True)
            arr = np.array(spec, dtype=np.float64)
            total += arr.T if arr.shape == (3, n_angles) else arr.reshape(n_angles, 3)
    expected = light["intensity"] * spot_profile(np.cos(th), math.cos(light["inner"]), math.cos(light["outer"]))
    expected = expected[:, None] * light["color"][None, :]
    # power = integral of I(theta) 2 pi sin(theta) dtheta (trapezoid)
    f = 2 * math.pi * np.sin(th)[:, None] * total
    power = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(th)[:, None], axis=0)
    return th, total, expected, power


# --------------------------------------------------------------------------- scene
def make_mesh(name, positions, indices, normals, bsdf, emitter=None):
    mi = mi_()
    props = mi.Properties()
    props["mesh_bsdf"] = bsdf
    if emitter is not None:
        props["mesh_emitter"] = emitter
    mesh = mi.Mesh(
        name,
        vertex_count=len(positions),
        face_count=len(indices),
        props=props,
        has_vertex_normals=normals is not None,
    )
    params = mi.traverse(mesh)
    # the buffers are mi.Float / mi.UInt32 in JIT variants, dr.scalar.ArrayXf/ArrayXu in scalar ones
    fbuf = type(params["vertex_positions"])
    ubuf = type(params["faces"])
    params["vertex_positions"] = fbuf(np.asarray(positions, np.float32).ravel())
    params["faces"] = ubuf(np.asarray(indices, np.uint32).ravel())
    if normals is not None:
        params["vertex_normals"] = fbuf(np.asarray(normals, np.float32).ravel())
    params.update()
    return mesh


def bsdf_for(mat):
    mi = mi_()
    if mat["metallic"] != 0.0:
        print(f"warning: material {mat['name']} metallic={mat['metallic']} rendered as Lambertian")
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": mat["base_color"].tolist()}}
    if mat["double_sided"]:
        bsdf = {"type": "twosided", "material": bsdf}
    return mi.load_dict(bsdf)


def build_scene_dict(flat, width=320, height=240, max_depth=-1, rr_depth=5, spot_steps=200,
                     face_normals=False, flip_emitters=False, verbose=True):
    """Mitsuba scene dict from a flattened glTF (gltf_scene.Gltf.flatten()).
    Returns (dict, info)."""
    mi = mi_()
    info = {"lights": []}
    d = {"type": "scene"}
    d["integrator"] = {"type": "path", "max_depth": int(max_depth), "rr_depth": int(rr_depth)}
    cam = flat["camera"]
    if cam is None:
        raise SystemExit("scene has no camera")
    # glTF camera: looks down local -Z, +Y up, +X right. Mitsuba: looks down +Z, +Y up,
    # +X left. Same frame up to a 180 deg rotation about Y.
    w = cam["world"] @ np.diag([-1.0, 1.0, -1.0, 1.0])
    lin = w[:3, :3]
    if not np.allclose(lin.T @ lin, np.eye(3), atol=1e-5):
        raise SystemExit("camera node has scale/shear; not supported")
    d["sensor"] = {
        "type": "perspective",
        "to_world": mi.ScalarTransform4f(w.tolist()),
        "fov_axis": "y",
        "fov": math.degrees(cam["yfov"]),
        "near_clip": 1e-3,
        "far_clip": 1e4,
        "film": {
            "type": "hdrfilm",
            "width": int(width),
            "height": int(height),
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
            "component_format": "float32",
        },
        "sampler": {"type": "independent"},
    }
    from gltf_scene import winding_normal_agreement

    for k, m in enumerate(flat["meshes"]):
        mat = flat["materials"][m["material"]] if m["material"] is not None else {
            "name": "default", "base_color": np.ones(3), "metallic": 0.0, "emission": np.zeros(3),
            "double_sided": False}
        bad = winding_normal_agreement(m)
        if bad:
            print(f"warning: {m['name']}: {bad} triangles whose vertex normals oppose the CCW winding")
        emitter = None
        if np.any(mat["emission"] > 0):
            emitter = mi.load_dict({"type": "area", "radiance": {"type": "rgb", "value": mat["emission"].tolist()}})
            if mat["double_sided"]:
                print(f"warning: {m['name']}: double-sided emitter rendered one-sided (front only)")
            info["lights"].append({"type": "area", "mesh": m["name"], "radiance": mat["emission"].tolist()})
        idx = m["indices"][:, ::-1] if (flip_emitters and emitter is not None) else m["indices"]
        nrm = None if (face_normals or m["normals"] is None) else m["normals"]
        if nrm is not None and flip_emitters and emitter is not None:
            nrm = -nrm
        d[f"mesh{k:03d}_{m['name']}"] = make_mesh(m["name"], m["positions"], idx, nrm, bsdf_for(mat), emitter)

    for light in flat["lights"]:
        if light.get("range") is not None:
            print(f"warning: light {light['name']}: range ignored (pure inverse square)")
        if light["type"] == "point":
            d[light["name"]] = {
                "type": "point",
                "position": light["position"].tolist(),
                "intensity": {"type": "rgb", "value": (light["intensity"] * light["color"]).tolist()},
            }
            info["lights"].append({"type": "point", "intensity": (light["intensity"] * light["color"]).tolist()})
        elif light["type"] == "spot":
            ems, binfo = spot_emitters(light, spot_steps)
            d.update(ems)
            binfo["type"] = "spot"
            info["lights"].append(binfo)
            if verbose:
                pa = binfo["power_analytic_W_per_unit_colour"]
                pb = binfo["power_bank_W_per_unit_colour"]
                print(f"spot '{light['name']}': bank of {binfo['cones']} cones; power per unit colour "
                      f"bank {pb:.6f} W vs analytic 2*pi*I*[(1-cos inner)+(cos inner-cos outer)/3] = {pa:.6f} W "
                      f"(rel. error {binfo['power_rel_error']:+.2e})")
        elif light["type"] == "directional":
            d[light["name"]] = {
                "type": "directional",
                "direction": light["direction"].tolist(),
                "irradiance": {"type": "rgb", "value": (light["intensity"] * light["color"]).tolist()},
            }
            info["lights"].append({"type": "directional"})
        else:
            raise SystemExit(f"unsupported light type {light['type']}")
    return d, info


# --------------------------------------------------------------------------- render
def render_passes(scene, spp, pass_spp, seed, label="", progress=True):
    """Render spp samples as independent passes of pass_spp (distinct seeds); return
    (image float64 HxWx3, per-channel mean, per-channel standard error from the scatter of
    the pass means, seconds)."""
    mi = mi_()
    npass = max(1, int(math.ceil(spp / pass_spp)))
    acc = None
    means = []
    t0 = time.time()
    for p in range(npass):
        img = np.array(mi.render(scene, spp=pass_spp, seed=seed * 1_000_003 + p), dtype=np.float64)
        acc = img if acc is None else acc + img
        means.append(img.reshape(-1, img.shape[-1])[:, :3].mean(axis=0))
        if progress and (p == 0 or (p + 1) % max(1, npass // 8) == 0 or p + 1 == npass):
            el = time.time() - t0
            print(f"  {label} pass {p + 1}/{npass} ({pass_spp} spp each), {el:.1f} s", flush=True)
    img = acc / npass
    means = np.array(means)
    mean = img.reshape(-1, img.shape[-1])[:, :3].mean(axis=0)
    se = means.std(axis=0, ddof=1) / math.sqrt(npass) if npass > 1 else np.full(3, float("nan"))
    return img[..., :3], mean, se, time.time() - t0, npass * pass_spp


def write_exr(path, img):
    mi = mi_()
    bmp = mi.Bitmap(np.ascontiguousarray(img, dtype=np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.write(path)


def write_png_preview(path, img, exposure=1.0):
    mi = mi_()
    bmp = mi.Bitmap(np.ascontiguousarray(img * exposure, dtype=np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB)
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(path)


def read_exr(path):
    mi = mi_()
    bmp = mi.Bitmap(path)
    arr = np.array(bmp, dtype=np.float64)
    if arr.ndim == 2:
        arr = arr[..., None]
    return arr
