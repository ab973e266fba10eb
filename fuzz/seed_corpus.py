#!/usr/bin/env python3
"""Fills fuzz/corpus/TARGET/ with seed inputs for every cargo-fuzz target.

Seeds are the small scenes of ../shared/scenes (glTF with its buffers embedded as base64,
the same scenes packed as GLB), the project's scenarios (and small ones with every kind of
`[[edit]]`), the configuration presets (the TOML blocks of the README and docs/), a few
images written by `illume render` (also as environment maps, with two Radiance HDR skies
written here), `--sky` values with `[sun]` tables, and tiny `.illumepc` files of
`builtin:sun-room` written by `illume precompute` (every domain, a shard, an adaptive
level). Run from the repository root after building
`illume`:

    python3 fuzz/seed_corpus.py [--scenes ../shared/scenes] [--illume target/release/illume]

The corpus is not committed (fuzz/README.md); this script is how it is made again.
"""

import argparse
import base64
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def put(target, name, data):
    folder = os.path.join(CORPUS, target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


def small_files(scenes, ext, max_bytes):
    for dirpath, _, files in os.walk(scenes):
        for name in sorted(files):
            path = os.path.join(dirpath, name)
            if name.lower().endswith(ext) and os.path.getsize(path) <= max_bytes:
                yield path


def embedded_gltf(path):
    """The glTF JSON with every external buffer turned into a base64 data URI."""
    with open(path, "rb") as f:
        doc = json.load(f)
    blobs = []
    for buf in doc.get("buffers", []):
        uri = buf.get("uri", "")
        if uri and not uri.startswith("data:"):
            with open(os.path.join(os.path.dirname(path), uri), "rb") as f:
                data = f.read()
            blobs.append(data)
            buf["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    return doc, blobs


def glb(path):
    """The same scene as a GLB: JSON chunk + one BIN chunk (the first buffer)."""
    with open(path, "rb") as f:
        doc = json.load(f)
    bufs = doc.get("buffers", [])
    if len(bufs) != 1:
        return None
    with open(os.path.join(os.path.dirname(path), bufs[0]["uri"]), "rb") as f:
        binary = f.read()
    del bufs[0]["uri"]
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def rgbe(r, g, b):
    """One Radiance RGBE texel."""
    m = max(r, g, b)
    if m < 1e-32:
        return bytes(4)
    e = 0
    while m >= 1.0:
        m /= 2.0
        e += 1
    while m < 0.5:
        m *= 2.0
        e -= 1
    f = 256.0 / (2.0 ** e)
    return bytes([min(255, int(r * f)), min(255, int(g * f)), min(255, int(b * f)), e + 128])


def hdr(w, h, rle):
    """A small Radiance HDR sky (brighter towards the top), flat or run-length encoded."""
    out = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode()
    for y in range(h):
        row = [rgbe(0.2 + x / w, 0.5 * (h - y) / h, 1.0 + y, ) for x in range(w)]
        if not rle:
            out += b"".join(row)
            continue
        # New RLE: a scan line marker, then each component as literal runs of ≤ 128.
        out += bytes([2, 2, w >> 8, w & 255])
        for c in range(4):
            values = bytes(t[c] for t in row)
            for i in range(0, w, 128):
                chunk = values[i:i + 128]
                out += bytes([len(chunk)]) + chunk
    return out


def seed_new_surfaces(illume, scen):
    """Seeds of the .illumepc reader, bench scenarios with edits, sky values and
    environment maps (issue 38)."""
    # Bench scenarios with [[edit]]s on builtin scenes (what the target loads).
    for name in sorted(os.listdir(scen)):
        with open(os.path.join(scen, name), "rb") as f:
            text = f.read()
        if b"builtin:" in text:
            put("scenario_edits", name, text)
    small = ('scene = "builtin:cornell-spot"\nwidth = 8\nheight = 8\nduration_s = 1\nfps = 4\n'
             '[reference]\nspp = 1\n[[technique]]\nname = "reference"\n')
    edits = {
        "instance": '[[edit]]\nat_s = 0.5\ninstance = "sphere"\ntranslation = [-0.2, 0.3, 0.2]\n'
                    'rotation_deg = [0, 45, 0]\n',
        "light": '[[edit]]\nat_s = 0.25\nlight = "spot"\ntranslation = [0, 1.9, 0]\n',
        "material": '[[edit]]\nat_s = 0.75\nmaterial = "white"\nbase_color = [0.5, 0.5, 0.5]\n'
                    'emission = [0, 0, 0]\n',
        "sun": '[[edit]]\nat_s = 0.5\nmaterial = "white"\nbase_color = [0.2, 0.7, 0.2]\n'
               '[sun]\nlatitude_deg = 40\ndate = "2026-03-20"\nseconds_per_hour = 1\n',
    }
    for name, edit in edits.items():
        put("scenario_edits", f"edit_{name}.toml", (small + edit).encode())
    put("scenario_edits", "edit_sun_room.toml",
        (small.replace("cornell-spot", "sun-room") + 'sky = [0.1, 0.2, 0.4]\n' + edits["sun"]).encode())

    # --sky values, then a [sun] table.
    sun = ('latitude_deg = 55.49\nlongitude_deg = 9.47\ndate = "2026-06-21"\nutc_offset_h = 2\n'
           'start_h = 6\nseconds_per_hour = 3600\nscale = 1\ncolour = [1, 0.95, 0.9]\nlight = "sun"\n')
    for i, sky in enumerate(["0.2,0.3,0.5", "0,0,0", "1e3, 2e3, 3e3", "1,2", "nan,1,1"]):
        put("sky", f"sky{i}.txt", f"{sky}\n{sun}".encode())
    put("sky", "winter.txt", b"0.1,0.1,0.1\nlatitude_deg = -33.9\ndate = \"2026-12-21\"\nutc_offset_h = 11\n")

    # Environment maps: Radiance HDR, flat and run-length encoded; OpenEXR renders.
    put("envmap", "sky_flat.hdr", hdr(4, 2, False))
    put("envmap", "sky_rle.hdr", hdr(16, 8, True))
    with tempfile.TemporaryDirectory() as tmp:
        for w, h in [(8, 4), (16, 8)]:
            out = os.path.join(tmp, f"e{w}.exr")
            subprocess.run([illume, "render", "builtin:cornell-spot", "--technique", "reference",
                            "--spp", "1", "--width", str(w), "--height", str(h), "-o", out],
                           check=True, capture_output=True)
            with open(out, "rb") as f:
                put("envmap", f"e{w}.exr", f.read())

        # .illumepc files of builtin:sun-room (the scene the target loads them for): every
        # domain, a shard, an adaptive level, joint colour. Tiny: 8×6 pixels, 1 spp.
        base = [illume, "precompute", "builtin:sun-room", "--width", "8", "--height", "6",
                "--spp", "1"]
        uniform = ["--schedule", "uniform", "--step-min", "120"]
        runs = {
            "screen": uniform,
            "screen_joint": uniform + ["--colour", "joint", "--components", "3"],
            "cube": uniform + ["--domain", "cube", "--set", "precomputed.cube_face=4"],
            "atlas": uniform + ["--domain", "atlas",
                                "--set", "precomputed.atlas_density=0.5", "--set", "precomputed.probe_spacing=4"],
            "shard": uniform + ["--shard", "1/2"],
            "level0": ["--level", "0", "--step-min", "120"],
            "adaptive": ["--step-min", "240"],
        }
        for name, extra in runs.items():
            out = os.path.join(tmp, f"{name}.illumepc")
            subprocess.run(base + extra + ["-o", out], check=True, capture_output=True)
            with open(out, "rb") as f:
                put("illumepc", f"{name}.illumepc", f.read())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=os.path.join(ROOT, "..", "shared", "scenes"))
    ap.add_argument("--illume", default=os.path.join(ROOT, "target", "release", "illume"))
    args = ap.parse_args()
    if not os.path.isdir(args.scenes):
        sys.exit(f"seed_corpus: no scenes folder at {args.scenes} (give --scenes)")
    if not os.access(args.illume, os.X_OK):
        sys.exit(f"seed_corpus: no illume binary at {args.illume} (cargo build --release -p illume, or give --illume)")
    shutil.rmtree(CORPUS, ignore_errors=True)

    for path in small_files(args.scenes, ".obj", 200_000):
        with open(path, "rb") as f:
            put("load_obj", os.path.basename(path), f.read())
    # OBJ + MTL pairs, split by the load_obj_mtl target at its separator line.
    for path in small_files(args.scenes, ".obj", 200_000):
        mtl = path[:-4] + ".mtl"
        if os.path.exists(mtl):
            with open(path, "rb") as f, open(mtl, "rb") as g:
                put("load_obj_mtl", os.path.basename(path), f.read() + b"\n%%MTL%%\n" + g.read())
    for path in small_files(args.scenes, ".ply", 300_000):
        with open(path, "rb") as f:
            put("load_ply", os.path.basename(path), f.read())
    for path in small_files(args.scenes, ".gltf", 100_000):
        doc, _ = embedded_gltf(path)
        put("load_gltf", os.path.basename(path), json.dumps(doc, indent=1).encode())
        packed = glb(path)
        if packed is not None:
            put("load_glb", os.path.basename(path)[:-5] + ".glb", packed)

    scen = os.path.join(ROOT, "scenarios")
    for name in sorted(os.listdir(scen)):
        with open(os.path.join(scen, name), "rb") as f:
            put("scenario", name, f.read())

    with tempfile.TemporaryDirectory() as tmp:
        # Configuration seeds: every TOML block of the README and the docs.
        n = 0
        for doc in [os.path.join(ROOT, "README.md")] + [
                os.path.join(d, f) for d, _, fs in os.walk(os.path.join(ROOT, "docs")) for f in sorted(fs)
                if f.endswith(".md")]:
            with open(doc, encoding="utf-8") as f:
                text = f.read()
            for block in re.findall(r"```toml\n(.*?)```", text, re.S):
                n += 1
                put("config", f"doc{n}.toml", block.encode())
        for w, h in [(8, 6), (16, 12)]:
            for ext, target in [("png", "read_png"), ("exr", "read_exr")]:
                out = os.path.join(tmp, f"r{w}.{ext}")
                subprocess.run([args.illume, "render", "builtin:cornell-spot", "--technique", "reference",
                                "--spp", "1", "--width", str(w), "--height", str(h), "-o", out],
                               check=True, capture_output=True)
                with open(out, "rb") as f:
                    put(target, f"r{w}.{ext}", f.read())
    seed_new_surfaces(args.illume, scen)
    for target in sorted(os.listdir(CORPUS)):
        print(f"{target}: {len(os.listdir(os.path.join(CORPUS, target)))} seeds")


if __name__ == "__main__":
    main()
