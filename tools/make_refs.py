#!/usr/bin/env python3
"""Render Tessera's reference images into refs/, with provenance.

Usage:
    python3 tools/make_refs.py                      # every scene in REFS (slow: tens of minutes)
    python3 tools/make_refs.py cornell-box furnace  # only these
    python3 tools/make_refs.py --scale 0.25 NAME    # quick trial: a quarter of the samples, into --out
    python3 tools/make_refs.py --readme             # only rebuild refs/README.md from refs/refs.json
    python3 tools/make_refs.py --rehash NAME ...    # restamp the scene hash of existing references

--rehash is for a scene-file change that provably leaves every image bit-identical (for example an
extension stating what the renderer already assumed): render the scene with the old and the new file
first and check `tessera compare` reports a max error of 0. It rewrites tessera:scene_hash in
refs/NAME.exr and NAME-stderr.exr (pixels unchanged) and in refs/refs.json, and renders nothing.

For each scene: K renders with independent seeds (1000, 1001, ...) of the scene's most robust
integrator; the reference is their per-pixel mean and the standard-error image is the standard error
of that mean across the K renders (sample standard deviation / sqrt(K)). This works for every
integrator, splatting ones (lt, bdpt) included, whose film keeps no per-pixel variance. Where a
second unbiased integrator can sample every path of the scene, it is rendered the same way (seeds
2000, ...) and the agreement recorded: the fraction of pixel channels within 2 and 3 combined standard
errors, the largest |z| and the relMSE between the two images.

Outputs (float32 RGB EXR, ZIP, about 100 kB each at these resolutions):
    refs/NAME.exr           reference (mean of the K renders)
    refs/NAME-stderr.exr    per-pixel standard error of that mean
    refs/thumbs/NAME.png    128-pixel-wide sRGB thumbnail
    refs/refs.json          provenance and agreement of every reference (machine-readable)
    refs/README.md          the same as a table
Every EXR carries its provenance as string attributes: tessera:command (the exact render command,
with SEED standing for each seed), tessera:integrator, tessera:spp (per render), tessera:seeds,
tessera:spp_total, tessera:render_seconds (sum over the K renders), tessera:git, plus the renderer's
own tessera:* attributes of the first render (scene hash, version, accel, max depth).

Tests and the convergence study must not use seeds 1000-2999 for their own renders.
Needs python3-numpy and python3-openimageio: `bash tools/bootstrap.sh --install study` installs them
when missing (this script calls it itself). tools/study --make-refs makes quick development
references with the same estimator (mean_of_renders below).
"""

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
TESSERA = os.path.join(ROOT, "build", "src", "tessera")

# name: scene, resolution, reference integrator, spp per render, renders K, and the
# agreement integrator (None when no second method samples every path) with its spp per render.
# Why each integrator: see WHY below and refs/README.md.
REF_SEED0, AGREE_SEED0, K = 1000, 2000, 8
SCENES = {
    "cornell-box": ("scenes/cornell-box/cornell-box.gltf", "96x96", "bdpt", 64, "ptnee", 128),
    "cornell-box-specular": ("scenes/cornell-box-specular/cornell-box-specular.gltf", "96x96",
                             "bdpt", 64, "ptnee", 128),
    "sphere-cornell": ("scenes/sphere-cornell/sphere-cornell.gltf", "128x96", "bdpt", 48, "ptnee", 96),
    "sphere-cornell-mirror": ("scenes/sphere-cornell/sphere-cornell-mirror.gltf", "128x96",
                              "bdpt", 48, "ptnee", 96),
    "sphere-cornell-glass": ("scenes/sphere-cornell/sphere-cornell-glass.gltf", "128x96",
                             "bdpt", 48, "ptnee", 96),
    "ring-caustic": ("scenes/ring-caustic/ring-caustic.gltf", "128x96", "bdpt", 128, None, 0),
    "dragon": ("scenes/dragon/dragon.gltf", "120x90", "bdpt", 32, "ptnee", 64),
    "glass-dragon": ("scenes/dragon/glass-dragon.gltf", "120x90", "bdpt", 32, None, 0),
    "veach-mis": ("scenes/veach-mis/veach-mis.gltf", "144x96", "bdpt", 64, "ptnee", 128),
    "tiny-light-10": ("scenes/tiny-light/tiny-light-10.gltf", "96x96", "bdpt", 64, "ptnee", 128),
    "tiny-light-100": ("scenes/tiny-light/tiny-light-100.gltf", "96x96", "bdpt", 64, "ptnee", 128),
    "door-ajar": ("scenes/door-ajar/door-ajar.gltf", "128x96", "bdpt", 32, "ptnee", 64),
    "sds-caustic": ("scenes/sds-caustic/sds-caustic.gltf", "128x96", "bdpt", 96, "ptnee", 192),
    "point-light-specular": ("scenes/point-light-specular/point-light-specular.gltf", "128x96",
                             "bdpt", 128, None, 0),
    "furnace": ("scenes/furnace/furnace.gltf", "64x64", "bdpt", 32, "ptnee", 64),
    "webxr-controllers": ("scenes/webxr/webxr-controllers.gltf", "128x96", "bdpt", 32, "ptnee", 64),
    "webxr-lineup": ("scenes/webxr/webxr-lineup.gltf", "160x90", "bdpt", 32, "ptnee", 64),
    "webxr-hdri": ("scenes/webxr/webxr-hdri.gltf", "128x96", "bdpt", 32, "ptnee", 64),
    "spot-light": ("scenes/spot-light/spot-light.gltf", "128x96", "bdpt", 256, "ptnee", 512),
    "hdri-spheres": ("scenes/hdri-spheres/hdri-spheres.gltf", "128x96", "bdpt", 256, "ptnee", 512),
    "hdri-sun": ("scenes/hdri-spheres/hdri-sun.gltf", "128x96", "bdpt", 256, "ptnee", 512),
}

