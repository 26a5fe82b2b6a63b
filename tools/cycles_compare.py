#!/usr/bin/python3
"""Tessera against Blender's Cycles at equal time on the same glTF scene, one thread each.

    tools/cycles_compare.py                      # Cornell box, 256x256, 16-1024 spp, 3 repeats -> markdown table
    tools/cycles_compare.py --spps 16 64 --ref-spp 8192 --out out/cycles

Packages: `bash tools/bootstrap.sh --install cycles` (Debian's blender). Steps:
 1. A Cycles reference at --ref-spp: the mean of --ref-spp / --ref-chunk renders of their own seeds
    (tools/cycles_render.py; cached in --out, keyed by their settings), rendered with --ref-threads
    threads (threads do not change what Cycles computes).
 2. For each spp, interleaved: Tessera ptnee with each --samplers and Cycles, each with one thread,
    --repeats times; seconds are the render alone (Tessera's --json "seconds", Cycles' render
    operator), relMSE is `tessera compare` against the reference (mean over pixels and RGB of
    (x - r)^2 / (r^2 + 0.01)); each render of a repeat has its own seed. The reference comes after
    these renders, so that it can be rendered alongside them (--ref-existing then takes its chunks).
 3. The means check: Tessera ptnee at the largest spp against the reference, per channel.
Prints a markdown table (median seconds and mean relMSE over repeats, and relMSE x seconds, the
inverse efficiency: lower is better at equal time) and writes it with every run to --out.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def parse(argv):
    p = argparse.ArgumentParser(prog="tools/cycles_compare.py", description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "cornell-box", "cornell-box.gltf"))
    p.add_argument("--resolution", default="256x256")
    p.add_argument("--spps", type=int, nargs="+", default=[16, 64, 256, 1024])
    p.add_argument("--samplers", nargs="+", default=["sobol", "independent"])
    p.add_argument("--ref-spp", type=int, default=8192)
    p.add_argument("--ref-resolution", help="the reference chunks' resolution, an integer multiple of --resolution "
                                            "(box-downsampled: exact for box-filtered pixels); default --resolution")
    p.add_argument("--ref-chunk", type=int, default=2048, help="the reference is the mean of renders of this many spp")
    p.add_argument("--ref-threads", type=int, default=2)
    p.add_argument("--ref-existing", action="store_true",
                   help="render no reference chunk: use the mean of the chunks already in --out (at least one)")
    p.add_argument("--repeats", type=int, default=3, help="renders per renderer and spp, interleaved, each with its own seed")
    p.add_argument("--out", default=os.path.join(ROOT, "out", "cycles"))
    p.add_argument("--score-only", action="store_true",
                   help="render nothing: score the renders listed in --out's runs file (written before scoring)")
    p.add_argument("--blender", default="blender")
    p.add_argument("--tessera", default=os.path.join(os.environ.get("TESSERA_BUILD", os.path.join(ROOT, "build")), "src", "tessera"))
    return p.parse_args(argv)


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def cycles(a, out, spp, seed, threads, resolution=None):
    cmd = [a.blender, "-b", "--factory-startup", "-noaudio", "-P", os.path.join(HERE, "cycles_render.py"), "--",
           a.scene, out, "--spp", str(spp), "--seed", str(seed), "--resolution", resolution or a.resolution, "--threads", str(threads)]
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines = [l for l in r.stdout.splitlines() if l.startswith("cycles-json ")]
    if r.returncode != 0 or not lines or not os.path.isfile(out):
        sys.exit(f"cycles_compare: Cycles failed ({' '.join(cmd)}):\n{r.stdout[-3000:]}")
    j = json.loads(lines[-1][len("cycles-json "):])
    j["command"] = " ".join(cmd)
    return j


def tessera(a, out, spp, seed, sampler):
    cmd = [a.tessera, "render", a.scene, "-o", out, "--no-png", "--quiet", "--json", "--integrator", "ptnee",
           "--spp", str(spp), "--seed", str(seed), "--threads", "1", "--resolution", a.resolution, "--sampler", sampler]
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"cycles_compare: tessera failed ({' '.join(cmd)}):\n{r.stderr}")
    j = json.loads([l for l in r.stdout.splitlines() if l.startswith("{")][-1])
    j["command"] = " ".join(cmd)
    return j


def compare(a, test, ref):
    r = subprocess.run([a.tessera, "compare", test, ref, "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"cycles_compare: compare failed: {r.stderr}")
    return json.loads(r.stdout.strip().splitlines()[-1])


def reference(a, stem):
    """The mean of the reference chunks (rendering the missing ones unless --ref-existing)."""
    import numpy as np
    import OpenImageIO as oiio
    chunks = []
    for k in range(max(1, a.ref_spp // a.ref_chunk)):
        path = os.path.join(a.out, f"{stem}-cycles-ref-{a.ref_resolution}-{a.ref_chunk}spp-seed{1001 + k}.exr")
        if not os.path.isfile(path) and not a.ref_existing:
            log(f"cycles_compare: reference chunk {path} ({a.ref_chunk} spp, {a.ref_threads} threads)")
            t0 = time.time()
            cycles(a, path + ".tmp.exr", a.ref_chunk, 1001 + k, a.ref_threads, a.ref_resolution)
            os.replace(path + ".tmp.exr", path)
            log(f"  done in {time.time() - t0:.0f} s")
        if os.path.isfile(path):
            chunks.append(path)
    if not chunks:
        sys.exit("cycles_compare: no reference chunk in " + a.out)
    img = sum(oiio.ImageBuf(p).get_pixels(oiio.FLOAT)[..., :3].astype(np.float64) for p in chunks) / len(chunks)
    w, h = (int(v) for v in a.resolution.split("x"))
    f = img.shape[1] // w
    if img.shape[1] != f * w or img.shape[0] != f * h:
        sys.exit(f"cycles_compare: --ref-resolution {a.ref_resolution} is not a multiple of --resolution {a.resolution}")
    if f > 1:
        # A box-filtered pixel of the coarse image is the mean of the f x f fine pixels it covers.
        img = img.reshape(h, f, w, f, 3).mean(axis=(1, 3))
    ref_spp = a.ref_chunk * len(chunks)
    ref = os.path.join(a.out, f"{stem}-cycles-ref-{a.resolution}-{ref_spp}spp.exr")
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.FLOAT)
    out = oiio.ImageBuf(spec)
    out.set_pixels(oiio.ROI(), img.astype(np.float32))
    if not out.write(ref):
        sys.exit(f"cycles_compare: cannot write {ref}: {out.geterror()}")
    log(f"cycles_compare: reference {ref}: mean of {len(chunks)} Cycles renders of {a.ref_chunk} spp")
    return ref, ref_spp


def main(argv):
    a = parse(argv)
    a.ref_resolution = a.ref_resolution or a.resolution
    os.makedirs(a.out, exist_ok=True)
    stem = os.path.splitext(os.path.basename(a.scene))[0]
    runs_path = os.path.join(a.out, f"{stem}-runs.json")
    runs = []
    if a.score_only:
        with open(runs_path) as f:
            runs = json.load(f)["runs"]
    for spp in [] if a.score_only else a.spps:
        for rep in range(a.repeats):
            for who in [f"tessera-{s}" for s in a.samplers] + ["cycles"]:
                seed = 1 + rep * 1000 + spp
                out = os.path.join(a.out, f"{stem}-{who}-{spp}-{rep}.exr")
                if who == "cycles":
                    j = cycles(a, out, spp, seed, 1)
                else:
                    j = tessera(a, out, spp, seed, who[len("tessera-"):])
                runs.append({"who": who, "spp": spp, "repeat": rep, "seed": seed, "seconds": j["seconds"], "out": out,
                             "command": j["command"]})
                log(f"  {who:<20} spp {spp:>5} rep {rep}: {j['seconds']:8.2f} s")
    with open(runs_path, "w") as f:
        json.dump({"runs": runs, "argv": argv}, f, indent=1)
    # The reference after the timed renders (it may still be rendering when they start: --ref-existing).
    ref, ref_spp = reference(a, stem)
    for row in runs:
        row["relmse"] = compare(a, row["out"], ref)["relmse"]
        log(f"  {row['who']:<20} spp {row['spp']:>5} rep {row['repeat']}: relMSE {row['relmse']:.3g}")
    # Means: Tessera's largest-spp sobol render against the Cycles reference.
    c = compare(a, [r for r in runs if r["who"] != "cycles" and r["spp"] == max(a.spps)][0]["out"], ref)
    log(f"cycles_compare: means check: {json.dumps(c)}")
    with open(runs_path, "w") as f:
        json.dump({"means_check": c, "reference_spp": ref_spp, "runs": runs, "argv": argv}, f, indent=1)

    whos = [f"tessera-{s}" for s in a.samplers] + ["cycles"]
    # Seconds: median and range over the repeats (the machine may be shared); relMSE: mean over the
    # repeats' seeds. The last columns: Cycles' relMSE×s over each Tessera sampler's (above 1: Tessera
    # ahead at equal time).
    head = ("| spp | " + " | ".join(f"{w}: s (min–max) / relMSE / relMSE×s" for w in whos) + " | "
            + " | ".join(f"Cycles / {w}" for w in whos[:-1]) + " |")
    lines = [head, "|---" * (2 * len(whos)) + "|"]
    for spp in a.spps:
        cells, work = [], {}
        for w in whos:
            rs = [r for r in runs if r["who"] == w and r["spp"] == spp]
            secs = [r["seconds"] for r in rs]
            s = statistics.median(secs)
            e = statistics.mean(r["relmse"] for r in rs)
            work[w] = e * s
            cells.append(f"{s:.2f} ({min(secs):.2f}–{max(secs):.2f}) / {e:.3g} / {e * s:.3g}")
        cells += [f"{work['cycles'] / work[w]:.2f}×" for w in whos[:-1]]
        lines.append(f"| {spp} | " + " | ".join(cells) + " |")
    table = "\n".join(lines)
    dm = [100.0 * (t / r - 1.0) for t, r in zip(c["mean_test"], c["mean_ref"])]
    top = [r["relmse"] for r in runs if r["who"] == "cycles" and r["spp"] == max(a.spps)]
    floor = statistics.mean(top) * max(a.spps) / ref_spp  # the reference's own relMSE, if Cycles converges as 1/spp
    summary = (f"reference: {ref_spp} spp of Cycles (its own relMSE, which every figure above includes, ~{floor:.2g}); means check: Tessera ptnee {max(a.spps)} spp against the {ref_spp}-spp Cycles reference: image means differ by "
               + ", ".join(f"{d:+.3f}%" for d in dm) + " (R, G, B)")
    with open(os.path.join(a.out, f"{stem}-table.md"), "w") as f:
        f.write(table + "\n\n" + summary + "\n")
    print(table)
    print()
    print(summary)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
