#!/usr/bin/env python3
"""Fills fuzz/corpus/TARGET/ with seed inputs for every cargo-fuzz target.

Seeds are the small scenes of ../shared/scenes (glTF with its buffers embedded as base64,
the same scenes packed as GLB), the project's scenarios, the configuration presets
(the TOML blocks of the README and docs/), and a
few images written by `illume render`. Run from the repository root after building
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
    for target in sorted(os.listdir(CORPUS)):
        print(f"{target}: {len(os.listdir(os.path.join(CORPUS, target)))} seeds")


if __name__ == "__main__":
    main()
