#!/usr/bin/env python3
"""Writes tests/corpus/malformed-mesh: PLY and OBJ files that the mesh loader must refuse with a
one-line error naming file, element/row or line, and problem (tests/test_robust_mesh_loader.cpp).
Run from anywhere: python3 tests/corpus/make_malformed_meshes.py
Files named fuzz-* are inputs found by tools/fuzz.sh, kept as found (not written here)."""
import gzip, os, struct

out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "malformed-mesh")
os.makedirs(out, exist_ok=True)

def header(fmt, nv, nf, vprops="property float x\nproperty float y\nproperty float z\n",
           fprop="property list uchar int vertex_indices\n"):
    return (f"ply\nformat {fmt} 1.0\nelement vertex {nv}\n{vprops}element face {nf}\n{fprop}end_header\n").encode()

QUAD_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
def ascii_body(verts, faces):
    s = "".join(f"{x} {y} {z}\n" for x, y, z in verts)
    s += "".join(f"{len(f)} " + " ".join(str(i) for i in f) + "\n" for f in faces)
    return s.encode()
def binary_body(verts, faces):
    b = b"".join(struct.pack("<3f", *v) for v in verts)
    b += b"".join(struct.pack("<B", len(f)) + struct.pack(f"<{len(f)}i", *f) for f in faces)
    return b

files = {
    # PLY: truncated data, ASCII and binary
    "truncated-ascii.ply": header("ascii", 4, 2) + ascii_body(QUAD_V, [(0, 1, 2)]),
    "truncated-binary.ply": (header("binary_little_endian", 4, 2) + binary_body(QUAD_V, [(0, 1, 2), (0, 2, 3)]))[:-7],
    # PLY: header problems
    "no-end-header.ply": b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n",
    "no-magic.ply": b"PLX\nformat ascii 1.0\nend_header\n",
    "bad-format.ply": header("binary_middle_endian", 4, 1) + ascii_body(QUAD_V, [(0, 1, 2)]),
    "no-format.ply": header("ascii", 4, 1).replace(b"format ascii 1.0\n", b"") + ascii_body(QUAD_V, [(0, 1, 2)]),
    "negative-count.ply": header("ascii", -3, 1) + ascii_body(QUAD_V, [(0, 1, 2)]),
    "non-numeric-count.ply": header("ascii", "four", 1) + ascii_body(QUAD_V, [(0, 1, 2)]),
    "unknown-type.ply": header("ascii", 4, 1, vprops="property float128 x\nproperty float y\nproperty float z\n")
                        + ascii_body(QUAD_V, [(0, 1, 2)]),
    "float-list-count.ply": header("ascii", 4, 1, fprop="property list float int vertex_indices\n")
                            + ascii_body(QUAD_V, [(0, 1, 2)]),
    "property-before-element.ply": b"ply\nformat ascii 1.0\nproperty float x\nend_header\n",
    "missing-z.ply": header("ascii", 4, 1, vprops="property float x\nproperty float y\n") + b"0 0\n1 0\n1 1\n0 1\n3 0 1 2\n",
    "no-faces.ply": b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
    # PLY: allocation bombs (counts the data cannot hold; memory limit)
    "vertex-count-bomb.ply": header("binary_little_endian", 4000000000, 1) + binary_body(QUAD_V, [(0, 1, 2)]),
    "face-count-bomb.ply": header("ascii", 4, 1 << 60) + ascii_body(QUAD_V, [(0, 1, 2)]),
    "list-length-bomb.ply": header("binary_little_endian", 4, 1, fprop="property list uint int vertex_indices\n")
                            + binary_body(QUAD_V, []) + struct.pack("<I", 0xffffffff) + struct.pack("<3i", 0, 1, 2),
    # PLY: bad values
    "index-out-of-range.ply": header("ascii", 4, 2) + ascii_body(QUAD_V, [(0, 1, 2), (0, 2, 4)]),
    "index-huge-binary.ply": header("binary_little_endian", 4, 1, fprop="property list uchar uint vertex_indices\n")
                             + binary_body(QUAD_V, []) + struct.pack("<B3I", 3, 0, 1, 0xfffffff0),
    "negative-index.ply": header("ascii", 4, 1) + ascii_body(QUAD_V, [(0, -1, 2)]),
    "fractional-index.ply": header("ascii", 4, 1) + ascii_body(QUAD_V, []) + b"3 0 1.5 2\n",
    "two-vertex-face.ply": header("ascii", 4, 1) + ascii_body(QUAD_V, [(0, 1)]),
    "nan-vertex.ply": header("ascii", 4, 1) + b"0 0 0\n1 nan 0\n1 1 0\n0 1 0\n3 0 1 2\n",
    "inf-vertex-binary.ply": header("binary_little_endian", 4, 1)
                             + binary_body([(0, 0, 0), (1, 0, 0), (1, float("inf"), 0), (0, 1, 0)], [(0, 1, 2)]),
    "overflow-vertex.ply": header("ascii", 4, 1) + b"0 0 0\n1 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n",
    "not-a-number.ply": header("ascii", 4, 1) + b"0 0 0\n1 zero 0\n1 1 0\n0 1 0\n3 0 1 2\n",
    # gzip: corrupt and truncated streams
    "bad-gzip.ply.gz": b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03" + bytes(range(200, 256)) * 4,
    "truncated-gzip.ply.gz": gzip.compress(header("ascii", 4, 2) + ascii_body(QUAD_V, [(0, 1, 2), (0, 2, 3)]) * 50)[:120],
    # OBJ
    "index-out-of-range.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nf 1 3 4\n",
    "index-huge.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4294967297\n",
    "relative-before-start.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf -1 -2 -4\n",
    "zero-index.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n",
    "bad-face-index.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 two 3\n",
    "two-vertex-face.obj": b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2\n",
    "nan-vertex.obj": b"v 0 0 0\nv 1 nan 0\nv 1 1 0\nf 1 2 3\n",
    "overflow-vertex.obj": b"v 0 0 0\nv 1 1e39 0\nv 1 1 0\nf 1 2 3\n",
    "short-vertex.obj": b"v 0 0 0\nv 1 0\nv 1 1 0\nf 1 2 3\n",
    "no-faces.obj": b"# only vertices\nv 0 0 0\nv 1 0 0\nv 1 1 0\n",
}
for name, data in files.items():
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)
print(f"{len(files)} files in {out}")