WHY = {
    "cornell-box": "diffuse only: every integrator samples every path; bdpt has the lowest variance per sample",
    "cornell-box-specular": "caustics under an area light: bdpt reaches them through t=1 (light tracing); "
                            "ptnee only by BSDF-sampling the light through glass (unbiased, fireflies)",
    "sphere-cornell": "the light is a radius-600 sphere whose visible cap is tiny: bdpt's light sub-paths start on it",
    "sphere-cornell-mirror": "as sphere-cornell, plus the mirror's caustic (bdpt t=1)",
    "sphere-cornell-glass": "as sphere-cornell, plus the glass sphere's caustic (bdpt t=1)",
    "ring-caustic": "the cardioid caustic is light -> mirror -> plane: bdpt gets it from t=1; ptnee only by "
                    "BSDF-sampling a tiny light through the mirror (its agreement would take hours)",
    "dragon": "diffuse: bdpt and ptnee both sample everything",
    "glass-dragon": "caustics through glass under an area light (bdpt t=1); SDS paths (caustics seen through "
                    "the glass) come only from s=0 in any method",
    "veach-mis": "MIS between BSDF and light sampling is the point of the scene: bdpt and ptnee both combine them",
    "tiny-light-10": "light sampling (ptnee, bdpt) is unaffected by the light's size at constant power",
    "tiny-light-100": "light sampling (ptnee, bdpt) is unaffected by the light's size at constant power",
    "door-ajar": "all light comes through the gap: bdpt's light sub-paths start in the lit room",
    "sds-caustic": "the caustic seen in the mirror is an SDS path: only s=0 (hitting the light by BSDF sampling "
                   "through the glass) samples it, in bdpt as in ptnee; lt cannot",
    "point-light-specular": "point light: ptnee misses the caustics, lt what the mirror shows; bdpt samples "
                            "all but point light -> specular -> diffuse -> specular -> camera (no method can)",
    "furnace": "analytic: every pixel Le / (1 - a) = (2, 1.4286, 3.3333)",
    "webxr-controllers": "third-party glTF assets (TESSERA_asset_gltf) under an area light: bdpt and ptnee both "
                         "sample every path",
    "webxr-lineup": "third-party glTF assets, two of them emissive, one with a transmissive part: bdpt and ptnee "
                    "both sample every path (the transmissive part's caustics only through BSDF sampling in ptnee)",
    "webxr-hdri": "third-party glTF assets lit only by an HDRI (plus the emissive LED texture): ptnee and bdpt "
                  "importance-sample the environment; bdpt's light sub-paths also start at it",
    "spot-light": "spot and directional lights only (deltas): pt sees black; ptnee reaches every path through "
                  "the glossy sphere by BSDF sampling, bdpt also by light tracing",
    "hdri-spheres": "environment only (a small sun holds 2/3 of the light): ptnee and bdpt sample it by "
                    "luminance; the glass sphere's caustic comes from bdpt's light sub-paths (t=1)",
    "hdri-sun": "environment only, no delta surfaces: every integrator samples every path (lt sees the sky "
                "directly through camera rays); ptnee and bdpt importance-sample the sun, pt must hit it",
}


