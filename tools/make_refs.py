#!/usr/bin/env python3
"""Reference images in refs/ from methods the judged renders do not share, with their agreement.

Usage (niced to 19 itself; resumable: a scene already made with the same settings is skipped, and the
renders of an unfinished scene are kept in out/refs-cache and reused):
    python3 tools/make_refs.py                         # every scene of SCENES, in order
    python3 tools/make_refs.py cornell-box furnace     # only these
    python3 tools/make_refs.py --budget 600 NAME       # stop starting renders after 600 s per scene
                                                       # (at least MIN_RENDERS per method; run again to go on)
    python3 tools/make_refs.py --force NAME            # remake from the cached renders (new statistics)
    python3 tools/make_refs.py --scale 0.25 --out DIR  # quick trial: a quarter of the samples, into DIR
    python3 tools/make_refs.py --readme                # only rebuild refs/README.md from refs/refs.json
    python3 tools/make_refs.py --rehash NAME ...       # restamp the scene hash of existing references

--rehash is for a scene-file change that provably leaves every image bit-identical: render the scene
with the old and the new file first and check `tessera compare` reports a max error of 0.

Per scene (SCENES): two or three *different* methods each render K independent images (same spp,
seeds METHOD_SEED0[j] + i) at the reference resolution (>= 256 pixels wide): Tessera's integrators
(ptnee, lt, bdpt: different estimators with different failure modes) and, for scenes of diffuse and
emissive triangles only, Blender's Cycles (tools/cycles_render.py), an independent renderer. A
method's mean has the standard error std/sqrt(K) across its renders. Then:
  * reference = the analytic value where the scene has one (furnace), else the inverse-variance
    combination of the methods (tools/make_refs_stats.combine), each weighted only where it samples
    every path (lt misses what the camera sees directly in a mirror or through glass: the
    "direct-delta" mask, rendered from a copy of the scene whose delta surfaces glow);
  * agreement of the judged integrator (the first method, which tests/test_scenes.cpp renders) with
    every other method, and with the analytic value (make_refs_stats.agreement);
  * the judged integrator's own standard error at the test's resolution (the Z-test's model of a
    test render's noise), and the noise margin: a test render's expected squared error over the
    reference's (issue 18 asks >= 16).
Outputs (half-float RGB EXR, ZIP, where half holds the values: see make_refs_stats.storage_type):
    refs/NAME.exr                 the reference
    refs/NAME-stderr.exr          its standard error
    refs/NAME-JUDGED-stderr.exr   the judged integrator's standard error at the test resolution
    refs/NAME-mask.exr            where a scene has a mask: 1 where every method samples well
                                  (tools/study judges the scene there only)
    refs/thumbs/NAME.png, refs/refs.json (provenance, agreement), refs/README.md (the table)
Every EXR carries its provenance as tessera:* attributes (commands, methods, seeds, git revision,
scene hash). Tests and the convergence study must not use seeds 1000-2999 for their own renders.
Needs python3-numpy and python3-openimageio (installed by this script through tools/bootstrap.sh
--install study) and, for Cycles, `bash tools/bootstrap.sh --install cycles`.
"""

import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # keep tools/ free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import study_deps  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
REFS = os.path.join(ROOT, "refs")
CACHE = os.path.join(ROOT, "out", "refs-cache")
TESSERA = os.path.join(ROOT, "build", "src", "tessera")
K, MIN_RENDERS = 8, 4
METHOD_SEED0 = (1000, 1400, 1800, 2200)  # method j's seeds: METHOD_SEED0[j] + i, i < K
TEST_SPP = 4  # samples per pixel of tests/test_scenes.cpp's Z-test render (at the test resolution)


