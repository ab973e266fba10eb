"""Minimal, dependency-light glTF 2.0 reader for illume's cross-check scripts.

Reads exactly what the illume test scenes use (../shared/scenes/gltf/*.gltf) with
nothing but json + numpy, and flattens the node hierarchy into world space:

* triangle meshes (mode 4, POSITION / NORMAL / indices) -> world positions, world
  normals (inverse-transpose of the node's linear part, renormalised), triangle
  indices (winding flipped when the world transform mirrors, per the glTF spec),
  material index;
* materials: baseColorFactor, emissiveFactor x KHR_materials_emissive_strength,
  doubleSided;
* KHR_lights_punctual point / spot / directional lights: world position, world
  direction (node local -Z), intensity, colour, cone angles;
* the first camera node (world matrix, yfov).

Node TRS animations (LINEAR / STEP samplers, translation / rotation / scale) can be
evaluated at a time t, so the same scene can be checked at any frame.

Anything the scenes do not use (textures, skins, morph targets, sparse accessors)
raises an error instead of being silently ignored.
"""

import json
import math
import os

import numpy as np

COMPONENT_DTYPES = {
    5120: np.int8,
    5121: np.uint8,
    5122: np.int16,
    5123: np.uint16,
    5125: np.uint32,
    5126: np.float32,
}
TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def quat_to_matrix(q):
    """glTF quaternion [x, y, z, w] -> 3x3 rotation matrix."""
    x, y, z, w = (float(c) for c in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def slerp(q0, q1, u):
    q0 = np.asarray(q0, float)
    q1 = np.asarray(q1, float)
    d = float(np.dot(q0, q1))
    if d < 0.0:
        q1, d = -q1, -d
    if d > 0.9995:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    th = math.acos(d)
    return (math.sin((1 - u) * th) * q0 + math.sin(u * th) * q1) / math.sin(th)


def trs_matrix(t, r, s):
    m = np.eye(4)
    m[:3, :3] = quat_to_matrix(r) @ np.diag(np.asarray(s, float))
    m[:3, 3] = np.asarray(t, float)
    return m


class Gltf:
    def __init__(self, path):
        self.path = os.path.abspath(path)
        with open(self.path) as f:
            self.doc = json.load(f)
        base = os.path.dirname(self.path)
        self.buffers = []
        for b in self.doc.get("buffers", []):
            uri = b["uri"]
            if uri.startswith("data:"):
                raise ValueError("data: URIs are not supported by this reader")
            with open(os.path.join(base, uri), "rb") as f:
                self.buffers.append(f.read())

    # ---------------------------------------------------------------- accessors
    def accessor(self, index):
        a = self.doc["accessors"][index]
        if "sparse" in a:
            raise ValueError("sparse accessors are not supported")
        bv = self.doc["bufferViews"][a["bufferView"]]
        dtype = np.dtype(COMPONENT_DTYPES[a["componentType"]])
        ncomp = TYPE_SIZES[a["type"]]
        count = a["count"]
        offset = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = bv.get("byteStride", 0) or dtype.itemsize * ncomp
        buf = self.buffers[bv["buffer"]]
        if stride == dtype.itemsize * ncomp:
            arr = np.frombuffer(buf, dtype, count * ncomp, offset).reshape(count, ncomp)
        else:
            rows = [np.frombuffer(buf, dtype, ncomp, offset + i * stride) for i in range(count)]
            arr = np.stack(rows)
        if a.get("normalized", False):
            raise ValueError("normalized integer accessors are not supported")
        return arr.copy()

    # ---------------------------------------------------------------- animation
    def animated_trs(self, time):
        """{node index: {'translation'|'rotation'|'scale': value}} at time `time`."""
        out = {}
        if time is None:
            return out
        for anim in self.doc.get("animations", []):
            for ch in anim["channels"]:
                samp = anim["samplers"][ch["sampler"]]
                target = ch["target"]
                path = target["path"]
                if path not in ("translation", "rotation", "scale"):
                    raise ValueError(f"animation path {path} not supported")
                times = self.accessor(samp["input"]).ravel().astype(float)
                vals = self.accessor(samp["output"]).astype(float)
                interp = samp.get("interpolation", "LINEAR")
                if interp == "CUBICSPLINE":
                    raise ValueError("CUBICSPLINE animation not supported")
                if time <= times[0]:
                    v = vals[0]
                elif time >= times[-1]:
                    v = vals[-1]
                else:
                    k = int(np.searchsorted(times, time, side="right")) - 1
                    u = (time - times[k]) / (times[k + 1] - times[k])
                    if interp == "STEP":
                        v = vals[k]
                    elif path == "rotation":
                        v = slerp(vals[k], vals[k + 1], u)
                    else:
                        v = (1 - u) * vals[k] + u * vals[k + 1]
                out.setdefault(target["node"], {})[path] = v
        return out

    # ---------------------------------------------------------------- flatten
    def flatten(self, time=None):
        """World-space scene description (see module docstring)."""
        doc = self.doc
        anim = self.animated_trs(time)
        scene = doc["scenes"][doc.get("scene", 0)]
        lights_def = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
        out = {"meshes": [], "lights": [], "camera": None, "materials": self.materials()}

        def local_matrix(idx, node):
            if "matrix" in node and idx not in anim:
                return np.array(node["matrix"], float).reshape(4, 4).T  # column-major
            if "matrix" in node:
                raise ValueError("animated node with a matrix is not allowed by glTF")
            a = anim.get(idx, {})
            t = a.get("translation", node.get("translation", [0, 0, 0]))
            r = a.get("rotation", node.get("rotation", [0, 0, 0, 1]))
            s = a.get("scale", node.get("scale", [1, 1, 1]))
            return trs_matrix(t, r, s)

        def visit(idx, parent):
            node = doc["nodes"][idx]
            if "skin" in node or "weights" in node:
                raise ValueError("skins / morph targets are not supported")
            world = parent @ local_matrix(idx, node)
            if "mesh" in node:
                self._add_mesh(out, node, world)
            ext = node.get("extensions", {}).get("KHR_lights_punctual")
            if ext is not None:
                ld = lights_def[ext["light"]]
                pos = world[:3, 3].copy()
                d = world[:3, :3] @ np.array([0.0, 0.0, -1.0])
                light = {
                    "name": ld.get("name", node.get("name", "light")),
                    "type": ld["type"],
                    "position": pos,
                    "direction": d / np.linalg.norm(d),
                    "intensity": float(ld.get("intensity", 1.0)),
                    "color": np.array(ld.get("color", [1.0, 1.0, 1.0]), float),
                    "range": ld.get("range"),
                }
                if ld["type"] == "spot":
                    sp = ld.get("spot", {})
                    light["inner"] = float(sp.get("innerConeAngle", 0.0))
                    light["outer"] = float(sp.get("outerConeAngle", math.pi / 4))
                out["lights"].append(light)
            if "camera" in node and out["camera"] is None:
                cam = doc["cameras"][node["camera"]]
                if cam["type"] != "perspective":
                    raise ValueError("only perspective cameras are supported")
                out["camera"] = {
                    "name": node.get("name", "camera"),
                    "world": world,
                    "yfov": float(cam["perspective"]["yfov"]),
                    "aspect": cam["perspective"].get("aspectRatio"),
                }
            for c in node.get("children", []):
                visit(c, world)

        for n in scene["nodes"]:
            visit(n, np.eye(4))
        return out

    def materials(self):
        mats = []
        for m in self.doc.get("materials", []):
            pbr = m.get("pbrMetallicRoughness", {})
            for key in ("baseColorTexture", "metallicRoughnessTexture"):
                if key in pbr:
                    raise ValueError(f"material {m.get('name')}: {key} not supported")
            for key in ("emissiveTexture", "normalTexture", "occlusionTexture"):
                if key in m:
                    raise ValueError(f"material {m.get('name')}: {key} not supported")
            metallic = float(pbr.get("metallicFactor", 1.0))  # glTF default is 1!
            strength = float(
                m.get("extensions", {})
                .get("KHR_materials_emissive_strength", {})
                .get("emissiveStrength", 1.0)
            )
            mats.append(
                {
                    "name": m.get("name", f"material{len(mats)}"),
                    "base_color": np.array(pbr.get("baseColorFactor", [1, 1, 1, 1])[:3], float),
                    "metallic": metallic,
                    "roughness": float(pbr.get("roughnessFactor", 1.0)),
                    "emission": np.array(m.get("emissiveFactor", [0, 0, 0]), float) * strength,
                    "double_sided": bool(m.get("doubleSided", False)),
                }
            )
        return mats

    def _add_mesh(self, out, node, world):
        mesh = self.doc["meshes"][node["mesh"]]
        lin = world[:3, :3]
        det = float(np.linalg.det(lin))
        normal_m = np.linalg.inv(lin).T
        for k, prim in enumerate(mesh["primitives"]):
            if prim.get("mode", 4) != 4:
                raise ValueError("only triangle lists (mode 4) are supported")
            pos = self.accessor(prim["attributes"]["POSITION"]).astype(float)
            if "indices" in prim:
                idx = self.accessor(prim["indices"]).astype(np.int64).reshape(-1, 3)
            else:
                idx = np.arange(len(pos)).reshape(-1, 3)
            wpos = pos @ lin.T + world[:3, 3]
            wnrm = None
            if "NORMAL" in prim["attributes"]:
                nrm = self.accessor(prim["attributes"]["NORMAL"]).astype(float)
                wnrm = nrm @ normal_m.T
                wnrm /= np.linalg.norm(wnrm, axis=1, keepdims=True)
            if det < 0:  # mirrored instance: glTF says the winding flips
                idx = idx[:, ::-1].copy()
            out["meshes"].append(
                {
                    "name": f"{mesh.get('name', 'mesh')}_{k}",
                    "positions": wpos,
                    "normals": wnrm,
                    "indices": idx,
                    "material": prim.get("material"),
                }
            )


def winding_normal_agreement(mesh):
    """Number of triangles whose winding (CCW) normal disagrees with its vertex normals."""
    p, i, n = mesh["positions"], mesh["indices"], mesh["normals"]
    fn = np.cross(p[i[:, 1]] - p[i[:, 0]], p[i[:, 2]] - p[i[:, 0]])
    if n is None:
        return 0
    return int(((fn * n[i].sum(axis=1)).sum(axis=1) <= 0).sum())