def git_revision():
    rev = subprocess.check_output(["git", "rev-parse", "HEAD"], cwd=ROOT, text=True).strip()
    dirty = subprocess.call(["git", "diff", "--quiet", "HEAD", "--", "src", "scenes"], cwd=ROOT)
    return rev + ("-dirty" if dirty else "")


RUN_BINARY = TESSERA  # replaced by a private copy in main(): a rebuild during the run cannot swap it


def render(scene, res, integrator, spp, seed, out, threads):
    cmd = [os.path.relpath(TESSERA, ROOT), "render", scene, "--integrator", integrator, "--spp", str(spp),
           "--seed", str(seed), "--resolution", res, "--max-depth", "-1", "--no-png", "--quiet", "--json",
           "-o", out]
    if threads:
        cmd += ["--threads", str(threads)]
    result = subprocess.run([RUN_BINARY] + cmd[1:], cwd=ROOT, check=True, capture_output=True, text=True)
    return json.loads(result.stdout.strip().splitlines()[-1]), cmd


def mean_of_renders(render_seed, seeds):
    """The reference estimator: render_seed(seed) renders one independent image and returns its EXR
    path; the reference is the per-pixel mean over `seeds`, its noise the standard error of that mean
    across the renders (sample standard deviation / sqrt(K)), valid for splatting integrators too.
    Returns (mean, stderr), float64 [H, W, 3]."""
    import numpy as np
    import exr_io
    stack = np.stack([exr_io.read_exr(render_seed(seed))[0] for seed in seeds])
    return stack.mean(axis=0), stack.std(axis=0, ddof=1) / np.sqrt(len(seeds))


def run_set(name, scene, res, integrator, spp, seed0, tmpdir, threads):
    """K renders; returns (mean, stderr, seconds, command template, first render's attributes)."""
    import exr_io
    state = {"seconds": 0.0, "attrs0": None, "template": None}

    def render_seed(seed):
        out = os.path.join(tmpdir, "%s-%s-%d.exr" % (name, integrator, seed))
        t0 = time.time()
        info, cmd = render(scene, res, integrator, spp, seed, out, threads)
        state["seconds"] += info["seconds"]
        if info["nonfinite_dropped"]:
            print("  warning: %d non-finite samples dropped" % info["nonfinite_dropped"], file=sys.stderr)
        if state["attrs0"] is None:
            state["attrs0"] = exr_io.read_exr(out)[1]
            state["template"] = " ".join("SEED" if c == str(seed) else c for c in cmd).replace(out, "OUT.exr")
        print("  %s %s seed %d: %.1f s (wall %.1f s)" % (name, integrator, seed, info["seconds"],
                                                       time.time() - t0), file=sys.stderr, flush=True)
        return out

    mean, stderr = mean_of_renders(render_seed, range(seed0, seed0 + K))
    return mean, stderr, state["seconds"], state["template"], state["attrs0"]


def agreement(a, sa, b, sb):
    import numpy as np
    se = np.sqrt(sa ** 2 + sb ** 2)
    diff = np.abs(a - b)
    ok = se > 0
    z = np.where(ok, diff / np.where(ok, se, 1.0), np.where(diff > 1e-6, np.inf, 0.0))
    return {
        "within_2se": float(np.mean(z < 2.0)),
        "within_3se": float(np.mean(z < 3.0)),
        "max_abs_z": float(np.max(z)),
        "relmse": float(np.mean((a - b) ** 2 / (a ** 2 + 0.01))),
        "mean_ratio": [float(x) for x in (b.mean(axis=(0, 1)) / np.maximum(a.mean(axis=(0, 1)), 1e-30))],
    }


