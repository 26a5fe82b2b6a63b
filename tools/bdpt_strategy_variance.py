#!/usr/bin/python3
"""Which BDPT strategies carry a render's error: each strategy's share of the variance.

    tools/bdpt_strategy_variance.py SCENE.gltf --ref REF.exr [--spp N] [--seeds K] [--tessera BIN]
                                    [--out DIR] [--top M] [-- RENDER_ARGS...]

Renders SCENE K times with `tessera render --integrator bdpt --bdpt-strategies` (seeds 1..K, at
the reference's resolution unless RENDER_ARGS, appended after `--`, give one; e.g. `--max-depth 9`;
the strategy images cover paths up to --max-depth + 2 vertices, 5 if unlimited), then for every
strategy (s, t) takes the variance across the K seeds of its weighted image, per pixel and
channel, divided by (r² + 0.01) with r the reference (the weights of `tessera compare`'s relMSE),
averaged over the image: its share of the render's expected relMSE (the variance part). The
strategies' shares add up to the whole render's variance when the strategies' estimates are
uncorrelated; the total render's figure is printed beside their sum to show how far they are.

The variance across K seeds of heavy-tailed strategies (SDS paths that only s = 0 builds) is itself
noisy: use K ≥ 6, and read shares, not digits. Each render costs one extra render per strategy
image (`--bdpt-strategies`), so a small resolution keeps it short.
"""
import argparse
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from exr_io import read_exr  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        k = argv.index("--")
        argv, extra = argv[:k], argv[k + 1:]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--ref", required=True, help="reference EXR at the render's resolution")
    ap.add_argument("--spp", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--tessera", default=os.path.join(ROOT, "build", "src", "tessera"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bdpt-strategy-variance"))
    ap.add_argument("--top", type=int, default=12, help="strategies listed (largest shares first)")
    a = ap.parse_args(argv)
    if a.seeds < 2:
        ap.error("--seeds must be at least 2 (a variance across seeds)")
    for what, path in (("scene", a.scene), ("--ref", a.ref), ("--tessera", a.tessera)):
        if not os.path.isfile(path):
            ap.error("%s: %s is not a file" % (what, path))

    ref = read_exr(a.ref)[0]
    if "--resolution" not in extra:  # render at the reference's size unless told otherwise
        extra += ["--resolution", "%dx%d" % (ref.shape[1], ref.shape[0])]
    weight = 1.0 / (ref ** 2 + 0.01)
    totals, folders = [], []
    for seed in range(1, a.seeds + 1):
        folder = os.path.join(a.out, "seed%d" % seed)
        os.makedirs(folder, exist_ok=True)
        for old in os.listdir(folder):  # a previous run's strategies (another depth) must not count
            if old.startswith("bdpt_") and old.endswith(".exr"):
                os.remove(os.path.join(folder, old))
        image = os.path.join(a.out, "seed%d.exr" % seed)
        cmd = [a.tessera, "render", a.scene, "--integrator", "bdpt", "--spp", str(a.spp), "--seed", str(seed),
               "-o", image, "--no-png", "--quiet", "--bdpt-strategies", folder] + extra
        print("rendering seed %d: %s" % (seed, " ".join(cmd)), file=sys.stderr)
        subprocess.run(cmd, check=True)
        img = read_exr(image)[0]
        if img.shape != ref.shape:
            sys.exit("bdpt_strategy_variance.py: %s is %s, the reference %s: give the reference's resolution"
                     % (image, img.shape[:2], ref.shape[:2]))
        totals.append(img)
        folders.append(folder)

    def relvar(stack):
        return float(np.mean(np.var(np.stack(stack), axis=0, ddof=1) * weight))

    total = relvar(totals)
    # One strategy at a time (K images in memory, not K times every strategy's).
    names = sorted(set.intersection(*(set(n for n in os.listdir(f) if n.endswith("_weighted.exr")) for f in folders)))
    rows = []
    for name in names:
        stack = [read_exr(os.path.join(f, name))[0] for f in folders]
        rows.append((relvar(stack), name[len("bdpt_"):-len("_weighted.exr")], float(np.mean(stack))))
    rows.sort(reverse=True)
    summed = sum(r[0] for r in rows)
    print("%s, %d spp, %d seeds: variance part of relMSE %.4g (the strategies' sum %.4g)" % (
        os.path.basename(a.scene), a.spp, a.seeds, total, summed))
    print("| strategy | variance (relMSE units) | share of the sum | mean of its image |")
    print("|---|---|---|---|")
    for v, k, m in rows[:a.top]:
        print("| %s | %.4g | %.1f%% | %.4g |" % (k.replace("_", ", "), v, 100.0 * v / summed if summed > 0 else 0.0, m))
    by_kind = {"s = 0 (camera sub-path hits the light)": 0.0, "t = 1 (light tracing)": 0.0, "s = 1 (next-event)": 0.0,
               "s, t >= 2 (connections)": 0.0}
    for v, k, _ in rows:
        s, t = (int(x[1:]) for x in k.split("_"))
        kind = list(by_kind)[0 if s == 0 else 1 if t == 1 else 2 if s == 1 else 3]
        by_kind[kind] += v
    print("by kind: " + "; ".join("%s %.1f%%" % (k, 100.0 * v / summed if summed > 0 else 0.0) for k, v in by_kind.items()))


if __name__ == "__main__":
    main()
