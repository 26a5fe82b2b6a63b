#!/usr/bin/env python3
"""Generate Tessera's built-in test scenes (glTF 2.0) under scenes/.

Usage:
    python3 tools/make_scenes.py           # (re)write every scene under scenes/
    python3 tools/make_scenes.py --check   # exit 1 if any file on disk differs

Standard library only; output is byte-for-byte deterministic (fixed key order,
fixed float formatting, little-endian binary buffers), so the generated files
are committed and `--check` can guard them in CI.

Scenes written:
  scenes/cornell-box/cornell-box.gltf (+ cornell-box.bin)
      The measured Cornell box (Cornell Program of Computer Graphics data),
      millimetres converted to metres, with the measured pinhole camera.
  scenes/sphere-cornell/sphere-cornell.gltf
      The smallpt-style box made of nine analytic spheres (TESSERA_sphere).
  scenes/sphere-cornell/sphere-cornell-mirror.gltf
      Same, left sphere is a perfect mirror.
  scenes/sphere-cornell/sphere-cornell-glass.gltf
      Same, right sphere is clear glass (IOR 1.5).
  scenes/README.md
      Table of the scenes above.

Conventions (what Tessera's loader reads):
  * Materials: pbrMetallicRoughness with metallicFactor written explicitly
    (glTF's default of 1 would mean metal). metallic 0 / roughness 1 is
    Lambertian with albedo = baseColorFactor.
  * Emitters: black base colour, emissiveFactor (max component 1) times
    KHR_materials_emissive_strength.emissiveStrength = radiance. Emission is
    one-sided: the front face is the counter-clockwise side, i.e. the face
    normal is cross(v1 - v0, v2 - v0).
  * TESSERA_render (root): default resolution/spp/maxDepth/seed/integrator.
  * TESSERA_sphere (node): analytic sphere of `radius` centred at the node's
    translation, using material index `material`. Listed in
    extensionsRequired because a viewer ignoring it would lose geometry.
  * glTF cameras look down local -z with +y up.

Every triangle's winding is checked against the intended normal direction
(room walls face the interior, block faces face outward, the light faces
down) and flipped if needed, then asserted. After writing, every file is
re-read and validated (buffer length, accessor bounds and min/max, index
range, material / node references).
"""

import json
import math
import os
import struct
import sys

GENERATOR = "tessera tools/make_scenes.py"
ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENES = os.path.join(ROOT, "scenes")

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