def make_one(name, out_dir, threads, scale):
    import numpy as np
    import exr_io
    scene, res, integ, spp, agree, agree_spp = SCENES[name]
    spp = max(1, int(round(spp * scale)))
    agree_spp = max(1, int(round(agree_spp * scale)))
    rev = git_revision()
    tmpdir = tempfile.mkdtemp(prefix="tessera-refs-")
    try:
        mean, stderr, seconds, template, attrs0 = run_set(name, scene, res, integ, spp, REF_SEED0, tmpdir, threads)
        entry = {
            "scene": scene, "resolution": res, "integrator": integ, "spp": spp, "renders": K,
            "seeds": "%d-%d" % (REF_SEED0, REF_SEED0 + K - 1), "spp_total": spp * K,
            "render_seconds": round(seconds, 1), "git": rev, "command": template,
            "mean_rgb": [round(float(x), 6) for x in mean.mean(axis=(0, 1))],
            "median_relative_stderr": float(np.median(stderr / np.maximum(mean, 1e-3))),
            "why": WHY[name],
            "scene_hash": attrs0.get("tessera:scene_hash", ""),
            "max_depth": attrs0.get("tessera:max_depth", ""),
            "accel": attrs0.get("tessera:accel", ""),
            "version": attrs0.get("tessera:version", ""),
        }
        if agree:
            amean, astderr, aseconds, atemplate, _ = run_set(name, scene, res, agree, agree_spp, AGREE_SEED0,
                                                            tmpdir, threads)
            entry["agreement"] = dict(agreement(mean, stderr, amean, astderr), integrator=agree,
                                      spp=agree_spp, renders=K,
                                      seeds="%d-%d" % (AGREE_SEED0, AGREE_SEED0 + K - 1),
                                      render_seconds=round(aseconds, 1), command=atemplate)
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
    attrs = {
        "tessera:command": entry["command"], "tessera:integrator": integ, "tessera:spp": spp,
        "tessera:renders": K, "tessera:seeds": entry["seeds"], "tessera:spp_total": spp * K,
        "tessera:render_seconds": entry["render_seconds"], "tessera:git": rev, "tessera:scene": scene,
        "tessera:resolution": res, "tessera:scene_hash": entry["scene_hash"],
        "tessera:max_depth": entry["max_depth"], "tessera:accel": entry["accel"],
        "tessera:version": entry["version"], "tessera:made_by": "tools/make_refs.py",
    }
    if "agreement" in entry:
        attrs["tessera:agreement"] = json.dumps(entry["agreement"])
    os.makedirs(out_dir, exist_ok=True)
    exr_io.write_exr(os.path.join(out_dir, name + ".exr"), mean, dict(attrs, **{"tessera:kind": "mean of the renders"}))
    exr_io.write_exr(os.path.join(out_dir, name + "-stderr.exr"), stderr,
              dict(attrs, **{"tessera:kind": "standard error of the mean across the renders"}))
    exr_io.write_thumbnail(os.path.join(out_dir, "thumbs", name + ".png"), mean)
    return entry


def fmt_agreement(e):
    a = e.get("agreement")
    if not a:
        return "— (no second method samples every path)"
    return ("%s %d×%d spp: %.1f%% within 3σ, largest z %.1f, relMSE %.2g, mean ratio %s" %
            (a["integrator"], a["renders"], a["spp"], 100 * a["within_3se"], a["max_abs_z"], a["relmse"],
             "/".join("%.3f" % r for r in a["mean_ratio"])))


