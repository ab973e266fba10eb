#!/usr/bin/env python3
"""How bright do glossy receivers come out of the interactive techniques, per roughness?

Issue 34 goal 4: selective's mesh elements store irradiance, and the display lets it
leave every surface as a Lambertian one would (ρ/π), though photons scatter by the glTF
metallic-roughness BRDF. This sweep measures what that costs against the reference path
tracer as the metals' roughness goes from near-mirror to fully rough, beside
photon_stream (whose VSLs treat receivers the same way) and a Lambertian control.

The scene is `builtin:metal-box` written as glTF with one roughness for both metals: the
white room (albedo 0.75, 2 m), the point light of 1 W/sr at (0, 1.8, −0.2), the camera,
a sphere (r = 0.25 m) and a tall box, both white metal (base colour 0.9, metallic 1).
The control replaces the metals by a white Lambertian (metallic 0, roughness 1).

    cargo build --release -p illume
    python3 benches/glossy_sweep.py [--spp 2048] [--width 160 --height 120]

Prints one Markdown row per roughness: HDR-FLIP and mean difference (all channels are
equal: a white scene) of each technique's still against the reference.
"""

import argparse
import base64
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def quad_box(inward):
    """(positions, normals, triangles) of the cube [−1, 1]³, flat faces."""
    pos, nrm, tri = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u, v = [(axis + 1) % 3, (axis + 2) % 3]
            base = len(pos)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[v] = sign, a, b
                pos.append(tuple(p))
                nrm.append(tuple(-x if inward else x for x in n))
            # (u, v, n) is right-handed, so u×v = n: the corners above turn
            # counter-clockwise seen from +n.
            quad = [(0, 1, 2), (0, 2, 3)] if sign > 0 else [(0, 2, 1), (0, 3, 2)]
            if inward:
                quad = [(a, c, b) for a, b, c in quad]
            tri += [(base + a, base + b, base + c) for a, b, c in quad]
    return pos, nrm, tri


def uv_sphere(r, slices=48, stacks=24):
    pos, nrm, tri = [], [], []
    for j in range(stacks + 1):
        th = math.pi * j / stacks
        for i in range(slices + 1):
            ph = 2 * math.pi * i / slices
            n = (math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph))
            nrm.append(n)
            pos.append(tuple(r * x for x in n))
    for j in range(stacks):
        for i in range(slices):
            a = j * (slices + 1) + i
            b = a + slices + 1
            if j != 0:
                tri.append((a, b, a + 1))
            if j != stacks - 1:
                tri.append((a + 1, b, b + 1))
    return pos, nrm, tri


def quat_x(angle):
    return [math.sin(angle / 2), 0.0, 0.0, math.cos(angle / 2)]


def quat_y(angle):
    return [0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2)]


def write_gltf(path, roughness, metallic):
    blob, views, accessors, meshes = b"", [], [], []
    parts = [(quad_box(True), 0), (uv_sphere(0.25), 1), (quad_box(False), 1)]
    for k, ((pos, nrm, tri), material) in enumerate(parts):
        first = len(accessors)
        for data, kind in ((pos, "VEC3"), (nrm, "VEC3")):
            b = b"".join(struct.pack("<3f", *v) for v in data)
            views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(b)})
            blob += b
            acc = {"bufferView": len(views) - 1, "componentType": 5126,
                   "count": len(data), "type": kind}
            if kind == "VEC3" and data is pos:
                acc["min"] = [min(v[a] for v in data) for a in range(3)]
                acc["max"] = [max(v[a] for v in data) for a in range(3)]
            accessors.append(acc)
        t = b"".join(struct.pack("<3I", *f) for f in tri)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(t)})
        blob += t
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125,
                          "count": 3 * len(tri), "type": "SCALAR"})
        meshes.append({"primitives": [{"attributes": {"POSITION": first, "NORMAL": first + 1},
                                       "indices": first + 2, "material": material}]})
    nodes = [
        {"name": "room", "mesh": 0, "translation": [0, 1, 0]},
        {"name": "sphere", "mesh": 1, "translation": [-0.4, 0.25, -0.3]},
        {"name": "metal_box", "mesh": 2, "translation": [0.4, 0.35, -0.45],
         "rotation": quat_y(0.4), "scale": [0.22, 0.35, 0.22]},
        {"name": "camera", "camera": 0, "translation": [0, 1.1, 0.95],
         "rotation": quat_x(math.radians(-12))},
        {"name": "point_light", "translation": [0, 1.8, -0.2],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
    ]
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {"name": "white", "pbrMetallicRoughness": {
                "baseColorFactor": [0.75, 0.75, 0.75, 1], "metallicFactor": 0,
                "roughnessFactor": 1}},
            {"name": "metal", "pbrMetallicRoughness": {
                "baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": metallic,
                "roughnessFactor": roughness}},
        ],
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": math.radians(60), "znear": 0.01}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 1.0, "color": [1, 1, 1]}]}},
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open(path, "w") as f:
        json.dump(doc, f)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{r.stderr}")
    return r.stdout + r.stderr


def compare(illume, ref, test):
    out = run([illume, "compare", ref, test])
    flip = float(re.search(r"hdr-flip\s+([0-9.]+)", out).group(1))
    diff = re.search(r"mean diff\s+([-+0-9.]+) %", out).group(1)
    return flip, diff


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--illume", default=os.path.join(ROOT, "target/release/illume"))
    ap.add_argument("--spp", type=int, default=2048)
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--roughness", default="0.1,0.3,0.6,1.0")
    ap.add_argument("--techniques", default="selective,photon_stream")
    a = ap.parse_args()
    size = ["--width", str(a.width), "--height", str(a.height)]
    techniques = a.techniques.split(",")
    cases = [("Lambertian control", 1.0, 0.0)] + [
        (f"metal, roughness {r}", float(r), 1.0) for r in a.roughness.split(",")]
    print("| receivers | " + " | ".join(f"{t} HDR-FLIP | {t} mean" for t in techniques) + " |")
    print("|---|" + "---:|---:|" * len(techniques))
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, roughness, metallic) in enumerate(cases):
            scene = os.path.join(tmp, f"case{k}.gltf")
            write_gltf(scene, roughness, metallic)
            ref = os.path.join(tmp, f"ref{k}.exr")
            run([a.illume, "render", scene, "--technique", "reference", "--spp", str(a.spp),
                 *size, "-o", ref])
            cells = []
            for t in techniques:
                out = os.path.join(tmp, f"{t}{k}.exr")
                run([a.illume, "render", scene, "--technique", t, *size, "-o", out])
                flip, diff = compare(a.illume, ref, out)
                cells += [f"{flip:.3f}", f"{diff} %"]
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
