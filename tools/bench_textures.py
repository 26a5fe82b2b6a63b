#!/usr/bin/env python3
"""Texture cost: samples/s of a scene of textured glTF assets against the same assets untextured.

Usage:
    python3 tools/bench_textures.py [SCENE] [--runs N] [--spp S] [--resolution WxH]
                                    [--integrator NAME] [--threads T]

SCENE (default scenes/webxr/webxr-controllers.gltf) names its assets by TESSERA_asset_gltf. For the
untextured runs each of those GLBs is rewritten into a temporary asset folder put first on
TESSERA_ASSETS, so the same scene file resolves to the copies: every texture slot of every material
is removed and its factor multiplied by the texture's mean (linear mean for the sRGB slots: base
colour, emissive, specular colour; the G and B means for metallic-roughness), so the light transport,
and with it the path lengths, stays close to the textured scene's and the difference in samples/s
is the cost of the texture lookups (and normal mapping, which has no factor to fold into). The
images, textures and samplers arrays are dropped, so no image is decoded either.

The renders alternate (textured, untextured, textured, ...) so that a change of load on a shared
machine hits both alike; each prints `tessera render --json`'s samples_per_second. The summary gives
the mean and standard deviation of each, and the cost ratio untextured / textured samples/s (issue 16
asks for <= 1.5) with its spread over the run pairs. Exit 0 unless a render fails.
Needs numpy and OpenImageIO's Python module (tools/bootstrap.sh --install study; called when missing).
"""

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import study_deps  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
TESSERA = os.path.join(ROOT, "build", "src", "tessera")

# Material texture slots: (path of the texture info inside the material, path of its factor, how the
# texture's mean folds into the factor).
SRGB, LINEAR_RGB, MR, CHANNEL_R, CHANNEL_A, NONE = "srgb", "linear", "mr", "r", "a", "none"
SLOTS = [
    (("pbrMetallicRoughness", "baseColorTexture"), ("pbrMetallicRoughness", "baseColorFactor"), SRGB),
    (("pbrMetallicRoughness", "metallicRoughnessTexture"), None, MR),
    (("emissiveTexture",), ("emissiveFactor",), SRGB),
    (("normalTexture",), None, NONE),
    (("occlusionTexture",), None, NONE),
    (("extensions", "KHR_materials_transmission", "transmissionTexture"),
     ("extensions", "KHR_materials_transmission", "transmissionFactor"), CHANNEL_R),
    (("extensions", "KHR_materials_specular", "specularTexture"),
     ("extensions", "KHR_materials_specular", "specularFactor"), CHANNEL_A),
    (("extensions", "KHR_materials_specular", "specularColorTexture"),
     ("extensions", "KHR_materials_specular", "specularColorFactor"), SRGB),
]
DEFAULT_FACTORS = {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "emissiveFactor": [0.0, 0.0, 0.0],
                   "transmissionFactor": 0.0, "specularFactor": 1.0, "specularColorFactor": [1.0, 1.0, 1.0]}


def read_glb(path):
    with open(path, "rb") as f:
        data = f.read()
    magic, version, _ = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2, path
    json_len, json_type = struct.unpack_from("<I4s", data, 12)
    assert json_type == b"JSON"
    doc = json.loads(data[20:20 + json_len])
    rest = data[20 + json_len:]
    binary = b""
    if rest:
        bin_len, bin_type = struct.unpack_from("<I4s", rest, 0)
        assert bin_type == b"BIN\0"
        binary = rest[8:8 + bin_len]
    return doc, binary


def write_glb(path, doc, binary):
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary = binary + b"\0" * (-len(binary) % 4)
    chunks = struct.pack("<I4s", len(text), b"JSON") + text
    if binary:
        chunks += struct.pack("<I4s", len(binary), b"BIN\0") + binary
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def image_mean(doc, binary, texture_index, tmpdir):
    """Per-channel mean (RGBA, 0..1, encoded values) of the image behind textures[texture_index]."""
    import numpy as np
    import OpenImageIO as oiio
    image = doc["images"][doc["textures"][texture_index]["source"]]
    view = doc["bufferViews"][image["bufferView"]]
    data = binary[view.get("byteOffset", 0):view.get("byteOffset", 0) + view["byteLength"]]
    ext = {"image/png": ".png", "image/jpeg": ".jpg"}.get(image.get("mimeType"), ".img")
    path = os.path.join(tmpdir, "texture" + ext)
    with open(path, "wb") as f:
        f.write(data)
    pixels = oiio.ImageBuf(path).get_pixels(oiio.FLOAT)
    if pixels is None or pixels.size == 0:
        raise RuntimeError("cannot decode texture %d" % texture_index)
    pixels = pixels.reshape(-1, pixels.shape[-1])
    if pixels.shape[1] < 4:
        pixels = np.concatenate([pixels, np.ones((pixels.shape[0], 4 - pixels.shape[1]))], axis=1)
    return pixels


def srgb_to_linear(v):
    import numpy as np
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def get(obj, path):
    for k in path:
        if not isinstance(obj, dict) or k not in obj:
            return None
        obj = obj[k]
    return obj


def put(obj, path, value):
    for k in path[:-1]:
        obj = obj.setdefault(k, {})
    obj[path[-1]] = value


