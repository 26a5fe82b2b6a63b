#!/usr/bin/env python3
"""Writes the texture and image cases of tests/corpus/malformed (scenes named image-*, texture-*,
sampler-*, texcoord-*, alpha-*, with the image files they reference) and the fuzzer's valid
textured seeds in tests/fuzz/seeds (a GLB that embeds a PNG, a .gltf with a data-URI PNG).
Every malformed scene must make `tessera render` exit 2 with one line naming the file, the material
and texture, and the problem (tests/test_malformed_corpus.cpp).
Run from anywhere: python3 tests/corpus/make_malformed_images.py  (output is deterministic)."""
import base64, copy, json, os, struct, zlib

here = os.path.dirname(os.path.abspath(__file__))
out = os.path.join(here, "malformed")
seeds = os.path.join(here, "..", "fuzz", "seeds")
os.makedirs(out, exist_ok=True)
os.makedirs(seeds, exist_ok=True)


def png(width, height, rows, colour_type=2, ihdr_size=None):
    """An 8-bit PNG; `rows` is the raw pixel bytes, row after row. `ihdr_size` overrides the
    size the header claims (the pixel data stays what `rows` holds)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
    w, h = ihdr_size or (width, height)
    stride = len(rows) // height
    raw = b"".join(b"\0" + rows[y * stride:(y + 1) * stride] for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checker(n=8):
    return bytes(v for y in range(n) for x in range(n) for v in ((230, 40, 40) if (x + y) % 2 else (30, 30, 200)))


CHECKER = png(8, 8, checker())

# A unit quad facing +z: positions, TEXCOORD_0, indices, in one data-URI buffer.
positions = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
uvs = struct.pack("<8f", 0, 1, 1, 1, 1, 0, 0, 0)
indices = struct.pack("<6I", 0, 1, 2, 0, 2, 3)
buffer = positions + uvs + indices


def scene(image_uri="checker.png", texture=None, material=None, primitive_attrs=None, extra=None):
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": [{"attributes": primitive_attrs or {"POSITION": 0, "TEXCOORD_0": 1},
                                    "indices": 2, "material": 0}]}],
        "materials": [material or {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [texture if texture is not None else {"source": 0}],
        "images": [{"uri": image_uri}],
        "buffers": [{"byteLength": len(buffer),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 80, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"}],
    }
    if extra:
        extra(doc)
    return doc


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f, separators=(", ", ": "))


def glb(doc, binary):
    doc = copy.deepcopy(doc)
    doc["buffers"] = [{"byteLength": len(binary)}]
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = struct.pack("<I", len(text)) + b"JSON" + text + struct.pack("<I", len(binary)) + b"BIN\0" + binary
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def glb_with_embedded_png(image_length=None):
    """The quad as a GLB whose image lives in a buffer view; `image_length` overrides that view's
    byteLength (to run it past the buffer's end)."""
    binary = buffer + CHECKER
    doc = scene()
    doc["bufferViews"].append({"buffer": 0, "byteOffset": len(buffer), "byteLength": image_length or len(CHECKER)})
    doc["images"] = [{"bufferView": 3, "mimeType": "image/png"}]
    return glb(doc, binary)


files = {
    # image bytes that do not decode
    "image-not-an-image.gltf": scene("not-an-image.png"),
    "image-truncated.gltf": scene("truncated.png"),
    "image-header-too-large.gltf": scene("huge-header.png"),
    "image-data-uri-garbage.gltf": scene("data:image/png;base64," + base64.b64encode(b"GIF89a, or so it says").decode()),
    # where the image is
    "image-missing-file.gltf": scene("missing.png"),
    "image-outside-folder.gltf": scene("../make_malformed_images.py"),
    "image-absolute-path.gltf": scene("/etc/passwd"),
    # indices
    "texture-index-out-of-range.gltf": scene(material={"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 7}}}),
    "texture-image-index-out-of-range.gltf": scene(texture={"source": 3}),
    "texture-without-source.gltf": scene(texture={}),
    "sampler-index-out-of-range.gltf": scene(texture={"source": 0, "sampler": 2}),
    "sampler-bad-wrap-mode.gltf": scene(texture={"source": 0, "sampler": 0},
                                        extra=lambda d: d.update(samplers=[{"wrapS": 1234}])),
    "texcoord-set-unsupported.gltf": scene(material={"name": "m", "normalTexture": {"index": 0, "texCoord": 2}}),
    "texcoord-attribute-missing.gltf": scene(material={"name": "m", "emissiveFactor": [1, 1, 1],
                                                       "emissiveTexture": {"index": 0, "texCoord": 1}}),
    "texture-transform-bad-scale.gltf": scene(material={"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {
        "index": 0, "extensions": {"KHR_texture_transform": {"scale": [1, "two"]}}}}}),
    "texture-extension-index-out-of-range.gltf": scene(material={"name": "m", "extensions": {
        "KHR_materials_specular": {"specularColorTexture": {"index": 5}}}}),
    "alpha-mode-unknown.gltf": scene(material={"name": "m", "alphaMode": "CUTOUT"}),
}
for name, doc in files.items():
    write_json(os.path.join(out, name), doc)

images = {
    "checker.png": CHECKER,
    "not-an-image.png": b"this is a text file with a .png name\n",
    "truncated.png": CHECKER[: len(CHECKER) * 3 // 5],
    # The header claims 200000 x 200000 RGB (40 G pixels); the data is one small row.
    "huge-header.png": png(4, 1, bytes(12), ihdr_size=(200000, 200000)),
}
for name, data in images.items():
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)

# The embedded image's view runs past the end of the GLB's buffer.
with open(os.path.join(out, "image-bufferview-past-buffer.glb"), "wb") as f:
    f.write(glb_with_embedded_png(image_length=len(CHECKER) + 4096))

# Valid seeds for tools/fuzz.sh: image decoding reached through a GLB buffer view and a data URI;
# checker.png is also the image file the fuzz target writes next to its scene.
with open(os.path.join(seeds, "checker.png"), "wb") as f:
    f.write(CHECKER)
with open(os.path.join(seeds, "textured-quad.glb"), "wb") as f:
    f.write(glb_with_embedded_png())
write_json(os.path.join(seeds, "textured-quad-data-uri.gltf"),
           scene("data:image/png;base64," + base64.b64encode(CHECKER).decode()))