def mm(p):
    """Measured millimetres -> metres."""
    return (p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0)


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
                 emission=None, transmission=None, ior=None):
        m = {
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [base[0], base[1], base[2], 1.0],
                "metallicFactor": metallic,
                "roughnessFactor": roughness,
            },
        }
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
# Cornell box (measured data, http://www.graphics.cornell.edu/online/box/data.html)
#
# Measured coordinates, millimetres. Each quad is listed as in the measured
# data; winding is fixed up below against the intended normal direction.
CB_FLOOR = [(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]
CB_CEILING = [(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2), (0.0, 548.8, 0.0)]
CB_BACK = [(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2), (556.0, 548.8, 559.2)]
# x ~ 0 wall. The camera at z = -800 looks along +z with +y up, so
# image-right = cross(forward, up) = cross(+z, +y) = -x: the x ~ 0 wall is on
# the image RIGHT (green) and the x ~ 550 wall on the image LEFT (red).
CB_X0_WALL = [(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)]
CB_X550_WALL = [(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2), (556.0, 548.8, 0.0)]
# The measured light sits in the ceiling plane (y = 548.8); it is lowered by
# 0.1 mm to y = 548.7 so it does not coincide with the ceiling.
CB_LIGHT_Y = 548.7
CB_LIGHT = [(343.0, CB_LIGHT_Y, 227.0), (343.0, CB_LIGHT_Y, 332.0),
            (213.0, CB_LIGHT_Y, 332.0), (213.0, CB_LIGHT_Y, 227.0)]
CB_SHORT_BLOCK = [
    [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
    [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
    [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
    [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
    [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
]
CB_TALL_BLOCK = [
    [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
    [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
    [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
    [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
    [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
]
CB_CAMERA_EYE = (278.0, 273.0, -800.0)
CB_FOCAL = 0.035    # metres
CB_FILM = 0.025     # metres, square film


def oriented_quads(quads, want):
    """Triangulate quads (v0,v1,v2,v3) -> (0,1,2),(0,2,3), reversing a quad's
    winding where needed so every triangle's normal cross(v1-v0, v2-v0) points
    along want(quad) (a direction vector). Returns (positions, triangles)."""
    positions, triangles = [], []
    for q in quads:
        d = want(q)
        n = cross(sub(q[1], q[0]), sub(q[2], q[0]))
        if dot(n, d) < 0:
            q = [q[0], q[3], q[2], q[1]]
        base = len(positions)
        positions += [mm(v) for v in q]
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


def cornell_box():
    g = Gltf("Measured Cornell box (Cornell PCG data, metres) with the measured camera; "
             "red wall left, green right, one downward-facing area light.")
    white = g.material("white", base=(0.725, 0.71, 0.68))
    red = g.material("red", base=(0.63, 0.065, 0.05))
    green = g.material("green", base=(0.14, 0.45, 0.091))
    # Radiance (17, 12, 4) = emissiveFactor (1, 12/17, 4/17) x strength 17.
    light = g.material("light", base=(0.0, 0.0, 0.0),
                       emission=((1.0, 12.0 / 17.0, 4.0 / 17.0), 17.0))

    up, down = (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)
    fixed = lambda d: (lambda q: d)
    parts = [
        ("floor", [CB_FLOOR], fixed(up), white),
        ("ceiling", [CB_CEILING], fixed(down), white),
        ("back wall", [CB_BACK], fixed((0.0, 0.0, -1.0)), white),
        ("left wall (red)", [CB_X550_WALL], fixed((-1.0, 0.0, 0.0)), red),
        ("right wall (green)", [CB_X0_WALL], fixed((1.0, 0.0, 0.0)), green),
    ]
    for name, faces in (("short block", CB_SHORT_BLOCK), ("tall block", CB_TALL_BLOCK)):
        c = centroid([v for f in faces for v in f])
        parts.append((name, faces, lambda q, c=c: sub(centroid(q), c), white))
    parts.append(("light", [CB_LIGHT], fixed(down), light))

    for name, quads, want, mat in parts:
        pos, tris = oriented_quads(quads, want)
        mesh = g.mesh(name, pos, tris, mat)
        g.add("nodes", {"name": name, "mesh": mesh})

    # glTF cameras look down -z; a 180 degree turn about +y makes that +z and
    # keeps +y up. Image-right is then the camera's local +x -> world -x.
    g.camera("camera", yfov=2.0 * math.atan(CB_FILM / 2.0 / CB_FOCAL), aspect=1.0,
             znear=0.01, translation=mm(CB_CAMERA_EYE), rotation=(0.0, 1.0, 0.0, 0.0))
    g.render((512, 512), 64, -1, 0, "ptnee")
    return g


# --------------------------------------------------------------------------
# Sphere Cornell box (after Kevin Beason's smallpt), camera at the origin.
def sphere_cornell(variant):
    descriptions = {
        None: "Box of nine analytic spheres after smallpt: red/green walls, two diffuse "
              "spheres, spherical cap light.",
        "mirror": "smallpt-style sphere box with the left sphere a perfect mirror.",
        "glass": "smallpt-style sphere box with the right sphere clear glass (IOR 1.5).",
    }
    g = Gltf(descriptions[variant])
    g.use("TESSERA_sphere", required=True)
    green = g.material("green", base=(0.0, 0.8, 0.0))
    red = g.material("red", base=(0.8, 0.0, 0.0))
    grey = g.material("grey", base=(0.8, 0.8, 0.8))
    white = g.material("white", base=(0.9, 0.9, 0.9))
    light = g.material("light", base=(0.0, 0.0, 0.0), emission=((1.0, 1.0, 0.75), 12.0))
    left_mat, right_mat = white, white
    if variant == "mirror":
        left_mat = g.material("mirror", base=(0.999, 0.999, 0.999), metallic=1.0, roughness=0.0)
    elif variant == "glass":
        right_mat = g.material("glass", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.0,
                               transmission=1.0, ior=1.5)

    # (name, centre literal, centre formula, radius, material). Centres are
    # written as decimal literals so the JSON is exact-looking; each is checked
    # against the formula it stands for.
    spheres = [
        ("right wall", (10049.0, 21.2, -149.0), (1e4 + 49, 21.2, -149), 1e4, green),
        ("left wall", (-10049.0, 21.2, -149.0), (-1e4 - 49, 21.2, -149), 1e4, red),
        ("front wall", (0.0, 21.2, 10010.6), (0, 21.2, 1e4 + 10.6), 1e4, grey),
        ("back wall", (0.0, 21.2, -10230.6), (0, 21.2, -1e4 - 230.6), 1e4, grey),
        ("ceiling", (0.0, 10039.6, -149.0), (0, 1e4 + 39.6, -149), 1e4, grey),
        ("floor", (0.0, -10042.0, -149.0), (0, -1e4 - 42, -149), 1e4, grey),
        ("left sphere", (-23.0, -25.5, -183.6), (-23, -25.5, -183.6), 16.5, left_mat),
        ("right sphere", (23.0, -25.5, -152.6), (23, -25.5, -152.6), 16.5, right_mat),
        ("light", (0.0, 639.39, -149.0), (0, 639.6 - 0.21, -149), 600.0, light),
    ]
    for name, centre, formula, radius, mat in spheres:
        for a, b in zip(centre, formula):
            assert abs(a - b) < 1e-9, (name, centre, formula)
        g.add("nodes", {"name": name, "translation": list(centre),
                        "extensions": {"TESSERA_sphere": {"radius": radius, "material": mat}}})

    g.camera("camera", yfov=2.0 * math.atan(0.5135), aspect=4.0 / 3.0, znear=0.1)
    g.render((640, 480), 64, -1, 0, "ptnee")
    return g


# --------------------------------------------------------------------------
# Validation of what was produced (re-parsed from text / bytes)
def validate(name, text, binary):
    doc = json.loads(text)
    asset = doc["asset"]
    assert asset["version"] == "2.0" and asset["generator"] == GENERATOR, name
    assert isinstance(asset["extras"]["description"], str) and "\n" not in asset["extras"]["description"]
    used = set(doc.get("extensionsUsed", []))
    required = set(doc.get("extensionsRequired", []))
    assert required <= used and required <= {"TESSERA_sphere"}, name

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
        if "rotation" in node:
            q = node["rotation"]
            assert abs(sum(x * x for x in q) - 1.0) < 1e-9
    assert sorted(doc["scenes"][doc["scene"]]["nodes"]) == list(range(len(nodes)))
    assert sum(1 for n in nodes if "camera" in n) == 1
    return doc


# --------------------------------------------------------------------------
def readme(entries):
    lines = [
        "# Scenes",
        "",
        "Generated by `tools/make_scenes.py` (Python 3, standard library only). Do not edit",
        "the `.gltf`/`.bin` files by hand; change the script and regenerate:",
        "",
        "```sh",
        "python3 tools/make_scenes.py          # rewrite everything under scenes/",
        "python3 tools/make_scenes.py --check  # verify the committed files are up to date",
        "```",
        "",
        "| Scene | Description |",
        "| --- | --- |",
    ]
    for path, desc in entries:
        lines.append("| [`%s`](%s) | %s |" % (path, path, desc))
    lines += [
        "",
        "All scenes are glTF 2.0. Tessera-specific data uses these extensions:",
        "",
        "- `TESSERA_render` (root): default `resolution`, `spp`, `maxDepth` (-1 = unlimited,",
        "  Russian roulette only), `seed`, `integrator`.",
        "- `TESSERA_sphere` (node): analytic sphere with `radius` and `material`, centred at the",
        "  node's translation. Listed in `extensionsRequired`.",
        "",
        "Emitters use `emissiveFactor` x `KHR_materials_emissive_strength`; emission is",
        "one-sided (counter-clockwise front face) unless the material is `doubleSided`.",
        "",
    ]
    return "\n".join(lines)


def build():
    """Return {relative path: bytes} for every generated file."""
    files = {}
    entries = []

    g = cornell_box()
    text, binary = g.finish("cornell-box.bin")
    validate("cornell-box.gltf", text, binary)
    files["cornell-box/cornell-box.gltf"] = text.encode()
    files["cornell-box/cornell-box.bin"] = binary
    entries.append(("cornell-box/cornell-box.gltf", g.doc["asset"]["extras"]["description"]))

    for variant, fname in ((None, "sphere-cornell.gltf"), ("mirror", "sphere-cornell-mirror.gltf"),
                           ("glass", "sphere-cornell-glass.gltf")):
        g = sphere_cornell(variant)
        text, binary = g.finish()
        validate(fname, text, binary)
        files["sphere-cornell/" + fname] = text.encode()
        entries.append(("sphere-cornell/" + fname, g.doc["asset"]["extras"]["description"]))

    files["README.md"] = readme(entries).encode()
    return files


def main(argv):
    check = "--check" in argv[1:]
    unknown = [a for a in argv[1:] if a != "--check"]
    if unknown:
        print(__doc__)
        return 2
    stale = []
    for rel, data in sorted(build().items()):
        path = os.path.join(SCENES, rel)
        if check:
            try:
                with open(path, "rb") as f:
                    if f.read() != data:
                        stale.append(rel)
            except FileNotFoundError:
                stale.append(rel)
            continue
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
        print("wrote scenes/%s (%d bytes)" % (rel, len(data)))
    if check:
        if stale:
            print("out of date (run python3 tools/make_scenes.py): " + ", ".join(stale))
            return 1
        print("scenes/ is up to date")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