def strip_textures(doc, binary, tmpdir):
    """Remove every texture of every material, folding each texture's mean into its factor."""
    removed = 0
    for m in doc.get("materials", []):
        for tex_path, factor_path, kind in SLOTS:
            info = get(m, tex_path)
            if info is None:
                continue
            removed += 1
            if kind != NONE:
                pixels = image_mean(doc, binary, info["index"], tmpdir)
                if kind == SRGB:
                    mean = srgb_to_linear(pixels[:, :3]).mean(axis=0).tolist()
                    mean.append(float(pixels[:, 3].mean()))
                elif kind == MR:
                    g, b = pixels[:, 1].mean(), pixels[:, 2].mean()
                    pbr = m.setdefault("pbrMetallicRoughness", {})
                    pbr["roughnessFactor"] = float(pbr.get("roughnessFactor", 1.0) * g)
                    pbr["metallicFactor"] = float(pbr.get("metallicFactor", 1.0) * b)
                else:
                    mean = float(pixels[:, 0 if kind == CHANNEL_R else 3].mean())
                if kind != MR:
                    factor = get(m, factor_path)
                    if factor is None:
                        factor = DEFAULT_FACTORS[factor_path[-1]]
                    if isinstance(factor, list):
                        factor = [float(f * mean[i]) for i, f in enumerate(factor)]
                    else:
                        factor = float(factor * mean)
                    put(m, factor_path, factor)
            del get(m, tex_path[:-1])[tex_path[-1]]  # get(m, ()) is m itself
    for key in ("textures", "images", "samplers"):
        doc.pop(key, None)
    return removed


def asset_roots():
    roots = [r for r in os.environ.get("TESSERA_ASSETS", "").split(":") if r]
    cache = os.environ.get("TESSERA_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "tessera")
    return roots + [cache]


def scene_assets(scene):
    with open(scene) as f:
        doc = json.load(f)
    return sorted({n["extensions"]["TESSERA_asset_gltf"]["asset"] for n in doc.get("nodes", [])
                   if "TESSERA_asset_gltf" in n.get("extensions", {})})


def render(scene, args, env):
    cmd = [TESSERA, "render", scene, "--spp", str(args.spp), "--resolution", args.resolution,
           "--threads", str(args.threads), "--seed", "1", "--no-png", "--quiet", "--json",
           "-o", os.path.join(env["BENCH_TMP"], "out.exr")]
    if args.integrator:
        cmd += ["--integrator", args.integrator]
    result = subprocess.run(cmd, cwd=ROOT, env=env, check=True, capture_output=True, text=True)
    return json.loads(result.stdout.strip().splitlines()[-1])["samples_per_second"]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default="scenes/webxr/webxr-controllers.gltf")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--spp", type=int, default=8)
    p.add_argument("--resolution", default="320x240")
    p.add_argument("--integrator", default=None, help="default: the scene's")
    p.add_argument("--threads", type=int, default=2)
    args = p.parse_args()
    study_deps.ensure_packages(("numpy", "OpenImageIO"))
    assets = scene_assets(os.path.join(ROOT, args.scene))
    if not assets:
        sys.exit("bench_textures.py: %s names no TESSERA_asset_gltf asset" % args.scene)
    with tempfile.TemporaryDirectory(prefix="tessera-bench-textures-") as tmp:
        plain = os.path.join(tmp, "untextured")
        for name in assets:
            source = next((os.path.join(r, name) for r in asset_roots() if os.path.isfile(os.path.join(r, name))), None)
            if source is None:
                sys.exit("bench_textures.py: asset %s not found: run tools/fetch_assets.sh" % name)
            doc, binary = read_glb(source)
            n = strip_textures(doc, binary, tmp)
            write_glb(os.path.join(plain, name), doc, binary)
            print("%s: %d texture slot(s) folded into factors" % (name, n))
        env_tex = dict(os.environ, BENCH_TMP=tmp)
        env_plain = dict(env_tex, TESSERA_ASSETS=":".join([plain] + asset_roots()))
        textured, untextured = [], []
        for i in range(args.runs):
            textured.append(render(args.scene, args, env_tex))
            untextured.append(render(args.scene, args, env_plain))
            print("run %d: textured %.0f samples/s, untextured %.0f samples/s, cost ratio %.3f"
                  % (i + 1, textured[-1], untextured[-1], untextured[-1] / textured[-1]))
    ratios = [u / t for t, u in zip(textured, untextured)]
    sd = (lambda xs: statistics.stdev(xs) if len(xs) > 1 else 0.0)
    print("scene %s, %s, %d spp, %d threads, %d runs each" % (args.scene, args.resolution, args.spp, args.threads, args.runs))
    print("textured:   %.0f +- %.0f samples/s" % (statistics.mean(textured), sd(textured)))
    print("untextured: %.0f +- %.0f samples/s" % (statistics.mean(untextured), sd(untextured)))
    print("cost ratio untextured/textured samples/s: %.3f (pairs: mean %.3f, sd %.3f, min %.3f, max %.3f; issue 16 asks <= 1.5)"
          % (statistics.mean(untextured) / statistics.mean(textured), statistics.mean(ratios), sd(ratios),
             min(ratios), max(ratios)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
