#!/usr/bin/env python3
"""Writing glTF 2.0 scenes from Python (standard library only), for tools/make_scenes.py.

`Gltf` builds one document with its binary buffer (float32 positions and normals, uint32
indices, accessor min/max written exactly), `validate` re-reads what was written and checks it
(buffer lengths, accessor bounds and min/max, index ranges, material and node references), and a
few vector helpers place cameras and walls. Output is byte-for-byte deterministic: fixed key
order, fixed float formatting, little-endian buffers.
"""

import json
import math
import struct

GENERATOR = "tessera tools/make_scenes.py"

# glTF constants
FLOAT = 5126
UNSIGNED_INT = 5125
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963
TRIANGLES = 4


# --------------------------------------------------------------------------
# small vector helpers
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(a, k):
    return (a[0] * k, a[1] * k, a[2] * k)


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def look_at_rotation(eye, target, up=(0.0, 1.0, 0.0)):
    """Unit quaternion (x, y, z, w) turning a glTF camera (looking down local
    -z, +y up) to look from eye at target."""
    back = normalize(sub(eye, target))           # local +z
    right = normalize(cross(up, back))           # local +x
    true_up = cross(back, right)                 # local +y
    # Rotation matrix with columns right, true_up, back -> quaternion
    # (Shepperd's method: branch on the largest diagonal term for accuracy).
    m = [[right[0], true_up[0], back[0]], [right[1], true_up[1], back[1]],
         [right[2], true_up[2], back[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        k = 2.0 * math.sqrt(tr + 1.0)
        q = ((m[2][1] - m[1][2]) / k, (m[0][2] - m[2][0]) / k, (m[1][0] - m[0][1]) / k, k / 4)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        k = 2.0 * math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2])
        q = (k / 4, (m[0][1] + m[1][0]) / k, (m[0][2] + m[2][0]) / k, (m[2][1] - m[1][2]) / k)
    elif m[1][1] > m[2][2]:
        k = 2.0 * math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2])
        q = ((m[0][1] + m[1][0]) / k, k / 4, (m[1][2] + m[2][1]) / k, (m[0][2] - m[2][0]) / k)
    else:
        k = 2.0 * math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1])
        q = ((m[0][2] + m[2][0]) / k, (m[1][2] + m[2][1]) / k, k / 4, (m[1][0] - m[0][1]) / k)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def f32(x):
    """Round a Python float to the nearest float32."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def f32_json(x):
    """Shortest decimal that parses (as double, then rounded to float32) to
    the same float32 as x. Used for accessor min/max so they match the data
    exactly without printing float32 noise like 0.5527999997138977."""
    target = f32(x)
    for digits in range(1, 18):
        s = "%.*g" % (digits, target)
        if f32(float(s)) == target:
            v = float(s)
            return 0.0 if v == 0 else v  # no "-0.0"
    return target


def oriented_quads(quads, want, convert=lambda v: v):
    """Triangulate quads (v0,v1,v2,v3) -> (0,1,2),(0,2,3), reversing a quad's
    winding where needed so every triangle's normal cross(v1-v0, v2-v0) points
    along want(quad) (a direction vector). `convert` maps each input vertex to
    output units (default: unchanged). Returns (positions, triangles)."""
    positions, triangles = [], []
    for q in quads:
        d = want(q)
        n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
        if dot(n, d) < 0:
            q = [q[0], q[3], q[2], q[1]]
        base = len(positions)
        positions += [convert(v) for v in q]
        for tri in ((0, 1, 2), (0, 2, 3)):
            a, b, c = (positions[base + i] for i in tri)
            tn = cross(sub(b, a), sub(c, a))
            nl = math.sqrt(dot(tn, tn))
            dl = math.sqrt(dot(d, d))
            # Well within the hemisphere, not merely on the right side.
            assert nl > 0 and dot(tn, d) / (nl * dl) > 0.9, (q, tri, tn, d)
            triangles.append(tuple(base + i for i in tri))
    return positions, triangles


def centroid(pts):
    n = float(len(pts))
    return (sum(p[0] for p in pts) / n, sum(p[1] for p in pts) / n, sum(p[2] for p in pts) / n)


# --------------------------------------------------------------------------
# glTF document builder
class Gltf:
    def __init__(self, description):
        self.doc = {
            "asset": {
                "version": "2.0",
                "generator": GENERATOR,
                "extras": {"description": description},
            },
        }
        self.bin = bytearray()
        self.used = []
        self.required = []

    def use(self, ext, required=False):
        if ext not in self.used:
            self.used.append(ext)
        if required and ext not in self.required:
            self.required.append(ext)

    def _list(self, key):
        return self.doc.setdefault(key, [])

    def add(self, key, obj):
        lst = self._list(key)
        lst.append(obj)
        return len(lst) - 1

    def material(self, name, base=(0.0, 0.0, 0.0), metallic=0.0, roughness=1.0,
                 emission=None, transmission=None, ior=None, double_sided=False,
                 specular=None, thickness=None):
        """A glTF metallic-roughness material. `specular` writes KHR_materials_specular's
        specularFactor (0: a pure Lambertian, no dielectric coat); `thickness` writes
        KHR_materials_volume's thicknessFactor (> 0: the mesh bounds a refracting volume,
        else a transmissive surface is thin-walled)."""
        m = {
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [base[0], base[1], base[2], 1.0],
                "metallicFactor": metallic,
                "roughnessFactor": roughness,
            },
        }
        if double_sided:
            m["doubleSided"] = True
        if emission is not None:
            factor, strength = emission
            m["emissiveFactor"] = list(factor)
            m["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
            self.use("KHR_materials_emissive_strength")
        if transmission is not None:
            m.setdefault("extensions", {})["KHR_materials_transmission"] = {
                "transmissionFactor": transmission}
            self.use("KHR_materials_transmission")
        if ior is not None:
            m.setdefault("extensions", {})["KHR_materials_ior"] = {"ior": ior}
            self.use("KHR_materials_ior")
        if specular is not None:
            m.setdefault("extensions", {})["KHR_materials_specular"] = {"specularFactor": specular}
            self.use("KHR_materials_specular")
        if thickness is not None:
            m.setdefault("extensions", {})["KHR_materials_volume"] = {"thicknessFactor": thickness}
            self.use("KHR_materials_volume")
        return self.add("materials", m)

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        offset = len(self.bin)
        self.bin += data
        return self.add("bufferViews", {
            "buffer": 0, "byteOffset": offset, "byteLength": len(data), "target": target})

    def mesh(self, name, positions, triangles, material):
        """positions: list of (x, y, z) floats; triangles: list of (i, j, k)."""
        pdata = b"".join(struct.pack("<3f", *p) for p in positions)
        idata = b"".join(struct.pack("<3I", *t) for t in triangles)
        lo = [f32_json(min(p[c] for p in positions)) for c in range(3)]
        hi = [f32_json(max(p[c] for p in positions)) for c in range(3)]
        pos = self.add("accessors", {
            "bufferView": self._view(pdata, ARRAY_BUFFER),
            "componentType": FLOAT, "count": len(positions), "type": "VEC3",
            "min": lo, "max": hi})
        ind = self.add("accessors", {
            "bufferView": self._view(idata, ELEMENT_ARRAY_BUFFER),
            "componentType": UNSIGNED_INT, "count": 3 * len(triangles), "type": "SCALAR"})
        return self.add("meshes", {"name": name, "primitives": [{
            "attributes": {"POSITION": pos}, "indices": ind,
            "material": material, "mode": TRIANGLES}]})

    def camera(self, name, yfov, aspect, znear, translation=None, rotation=None):
        cam = self.add("cameras", {"name": name, "type": "perspective", "perspective": {
            "yfov": yfov, "aspectRatio": aspect, "znear": znear}})
        node = {"name": name, "camera": cam}
        if translation is not None:
            node["translation"] = list(translation)
        if rotation is not None:
            node["rotation"] = list(rotation)
        return self.add("nodes", node)

    def point_light(self, name, position, color, intensity):
        """KHR_lights_punctual point light; Tessera reads intensity x color as
        radiant intensity (W/sr)."""
        self.use("KHR_lights_punctual")
        lights = self.doc.setdefault("extensions", {}).setdefault(
            "KHR_lights_punctual", {"lights": []})["lights"]
        lights.append({"name": name, "type": "point", "color": list(color), "intensity": intensity})
        return self.add("nodes", {"name": name, "translation": list(position),
                                  "extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}})

    def asset_mesh(self, name, asset, material, translation, scale, rotation=None):
        """TESSERA_asset_mesh: a mesh file that is never committed (e.g. the
        Stanford dragon), named relative to TESSERA_ASSETS / the fetch cache."""
        self.use("TESSERA_asset_mesh", required=True)
        node = {"name": name, "translation": list(translation), "scale": [scale, scale, scale],
                "extensions": {"TESSERA_asset_mesh": {"asset": asset, "material": material}}}
        if rotation is not None:
            node["rotation"] = list(rotation)
        return self.add("nodes", node)

    def asset_gltf(self, name, asset, translation, scale, rotation=None):
        """TESSERA_asset_gltf: a glTF/GLB file that is never committed (e.g. a
        WebXR controller), named relative to TESSERA_ASSETS / the fetch cache,
        loaded with its meshes, materials, textures and node hierarchy."""
        self.use("TESSERA_asset_gltf", required=True)
        node = {"name": name, "translation": list(translation), "scale": [scale, scale, scale],
                "extensions": {"TESSERA_asset_gltf": {"asset": asset}}}
        if rotation is not None:
            node["rotation"] = list(rotation)
        return self.add("nodes", node)

    def sphere(self, name, centre, radius, material):
        self.use("TESSERA_sphere", required=True)
        return self.add("nodes", {"name": name, "translation": list(centre),
                                  "extensions": {"TESSERA_sphere": {"radius": radius,
                                                                    "material": material}}})

    def quads(self, name, quads, want, material):
        """A mesh node of quads in scene units, each facing along want(quad)."""
        pos, tris = oriented_quads(quads, want)
        return self.add("nodes", {"name": name, "mesh": self.mesh(name, pos, tris, material)})

    def render(self, resolution, spp, max_depth, seed, integrator):
        self.doc.setdefault("extensions", {})["TESSERA_render"] = {
            "resolution": list(resolution), "spp": spp, "maxDepth": max_depth,
            "seed": seed, "integrator": integrator}
        self.use("TESSERA_render")

    def finish(self, bin_name=None):
        """Return (gltf_text, bin_bytes_or_None)."""
        doc = dict(self.doc)
        nodes = list(range(len(doc.get("nodes", []))))
        doc["scene"] = 0
        doc["scenes"] = [{"nodes": nodes}]
        if self.bin:
            assert bin_name
            doc["buffers"] = [{"uri": bin_name, "byteLength": len(self.bin)}]
        if self.used:
            doc["extensionsUsed"] = list(self.used)
        if self.required:
            doc["extensionsRequired"] = list(self.required)
        # Put the well-known top-level keys in a stable, readable order.
        order = ["asset", "extensionsUsed", "extensionsRequired", "extensions", "scene",
                 "scenes", "nodes", "cameras", "meshes", "materials", "accessors",
                 "bufferViews", "buffers"]
        out = {k: doc[k] for k in order if k in doc}
        assert set(out) == set(doc), set(doc) - set(out)
        text = json.dumps(out, indent=2, allow_nan=False) + "\n"
        return text, (bytes(self.bin) if self.bin else None)


# --------------------------------------------------------------------------
# Validation of what was produced (re-parsed from text / bytes)
def validate(name, text, binary):
    doc = json.loads(text)
    asset = doc["asset"]
    assert asset["version"] == "2.0" and asset["generator"] == GENERATOR, name
    assert isinstance(asset["extras"]["description"], str) and "\n" not in asset["extras"]["description"]
    used = set(doc.get("extensionsUsed", []))
    required = set(doc.get("extensionsRequired", []))
    assert required <= used and required <= {"TESSERA_sphere", "TESSERA_asset_mesh", "TESSERA_asset_gltf"}, name

    found = set()

    def walk(o):
        if isinstance(o, dict):
            for k, v in o.items():
                if k == "extensions":
                    found.update(v.keys())
                walk(v)
        elif isinstance(o, list):
            for v in o:
                walk(v)
    walk(doc)
    assert found == used, (name, found, used)

    materials = doc.get("materials", [])
    for i, m in enumerate(materials):
        pbr = m["pbrMetallicRoughness"]
        assert "metallicFactor" in pbr and "roughnessFactor" in pbr, (name, i)
        assert len(pbr["baseColorFactor"]) == 4
        assert all(0.0 <= c <= 1.0 for c in pbr["baseColorFactor"] + m.get("emissiveFactor", []))

    buffers = doc.get("buffers", [])
    if buffers:
        assert len(buffers) == 1 and binary is not None
        assert buffers[0]["byteLength"] == len(binary), name
    else:
        assert binary is None
    views = doc.get("bufferViews", [])
    for v in views:
        assert v["byteOffset"] % 4 == 0
        assert v["byteOffset"] + v["byteLength"] <= len(binary)
    accessors = doc.get("accessors", [])

    def read(acc):
        v = views[acc["bufferView"]]
        start = v["byteOffset"] + acc.get("byteOffset", 0)
        comps = {"SCALAR": 1, "VEC3": 3}[acc["type"]]
        fmt = {FLOAT: "f", UNSIGNED_INT: "I"}[acc["componentType"]]
        n = acc["count"] * comps
        assert start + 4 * n <= v["byteOffset"] + v["byteLength"]
        vals = struct.unpack_from("<%d%s" % (n, fmt), binary, start)
        return [vals[i:i + comps] for i in range(0, n, comps)]

    meshes = doc.get("meshes", [])
    for mi, mesh in enumerate(meshes):
        for prim in mesh["primitives"]:
            pa = accessors[prim["attributes"]["POSITION"]]
            pts = read(pa)
            assert "min" in pa and "max" in pa, (name, mi)
            for c in range(3):
                assert f32(pa["min"][c]) == min(p[c] for p in pts), (name, mi, c)
                assert f32(pa["max"][c]) == max(p[c] for p in pts), (name, mi, c)
            idx = [i[0] for i in read(accessors[prim["indices"]])]
            assert len(idx) % 3 == 0 and all(0 <= i < len(pts) for i in idx), (name, mi)
            assert 0 <= prim["material"] < len(materials)
    cameras = doc.get("cameras", [])
    nodes = doc.get("nodes", [])
    for node in nodes:
        if "mesh" in node:
            assert 0 <= node["mesh"] < len(meshes)
        if "camera" in node:
            assert 0 <= node["camera"] < len(cameras)
        s = node.get("extensions", {}).get("TESSERA_sphere")
        if s is not None:
            assert "mesh" not in node and s["radius"] > 0 and 0 <= s["material"] < len(materials)
        a = node.get("extensions", {}).get("TESSERA_asset_mesh")
        if a is not None:
            assert "mesh" not in node and 0 <= a["material"] < len(materials)
            parts = a["asset"].split("/")
            assert all(p and p not in (".", "..") and
                       all(ch.isalnum() or ch in "._-" for ch in p) for p in parts), a["asset"]
        ag = node.get("extensions", {}).get("TESSERA_asset_gltf")
        if ag is not None:
            assert "mesh" not in node and set(ag) == {"asset"}, ag
            parts = ag["asset"].split("/")
            assert ag["asset"].endswith((".glb", ".gltf")) and all(
                p and p not in (".", "..") and all(ch.isalnum() or ch in "._-" for ch in p) for p in parts), ag["asset"]
        lp = node.get("extensions", {}).get("KHR_lights_punctual")
        if lp is not None:
            assert 0 <= lp["light"] < len(doc["extensions"]["KHR_lights_punctual"]["lights"])
        if "rotation" in node:
            q = node["rotation"]
            assert abs(sum(x * x for x in q) - 1.0) < 1e-9
    assert sorted(doc["scenes"][doc["scene"]]["nodes"]) == list(range(len(nodes)))
    assert sum(1 for n in nodes if "camera" in n) == 1
    return doc