def S(scene, res, methods, why, test_res=None, analytic=None, mask=None, independent=None):
    """A scene's reference recipe. methods: [(method, spp per render)], the first the judged one
    (the integrator the test renders with); test_res: the test's resolution (the reference's / 2 by
    default); analytic: the exact RGB of every pixel; mask: 'direct-delta' where lt is one of the
    methods and the camera sees mirrors or glass; independent: why the methods are independent."""
    w, h = (int(v) for v in res.split("x"))
    return {"scene": scene, "resolution": res, "methods": [list(m) for m in methods],
            "test_resolution": test_res or "%dx%d" % (w // 2, h // 2), "analytic": analytic, "mask": mask,
            "why": why, "independent": independent or ""}


# Cheapest and most important first: the order `make_refs.py` with no names renders them in.
SCENES = {
    "furnace": S("scenes/furnace/furnace.gltf", "256x256", [("bdpt", 8), ("ptnee", 16)],
                 "analytic: every pixel Le / (1 - a) = (2, 1.4286, 3.3333)",
                 analytic=[1.0 / 0.5, 1.0 / 0.7, 1.0 / 0.3]),
    "cornell-box": S("scenes/cornell-box/cornell-box.gltf", "256x256", [("bdpt", 16), ("ptnee", 64), ("cycles", 32)],
                     "diffuse only: every method samples every path",
                     independent="Cycles is another renderer; ptnee and bdpt share only Tessera's scene code"),
    "tiny-light-10": S("scenes/tiny-light/tiny-light-10.gltf", "256x256", [("bdpt", 16), ("ptnee", 64), ("cycles", 32)],
                       "light sampling (ptnee, bdpt, Cycles) is unaffected by the light's size at constant power",
                       independent="Cycles is another renderer"),
    "tiny-light-100": S("scenes/tiny-light/tiny-light-100.gltf", "256x256", [("bdpt", 16), ("ptnee", 64), ("cycles", 32)],
                        "light sampling (ptnee, bdpt, Cycles) is unaffected by the light's size at constant power",
                        independent="Cycles is another renderer"),
    "ring-caustic": S("scenes/ring-caustic/ring-caustic.gltf", "256x192", [("bdpt", 64), ("lt", 128)],
                      "the cardioid caustic is light -> mirror -> plane: lt samples it directly, bdpt through "
                      "t=1 with MIS; lt cannot see the ring itself (direct-delta mask: there bdpt alone)",
                      mask="direct-delta",
                      independent="lt is a different estimator (light paths splatted to the camera); bdpt's "
                                  "s=0 and s=1 strategies are absent from it"),
    # sds-caustic and hdri-spheres: the study gives these rare-event scenes 16x its budget
    # (tools/study_run.py, RARE_EVENT_BUDGET_SCALE; its largest renders reach 128-1024 spp), so their
    # references hold 8 x 512 bdpt and 8 x 1024 ptnee samples per pixel: the unbiased methods' largest
    # study renders have >= 47x the references' noise (refs/study/summary.csv, ref_floor).
    "sds-caustic": S("scenes/sds-caustic/sds-caustic.gltf", "256x192", [("bdpt", 512), ("ptnee", 1024)],
                     "the caustic seen in the mirror is an SDS path: only s=0 (hitting the light by BSDF sampling "
                     "through the glass) samples it, in bdpt as in ptnee; lt cannot. The camera sees 93% of the "
                     "image in the mirror, so no part is left to judge on alone: no method samples it well",
                     independent="ptnee is a different estimator (no light sub-paths, no MIS over s)"),
    "veach-mis": S("scenes/veach-mis/veach-mis.gltf", "288x192", [("bdpt", 32), ("ptnee", 64)],
                   "MIS between BSDF and light sampling is the point of the scene: bdpt and ptnee combine them",
                   independent="ptnee is a different estimator"),
    "cornell-box-specular": S("scenes/cornell-box-specular/cornell-box-specular.gltf", "256x256",
                              [("bdpt", 32), ("ptnee", 128)],
                              "caustics under an area light: bdpt reaches them through t=1; ptnee by BSDF-sampling "
                              "the light through glass (unbiased, fireflies)",
                              independent="ptnee is a different estimator"),
    "sphere-cornell": S("scenes/sphere-cornell/sphere-cornell.gltf", "256x192", [("bdpt", 24), ("ptnee", 48)],
                        "the light is a radius-600 sphere whose visible cap is tiny: bdpt's light sub-paths start on it",
                        independent="ptnee is a different estimator"),
    "sphere-cornell-mirror": S("scenes/sphere-cornell/sphere-cornell-mirror.gltf", "256x192",
                               [("bdpt", 24), ("ptnee", 48)], "as sphere-cornell, plus the mirror's caustic (bdpt t=1)",
                               independent="ptnee is a different estimator"),
    "sphere-cornell-glass": S("scenes/sphere-cornell/sphere-cornell-glass.gltf", "256x192",
                              [("bdpt", 24), ("ptnee", 48)], "as sphere-cornell, plus the glass sphere's caustic (bdpt t=1)",
                              independent="ptnee is a different estimator"),
    "door-ajar": S("scenes/door-ajar/door-ajar.gltf", "256x192", [("bdpt", 16), ("ptnee", 32)],
                   "all light comes through the gap: bdpt's light sub-paths start in the lit room",
                   independent="ptnee is a different estimator"),
    "dragon": S("scenes/dragon/dragon.gltf", "256x192", [("bdpt", 16), ("ptnee", 32)],
                "diffuse: bdpt and ptnee both sample everything", independent="ptnee is a different estimator"),
    "glass-dragon": S("scenes/dragon/glass-dragon.gltf", "256x192", [("bdpt", 16), ("ptnee", 32)],
                      "caustics through glass under an area light (bdpt t=1); SDS paths come only from s=0 in any method",
                      independent="ptnee is a different estimator"),
    "point-light-specular": S("scenes/point-light-specular/point-light-specular.gltf", "256x192",
                              [("bdpt", 64), ("lt", 128)],
                              "point light: ptnee misses the caustics, lt what the mirror shows; bdpt samples all but "
                              "point light -> specular -> diffuse -> specular -> camera (no method can); compared with lt "
                              "outside the direct-delta mask", mask="direct-delta",
                              independent="lt is a different estimator"),
    "webxr-controllers": S("scenes/webxr/webxr-controllers.gltf", "256x192", [("bdpt", 16), ("ptnee", 32)],
                           "third-party glTF assets under an area light: bdpt and ptnee both sample every path",
                           independent="ptnee is a different estimator"),
    "webxr-lineup": S("scenes/webxr/webxr-lineup.gltf", "320x180", [("bdpt", 16), ("ptnee", 32)],
                      "third-party glTF assets, two of them emissive, one with a transmissive part",
                      test_res="160x90", independent="ptnee is a different estimator"),
    "webxr-hdri": S("scenes/webxr/webxr-hdri.gltf", "256x192", [("bdpt", 16), ("ptnee", 32)],
                    "third-party glTF assets lit only by an HDRI: ptnee and bdpt importance-sample the environment",
                    independent="ptnee is a different estimator"),
    "spot-light": S("scenes/spot-light/spot-light.gltf", "256x192", [("bdpt", 128), ("ptnee", 256)],
                    "spot and directional lights only (deltas): ptnee reaches every path through the glossy sphere by "
                    "BSDF sampling, bdpt also by light tracing", independent="ptnee is a different estimator"),
    "hdri-spheres": S("scenes/hdri-spheres/hdri-spheres.gltf", "256x192", [("bdpt", 512), ("ptnee", 1024)],
                      "environment only (a small sun holds 2/3 of the light); the glass sphere's caustic comes from "
                      "bdpt's light sub-paths (t=1); seen through the glass it is SDS (direct-delta mask)",
                      mask="direct-delta", independent="ptnee is a different estimator"),
    "hdri-sun": S("scenes/hdri-spheres/hdri-sun.gltf", "256x192", [("bdpt", 128), ("ptnee", 256)],
                  "environment only, no delta surfaces: every integrator samples every path",
                  independent="ptnee is a different estimator"),
}

RUN_BINARY = TESSERA  # replaced by a private copy in main(): a rebuild during the run cannot swap it


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def git_revision():
    rev = subprocess.check_output(["git", "rev-parse", "HEAD"], cwd=ROOT, text=True).strip()
    dirty = subprocess.call(["git", "diff", "--quiet", "HEAD", "--", "src", "scenes"], cwd=ROOT)
    return rev + ("-dirty" if dirty else "")


def fnv1a64_of_file(path):
    """The scene hash the renderer writes (tessera:scene_hash): FNV-1a 64 of the file's bytes."""
    h = 0xcbf29ce484222325
    with open(path, "rb") as f:
        for b in f.read():
            h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return "fnv1a64:%016x" % h


def render_command(method, scene, res, spp, seed, out, threads):
    """The command line of one render (argv, relative paths) and how to run it."""
    if method == "cycles":
        return ["blender", "-b", "--factory-startup", "-noaudio", "-P", "tools/cycles_render.py", "--", scene, out,
                "--spp", str(spp), "--seed", str(seed), "--resolution", res, "--threads", str(threads)]
    return [os.path.relpath(TESSERA, ROOT), "render", scene, "--integrator", method, "--sampler", "independent",
            "--spp", str(spp), "--seed", str(seed), "--resolution", res, "--max-depth", "-1", "--no-png", "--quiet",
            "--json", "--threads", str(threads), "-o", out]


def run_render(method, scene, res, spp, seed, out, threads):
    """Renders one image to `out` (atomically); returns (seconds, command template)."""
    cmd = render_command(method, scene, res, spp, seed, out + ".tmp.exr", threads)
    argv = ["nice", "-n", "19"] + ([RUN_BINARY] + cmd[1:] if method != "cycles" else cmd)
    env = dict(os.environ)
    if method == "cycles":
        # Blender's Python finds its modules (numpy) through the system interpreter: keep a pyenv or
        # virtualenv python3 earlier on PATH from standing in for it.
        env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                      if ".pyenv" not in p and "virtualenv" not in p and p != os.environ.get("VIRTUAL_ENV"))
    r = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise RuntimeError("render failed (%s):\n%s%s" % (" ".join(cmd), r.stdout[-2000:], r.stderr[-2000:]))
    if method == "cycles":
        lines = [l for l in r.stdout.splitlines() if l.startswith("cycles-json ")]
        if not lines or not os.path.exists(out + ".tmp.exr"):
            raise RuntimeError("Cycles failed (%s):\n%s%s" % (" ".join(cmd), r.stdout[-3000:], r.stderr[-2000:]))
        seconds = json.loads(lines[-1][len("cycles-json "):])["seconds"]
    else:
        info = json.loads(r.stdout.strip().splitlines()[-1])
        seconds = info["seconds"]
        if info["nonfinite_dropped"]:
            log("  warning: %d non-finite samples dropped" % info["nonfinite_dropped"])
    os.replace(out + ".tmp.exr", out)
    template = " ".join("SEED" if c == str(seed) else c for c in cmd).replace(out + ".tmp.exr", "OUT.exr")
    return seconds, template