def write_readme(db):
    lines = [
        "# Reference images",
        "",
        "Made by `tools/make_refs.py` (see its docstring); provenance is in each EXR's `tessera:*`",
        "attributes and in `refs.json`. Each reference `NAME.exr` is the per-pixel mean of K = %d" % K,
        "renders with seeds 1000…1007 of the integrator named; `NAME-stderr.exr` is the standard error",
        "of that mean across the renders (so it is valid for splatting integrators too). The test",
        "`Shipped/ShippedSceneTest.MatchesItsReference/*` (tests/test_scenes.cpp) renders each scene again with other seeds and",
        "Z-tests it against these two images. Float32 RGB EXR (not half: dark pixels and standard errors",
        "fall below half's smallest normal, which a reader with denormals-are-zero set, as in any thread",
        "that has rendered, reads as 0); `tessera compare` reads them.",
        "",
        "Regenerate (slow; niced, 2 threads): `python3 tools/make_refs.py [NAME...]`, after",
        "`tools/fetch_assets.sh` for the dragons and the WebXR controllers.",
        "",
        "Agreement: a second, independent integrator rendered the same way (seeds 2000…2007) where it",
        "can sample every path; z = |a − b| / sqrt(σa² + σb²) per pixel channel; mean ratio = its image",
        "mean / the reference's. With K = 8 renders each σ has 7 degrees of freedom, so about 1% of",
        "channels exceed 3σ even when both agree; heavy-tailed estimators (ptnee's BSDF-sampled caustics)",
        "underestimate their own σ and show more. The dragon scenes read the Stanford dragon and the",
        "webxr scenes the WebXR input-profile GLBs (MIT) that `tools/fetch_assets.sh` fetches (SHA-256",
        "checked), found through `TESSERA_ASSETS` or the fetch cache; the webxr references show the",
        "renderer's materials of their date (textures and the full glTF material model make them stale:",
        "regenerate them when those land).",
        "",
        "| reference | integrator, renders × spp | resolution | render s | mean RGB | median rel. stderr | agreement | why this integrator |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in SCENES:
        e = db.get(name)
        if not e:
            lines.append("| `%s` | *not rendered* | | | | | | %s |" % (name, WHY[name]))
            continue
        lines.append("| ![](thumbs/%s.png) `%s` | %s, %d × %d | %s | %.0f | %s | %.3f | %s | %s |" % (
            name, name, e["integrator"], e["renders"], e["spp"], e["resolution"], e["render_seconds"],
            ", ".join("%.4g" % x for x in e["mean_rgb"]), e["median_relative_stderr"], fmt_agreement(e),
            e["why"]))
    lines += ["", "Exact commands (`SEED` = each seed of the set; git revision of the renderer):", ""]
    for name in SCENES:
        e = db.get(name)
        if not e:
            continue
        lines.append("- `%s` (git %s, %s): `%s`" % (name, e["git"][:12], e["seeds"], e["command"]))
        if e.get("agreement"):
            lines.append("  - agreement (%s): `%s`" % (e["agreement"]["seeds"], e["agreement"]["command"]))
    lines.append("")
    with open(os.path.join(REFS, "README.md"), "w") as f:
        f.write("\n".join(lines))


def fnv1a64_of_file(path):
    """The scene hash the renderer writes (tessera:scene_hash): FNV-1a 64 of the file's bytes."""
    h = 0xcbf29ce484222325
    with open(path, "rb") as f:
        for b in f.read():
            h = ((h ^ b) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return "fnv1a64:%016x" % h


def rehash(names):
    study_deps.ensure_packages(("numpy", "OpenImageIO"))
    import exr_io
    db_path = os.path.join(REFS, "refs.json")
    with open(db_path) as f:
        db = json.load(f)
    for name in names:
        new = fnv1a64_of_file(os.path.join(ROOT, SCENES[name][0]))
        for suffix in ("", "-stderr"):
            path = os.path.join(REFS, name + suffix + ".exr")
            pixels, meta = exr_io.read_exr(path)
            meta = {k: v for k, v in meta.items() if k.startswith("tessera:")}
            meta["tessera:scene_hash"] = new
            exr_io.write_exr(path, pixels, meta)
        db[name]["scene_hash"] = new
        print("%s: scene_hash %s" % (name, new), file=sys.stderr)
    with open(db_path, "w") as f:
        json.dump(db, f, indent=1)
        f.write("\n")
    write_readme(db)
    return 0


def main(argv):
    args = argv[1:]
    if args and args[0] == "--rehash":
        unknown = [a for a in args[1:] if a not in SCENES]
        if unknown or not args[1:]:
            print("--rehash needs scene names; unknown: " + ", ".join(unknown))
            return 2
        return rehash(args[1:])
    threads, scale, out_dir = 2, 1.0, REFS
    names = []
    while args:
        a = args.pop(0)
        if a == "--threads":
            threads = int(args.pop(0))
        elif a == "--scale":
            scale = float(args.pop(0))
            out_dir = None
        elif a == "--out":
            out_dir = args.pop(0)
        elif a == "--readme":
            with open(os.path.join(REFS, "refs.json")) as f:
                write_readme(json.load(f))
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
    db = {}
    if os.path.exists(db_path):
        with open(db_path) as f:
            db = json.load(f)
    for name in names or list(SCENES):
        print("reference %s" % name, file=sys.stderr, flush=True)
        db[name] = make_one(name, out_dir, threads, scale)
        with open(db_path, "w") as f:
            json.dump({k: db[k] for k in SCENES if k in db}, f, indent=1)
            f.write("\n")
    if out_dir == REFS:
        write_readme(db)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
