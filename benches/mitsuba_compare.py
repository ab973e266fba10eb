#!/usr/bin/env python3
"""illume's reference path tracer against Mitsuba 3 on the same triangles.

Optional yardstick (the project does not need Mitsuba): `pip install mitsuba`, build
illume (`cargo build --release -p illume`), then

    python3 benches/mitsuba_compare.py [--spp 1024] [--width 160 --height 120]

Two scenes share one geometry: a grey Lambertian floor (4 m × 4 m, albedo 0.5) and a
white rough metal sphere (glTF metallic 1, roughness 0.5 → GGX α = 0.25; Mitsuba
`roughconductor`, `distribution = "ggx"`, `material = "none"`, so Fresnel = 1 in both).
`glossy`: one point light of 8 W/sr at (1.5, 2.5, 1.0). `sky`: a uniform sky of radiance
(0.4, 0.6, 1.0) W/(m²·sr), no other light. The same flat-shaded triangles go to both (a
glTF with an embedded buffer for illume, an OBJ for Mitsuba), the same camera, box pixel
filter. Prints per-channel means and their ratio, and illume's HDR-FLIP between the two
images (`illume compare`).

Expected difference: Mitsuba's GGX masking-shadowing is the uncorrelated product
G1(wo)·G1(wi); glTF's (and illume's) is the height-correlated Smith form, which is larger
at grazing angles; so illume's metal is slightly brighter near the sphere's silhouette.
"""

import argparse
import base64
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EYE, TARGET, FOV_Y = (0.0, 1.5, 4.0), (0.0, 0.5, 0.0), 40.0
LIGHT_POS, LIGHT_I = (1.5, 2.5, 1.0), 8.0
SKY = (0.4, 0.6, 1.0)


def geometry():
    """(positions, triangles) of the floor, then of the sphere (counter-clockwise out)."""
    floor_p = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)]
    floor_t = [(0, 2, 1), (0, 3, 2)]  # faces +y
    c, r, slices, stacks = (0.0, 0.6, 0.0), 0.6, 64, 32
    sp, st = [], []
    for j in range(stacks + 1):
        th = math.pi * j / stacks
        for i in range(slices + 1):
            ph = 2 * math.pi * i / slices
            sp.append((c[0] + r * math.sin(th) * math.cos(ph), c[1] + r * math.cos(th),
                       c[2] + r * math.sin(th) * math.sin(ph)))
    for j in range(stacks):
        for i in range(slices):
            a = j * (slices + 1) + i
            b = a + slices + 1
            if j != 0:
                st.append((a, a + 1, b))
            if j != stacks - 1:
                st.append((a + 1, b + 1, b))
    return (floor_p, floor_t), (sp, st)


def write_gltf(path, parts, sky):
    blob, views, accessors, meshes, nodes = b"", [], [], [], []
    for k, (pos, tri) in enumerate(parts):
        p = b"".join(struct.pack("<3f", *v) for v in pos)
        t = b"".join(struct.pack("<3I", *f) for f in tri)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(p)})
        blob += p
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(t)})
        blob += t
        lo = [min(v[a] for v in pos) for a in range(3)]
        hi = [max(v[a] for v in pos) for a in range(3)]
        accessors.append({"bufferView": 2 * k, "componentType": 5126, "count": len(pos),
                          "type": "VEC3", "min": lo, "max": hi})
        accessors.append({"bufferView": 2 * k + 1, "componentType": 5125,
                          "count": 3 * len(tri), "type": "SCALAR"})
        meshes.append({"primitives": [{"attributes": {"POSITION": 2 * k},
                                       "indices": 2 * k + 1, "material": k}]})
        nodes.append({"mesh": k, "name": ["floor", "sphere"][k]})
    pitch = math.atan2(EYE[1] - TARGET[1], EYE[2] - TARGET[2])
    nodes.append({"camera": 0, "translation": list(EYE),
                  "rotation": [-math.sin(pitch / 2), 0, 0, math.cos(pitch / 2)]})
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes) + (0 if sky else 1)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                                       "metallicFactor": 0, "roughnessFactor": 1}},
            {"name": "metal", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1],
                                                       "metallicFactor": 1, "roughnessFactor": 0.5}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(FOV_Y),
                                                             "znear": 0.01}}],
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    if sky:
        doc["extras"] = {"illume_sky": {"radiance": list(SKY)}}
    else:
        doc["extensionsUsed"] = ["KHR_lights_punctual"]
        doc["extensions"] = {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": LIGHT_I, "color": [1, 1, 1]}]}}
        doc["nodes"].append({"translation": list(LIGHT_POS),
                             "extensions": {"KHR_lights_punctual": {"light": 0}}})
        doc["scenes"][0]["nodes"] = list(range(len(doc["nodes"])))
    with open(path, "w") as f:
        json.dump(doc, f)


def write_obj(path, pos, tri):
    with open(path, "w") as f:
        for v in pos:
            f.write("v %.9g %.9g %.9g\n" % v)
        for t in tri:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def mitsuba_render(parts_obj, sky, spp, w, h, out):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": -1},
        "sensor": {"type": "perspective", "fov": FOV_Y, "fov_axis": "y",
                   "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "floor": {"type": "obj", "filename": parts_obj[0], "face_normals": True,
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}},
        "sphere": {"type": "obj", "filename": parts_obj[1], "face_normals": True,
                   "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.25,
                            "material": "none"}},
    }
    if sky:
        scene["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": list(SKY)}}
    else:
        scene["light"] = {"type": "point", "position": list(LIGHT_POS),
                          "intensity": {"type": "rgb", "value": [LIGHT_I] * 3}}
    img = mi.render(mi.load_dict(scene))
    mi.Bitmap(img).write(out)


def mean_exr(path):
    import mitsuba as mi
    import numpy as np
    return np.array(mi.Bitmap(path)).reshape(-1, 3).mean(axis=0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--illume", default=os.path.join(ROOT, "target/release/illume"))
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="illume-mitsuba-")
    (fp, ft), (sp, st) = geometry()
    objs = [os.path.join(tmp, "floor.obj"), os.path.join(tmp, "sphere.obj")]
    write_obj(objs[0], fp, ft)
    write_obj(objs[1], sp, st)
    for name, sky in [("glossy", False), ("sky", True)]:
        gltf = os.path.join(tmp, f"{name}.gltf")
        write_gltf(gltf, [(fp, ft), (sp, st)], sky)
        ours, theirs = os.path.join(tmp, f"{name}_illume.exr"), os.path.join(tmp, f"{name}_mitsuba.exr")
        subprocess.run([a.illume, "render", gltf, "--technique", "reference", "--spp", str(a.spp),
                        "--width", str(a.width), "--height", str(a.height), "-o", ours], check=True,
                       stderr=subprocess.DEVNULL)
        mitsuba_render(objs, sky, a.spp, a.width, a.height, theirs)
        mo, mm = mean_exr(ours), mean_exr(theirs)
        flip = subprocess.run([a.illume, "compare", theirs, ours, "--metric", "hdr-flip"],
                              capture_output=True, text=True).stdout.strip()
        print(f"{name}: illume mean {mo.round(5)}, Mitsuba mean {mm.round(5)}, "
              f"ratio {(mo / mm).round(4)}")
        print(f"  {flip}")
    print(f"images in {tmp}")


if __name__ == "__main__":
    sys.exit(main())