def settings_key(name, spec, scale):
    """What makes a reference besides the scene's bytes: recipe and sample scale."""
    blob = json.dumps({"spec": {k: v for k, v in spec.items() if k not in ("why", "independent")}, "scale": scale,
                       "K": K, "seeds": METHOD_SEED0}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def direct_delta_scene(scene):
    """A copy of the scene whose mirror and glass (delta) surfaces glow white (1) and everything else
    is black without lights: its render is each pixel's coverage by delta surfaces the camera sees
    directly, where light tracing (lt) cannot reach the camera."""
    with open(os.path.join(ROOT, scene)) as f:
        g = json.load(f)
    for m in g.get("materials", []):
        pbr = m.setdefault("pbrMetallicRoughness", {})
        ext = m.get("extensions", {})
        rough = pbr.get("roughnessFactor", 1.0)
        delta = rough == 0.0 and (pbr.get("metallicFactor", 1.0) == 1.0 or
                                  ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0) > 0)
        pbr.update({"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0})
        m["extensions"] = {"KHR_materials_specular": {"specularFactor": 0.0}}
        m["emissiveFactor"] = [1.0, 1.0, 1.0] if delta else [0.0, 0.0, 0.0]
        m.pop("doubleSided", None)
        m["doubleSided"] = True
    for n in g.get("nodes", []):
        n.get("extensions", {}).pop("KHR_lights_punctual", None)
    g.get("extensions", {}).pop("TESSERA_environment", None)
    # Beside the scene (hidden, removed after the render), so that its buffers resolve as they do for
    # the scene itself.
    out = os.path.join(os.path.dirname(os.path.join(ROOT, scene)), ".direct-delta-%d.gltf" % os.getpid())
    with open(out, "w") as f:
        json.dump(g, f)
    return out


def method_renders(name, spec, j, spp, cache_dir, threads, deadline, upto):
    """Paths of method j's first `upto` renders, rendering the missing ones while time is left (past
    the deadline, only up to MIN_RENDERS); returns (paths, render seconds, command template)."""
    method = spec["methods"][j][0]
    paths, seconds, template = [], 0.0, None
    for i in range(upto):
        seed = METHOD_SEED0[j] + i
        path = os.path.join(cache_dir, "%s-%s-%dspp-seed%d.exr" % (method, spec["resolution"], spp, seed))
        meta = path + ".json"
        if not os.path.exists(meta):
            if deadline and time.time() > deadline and i >= MIN_RENDERS:
                break
            t0 = time.time()
            s, tpl = run_render(method, spec["scene"], spec["resolution"], spp, seed, path, threads)
            with open(meta, "w") as f:
                json.dump({"seconds": s, "command": tpl, "git": git_revision()}, f)
            log("  %s %s seed %d: %.1f s (wall %.1f s)" % (name, method, seed, s, time.time() - t0))
        with open(meta) as f:
            m = json.load(f)
        paths.append(path)
        seconds += m["seconds"]
        template = template or m["command"]
    return paths, seconds, template


def make_one(name, out_dir, threads, scale, budget):
    import numpy as np
    import exr_io
    import make_refs_stats as st
    spec = SCENES[name]
    key = settings_key(name, spec, scale)
    cache_dir = os.path.join(CACHE, "%s-%s-%s" % (name, key, fnv1a64_of_file(os.path.join(ROOT, spec["scene"]))[-8:]))
    os.makedirs(cache_dir, exist_ok=True)
    methods = [(m, max(1, int(round(spp * scale)))) for m, spp in spec["methods"]]
    deadline = time.time() + budget if budget else None
    # Interleave the methods' renders so that a budget cut leaves every method with renders.
    sets = [None] * len(methods)
    for i in range(1, K + 1):
        for j, (m, spp) in enumerate(methods):
            sets[j] = method_renders(name, spec, j, spp, cache_dir, threads, deadline, i)
    if any(len(s[0]) < 2 for s in sets):
        raise RuntimeError("%s: too few renders within the budget" % name)
    complete = all(len(s[0]) == K for s in sets)
    stacks = [np.stack([exr_io.read_exr(p)[0] for p in s[0]]) for s in sets]
    h, w = stacks[0].shape[1:3]
    tw, th = (int(v) for v in spec["test_resolution"].split("x"))
    f = w // tw
    assert f * tw == w and f * th == h, "test resolution must divide the reference's"
    means, ses = zip(*[st.mean_and_stderr(s) for s in stacks])
    valid = [np.ones((h, w), bool) for _ in methods]
    mask = None
    if spec["mask"] == "direct-delta":
        mpath = os.path.join(cache_dir, "direct-delta.exr")
        if not os.path.exists(mpath):
            derived = direct_delta_scene(spec["scene"])
            try:
                run_render("ptnee", os.path.relpath(derived, ROOT), spec["resolution"], 16, 1, mpath, threads)
            finally:
                os.remove(derived)
        coverage = exr_io.read_exr(mpath)[0].max(axis=2)
        # Pixels lt samples completely: no delta surface in them or their 8 neighbours (16 spp can
        # miss a sliver of an edge pixel).
        mask = st.box_blur(coverage[:, :, None], 1)[:, :, 0] <= 0.0
        for j, (m, _) in enumerate(methods):
            if m == "lt":
                valid[j] = mask
    if spec["analytic"]:
        ref = np.broadcast_to(np.array(spec["analytic"], float), means[0].shape).copy()
        ref_se = np.zeros_like(ref)
    else:
        ref, ref_se = st.combine(list(means), list(ses), valid)
    judged, judged_spp = methods[0]
    judged_se = st.judged_stderr(stacks[0], f)
    judged_spp_total = judged_spp * len(sets[0][0]) * f * f  # samples per test-resolution pixel
    # Noise margin: a TEST_SPP render's expected squared error at the test resolution over the reference's.
    test_var = judged_se ** 2 * judged_spp_total / TEST_SPP
    ref_var = st.box_downsample(ref_se ** 2, f) / (f * f)
    margin = float(test_var.mean() / ref_var.mean()) if ref_var.mean() > 0 else None  # None: exact
    # Equivalent judged-integrator spp of the reference at its own resolution.
    ses0_var = (ses[0] ** 2).mean() * judged_spp * len(sets[0][0])
    equiv_spp = float(ses0_var / (ref_se ** 2).mean()) if (ref_se ** 2).mean() > 0 else None
    rev = git_revision()
    entry = {
        "scene": spec["scene"], "resolution": spec["resolution"], "test_resolution": spec["test_resolution"],
        "integrator": judged, "settings": key, "complete": complete, "git": rev,
        "scene_hash": fnv1a64_of_file(os.path.join(ROOT, spec["scene"])),
        "methods": [{"method": m, "spp": spp, "renders": len(s[0]), "seeds": "%d-%d" % (METHOD_SEED0[j], METHOD_SEED0[j] + len(s[0]) - 1),
                     "render_seconds": round(s[1], 1), "command": s[2],
                     "mean_rgb": [round(float(x), 6) for x in means[j].mean(axis=(0, 1))],
                     "covers": "outside the direct-delta mask" if (m == "lt" and mask is not None) else "every pixel"}
                    for j, ((m, spp), s) in enumerate(zip(methods, sets))],
        "reference": "analytic" if spec["analytic"] else "inverse-variance combination of " + " + ".join(m for m, _ in methods),
        "mean_rgb": [round(float(x), 6) for x in ref.mean(axis=(0, 1))],
        "median_relative_stderr": float(np.median(ref_se / np.maximum(ref, 1e-3))),
        "noise_margin": margin, "equivalent_judged_spp": equiv_spp,
        "why": spec["why"], "independent": spec["independent"],
    }
    if mask is not None:
        entry["mask_pixels_excluded"] = float(1.0 - mask.mean())
    entry["agreement"] = []
    if spec["analytic"]:
        for j, (m, _) in enumerate(methods):
            entry["agreement"].append(dict(st.agreement(ref, ref_se, means[j], ses[j]), a="analytic", b=m))
    for j in range(1, len(methods)):
        entry["agreement"].append(dict(st.agreement(means[0], ses[0], means[j], ses[j],
                                                    valid[j] if methods[j][0] == "lt" else None),
                                       a=methods[0][0], b=methods[j][0]))
    write_outputs(name, out_dir, entry, ref, ref_se, judged_se, judged, judged_spp_total, f)
    if mask is not None:
        # The pixels every method samples well (1) and those seen directly in a mirror or through glass
        # (0): tools/study judges the scene on the former only (refs/README.md says why).
        m = np.repeat(mask[:, :, None].astype(float), 3, axis=2)
        exr_io.write_exr(os.path.join(out_dir, name + "-mask.exr"), m,
                         {"tessera:made_by": "tools/make_refs.py", "tessera:scene": spec["scene"],
                          "tessera:kind": "1 = no mirror or glass seen directly in the pixel or its neighbours"},
                         half=True)
        entry["files"][name + "-mask.exr"] = {"bytes": os.path.getsize(os.path.join(out_dir, name + "-mask.exr")),
                                              "type": "half"}
    return entry


def write_outputs(name, out_dir, entry, ref, ref_se, judged_se, judged, judged_spp_total, f):
    import exr_io
    import make_refs_stats as st
    attrs = {
        "tessera:made_by": "tools/make_refs.py", "tessera:scene": entry["scene"],
        "tessera:scene_hash": entry["scene_hash"], "tessera:resolution": entry["resolution"],
        "tessera:integrator": judged, "tessera:git": entry["git"], "tessera:reference": entry["reference"],
        "tessera:methods": json.dumps(entry["methods"]), "tessera:max_depth": "-1",
    }
    os.makedirs(os.path.join(out_dir, "thumbs"), exist_ok=True)
    ref_se = st.lift_stderr(ref_se)
    judged_se = st.lift_stderr(judged_se)
    sizes = {}
    for suffix, img, kind, is_se, extra in (
            ("", ref, "reference", False, {}),
            ("-stderr", ref_se, "standard error of the reference", True, {}),
            ("-%s-stderr" % judged, judged_se, "standard error of the judged integrator's mean at the test resolution",
             True, {"tessera:spp_total": judged_spp_total, "tessera:downsample": f,
                    "tessera:test_resolution": entry["test_resolution"]})):
        path = os.path.join(out_dir, name + suffix + ".exr")
        # An analytic reference stays float32: half would round 1/0.7 by 1e-4 relative (and it
        # compresses to nothing either way).
        analytic = suffix == "" and entry["reference"] == "analytic"
        half = st.storage_type(img, is_se) == "half" and not analytic
        if not half and not analytic:
            img = st.round_to_half_precision(img)
        exr_io.write_exr(path, img, dict(attrs, **extra, **{"tessera:kind": kind}), half=half)
        sizes[os.path.basename(path)] = (os.path.getsize(path), "half" if half else "float")
    entry["files"] = {k: {"bytes": v[0], "type": v[1]} for k, v in sizes.items()}
    exr_io.write_thumbnail(os.path.join(out_dir, "thumbs", name + ".png"), ref)


def main(argv):
    import make_refs_readme
    args = argv[1:]
    if args and args[0] == "--rehash":
        unknown = [a for a in args[1:] if a not in SCENES]
        if unknown or not args[1:]:
            print("--rehash needs scene names; unknown: " + ", ".join(unknown))
            return 2
        return make_refs_readme.rehash(args[1:])
    threads, scale, out_dir, budget, force = 2, 1.0, REFS, None, False
    names = []
    while args:
        a = args.pop(0)
        if a == "--threads":
            threads = int(args.pop(0))
        elif a == "--scale":
            scale = float(args.pop(0))
            out_dir = None
        elif a == "--force":
            force = True
        elif a == "--budget":
            budget = float(args.pop(0))
        elif a == "--out":
            out_dir = args.pop(0)
        elif a == "--readme":
            make_refs_readme.write_readme(make_refs_readme.load_db())
            return 0
        elif a in SCENES:
            names.append(a)
        else:
            print(__doc__)
            print("unknown argument or scene: " + a + "; scenes: " + ", ".join(SCENES))
            return 2
    if out_dir is None:
        print("--scale writes trial references: give --out DIR (refs/ holds only full ones)")
        return 2
    study_deps.ensure_packages(("numpy", "OpenImageIO"))
    if not os.path.exists(TESSERA):
        print("build first: cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build")
        return 1
    global RUN_BINARY
    bindir = tempfile.mkdtemp(prefix="tessera-refs-bin-")
    RUN_BINARY = os.path.join(bindir, "tessera")
    shutil.copy2(TESSERA, RUN_BINARY)
    db_path = os.path.join(out_dir, "refs.json")
    db = make_refs_readme.load_db(db_path)
    failed = []
    for name in names or list(SCENES):
        e = db.get(name, {})
        if (not force and e.get("settings") == settings_key(name, SCENES[name], scale) and e.get("complete") and
                e.get("scene_hash") == fnv1a64_of_file(os.path.join(ROOT, SCENES[name]["scene"])) and
                os.path.exists(os.path.join(out_dir, name + ".exr"))):
            log("reference %s: up to date" % name)
            continue
        log("reference %s" % name)
        try:
            entry = make_one(name, out_dir, threads, scale, budget)
        except (RuntimeError, OSError, ValueError) as err:
            log("reference %s: FAILED, left as it was: %s" % (name, err))
            failed.append(name)
            continue
        db = make_refs_readme.load_db(db_path)  # another run may have finished a scene meanwhile
        db[name] = entry
        with open(db_path + ".tmp", "w") as f:
            json.dump({k: db[k] for k in list(SCENES) + sorted(set(db) - set(SCENES)) if k in db}, f, indent=1)
            f.write("\n")
        os.replace(db_path + ".tmp", db_path)
        if out_dir == REFS:
            make_refs_readme.write_readme(db)
    if failed:
        log("failed: " + " ".join(failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
