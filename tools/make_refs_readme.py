"""refs/README.md from refs/refs.json, and --rehash, for tools/make_refs.py."""
import json
import os

from make_refs import K, METHOD_SEED0, REFS, ROOT, SCENES, TEST_SPP, fnv1a64_of_file, log

HEADER = """# Reference images

Made by `tools/make_refs.py` (its docstring has the details; `tools/make_refs_stats.py` the
statistics). A reference is backed by a method the judged renders do not share: the analytic value
(furnace), or two or three *different* methods that agree: Tessera's `bdpt` (the judged integrator:
`tests/test_scenes.cpp` renders it again and Z-tests it), a different Tessera estimator (`ptnee`: no
light sub-paths; `lt`: light paths splatted to the camera) and, for scenes of diffuse and emissive
triangles, Blender's Cycles (`tools/cycles_render.py`), another renderer. Each method renders
K = %d independent images (seeds %s + i, one set per method); the reference is the
inverse-variance combination of the methods' means (variances blurred over 9x9 pixels for the
weights), each method weighted only where it samples every path.

Files per scene: `NAME.exr` (the reference), `NAME-stderr.exr` (its standard error),
`NAME-bdpt-stderr.exr` (the judged integrator's standard error at the test's resolution, the
Z-test's model of a test render's noise) and, for `ring-caustic` and `point-light-specular`,
`NAME-mask.exr` (1 where the camera sees no mirror or glass directly: where `lt` is used, and what
`tools/study` judges the scene on); all
half-float RGB EXR where half holds the values (else float32 rounded to half's precision), with
their provenance in `tessera:*` attributes; `refs.json` has everything below and more.

Columns: *agreement*, for the judged integrator against each other method (or each method against
the analytic value), over the pixels both sample: mean relative difference of the image means per
channel and its Z (difference / its standard error), the fraction of pixel channels with
|z| < 3 where z = (a − b) / sqrt(σa² + σb²) (≈ 99%% expected with K = 8: σ has 7 degrees of freedom)
and the same over 8x8-pixel bins (near normal even where fireflies are) with the largest bin |z|.
*Noise margin*: the expected squared error of the test's %d-spp `bdpt` render at the test resolution
over the reference's own (issue 18 asks >= 16); *worth*: the reference's variance expressed in
`bdpt` samples per pixel at the reference resolution (a study render with fewer has >= 16x the
reference's squared error only if it has <= 1/16 of them, in `bdpt` terms).

Regenerate (niced, resumable, hours of 2-core time for all): `python3 tools/make_refs.py [NAME...]`
(`--budget SECONDS` per scene), after `tools/fetch_assets.sh` for the dragon, WebXR and HDRI scenes and
`bash tools/bootstrap.sh --install cycles` for Cycles.
"""


# What the numbers alone do not say (read from the methods' renders; tools/make_refs_stats.py).
NOTES = {
    "furnace": "bdpt and ptnee sit 0.01–0.06% above the analytic value (Z up to 2.9; the channels share every "
               "path, so that is one event per method): chance in these 16 renders, not a bias. They reproduce bit "
               "for bit, and the same commands with other seeds do not show it: ptnee 100 renders (seeds 7000-7099) "
               "-0.002%/-0.0004%/-0.010% ± 0.001%/0.0003%/0.006%, bdpt 40 renders (8000-8039) -0.004%/-0.001%/-0.012% "
               "± 0.006%/0.002%/0.015%; at 64x64, 100 renders of 1M paths each of pt and ptnee (both samplers) and "
               "50 of bdpt lie within 1.5 standard errors (≤ 0.007%) of it. ptnee's σ is right (the spread of its 100 "
               "renders' means is what its pixels' σ predicts, within 6%); bdpt's pixels share its light paths' "
               "splats, so their σ understates its mean's by 1.3x: its Z is at most 1.8, not 2.3. 97.7% of pixel channels within 3σ is what 8 renders "
               "give with any seeds (7000-7007: 97.7%): a σ from 8 renders has 7 degrees of freedom, which leaves 2% "
               "of even normal values outside 3σ (Student's t)",
    "cornell-box-specular": "only 90.5% of pixel channels within 3σ (99.2% of bins): ptnee reaches the caustics "
                            "under the glass and mirror spheres only by BSDF samples that hit the light, so its "
                            "pixels there are heavy-tailed and their σ from 8 renders too small",
    "spot-light": "95.9% of pixel channels and 98.0% of bins within 3σ: the light the glossy sphere reflects "
                  "onto the floor reaches ptnee only through BSDF samples, heavy-tailed pixels whose σ from 8 "
                  "renders is too small",
    "sds-caustic": "the caustic in the glass sphere's shadow, seen in the mirror that fills 93% of the view, is "
                   "an SDS path that only s = 0 samples, in bdpt as in ptnee: the reference still shows its "
                   "fireflies and its σ there is underestimated (no method samples it well)",
    "glass-dragon": "97.6% of pixel channels within 3σ (99.6% of bins), 97.1% on the walls and floor around the "
                    "dragon, where 92% of those beyond 3σ have ptnee below bdpt: light that passed through the glass "
                    "reaches ptnee only by BSDF samples that hit the light, heavy-tailed pixels whose σ from 8 renders "
                    "is too small; around the dragon the image means agree to +0.03% (Z 0.4), the rest of the "
                    "-0.16% is what the glass shows (SDS paths, s = 0 only in either method)",
    "hdri-spheres": "ptnee is low on the floor beside the glass sphere: the largest bin |z| (9.4, the floor right "
                    "of the sphere's base, bin (16, 29) of 8x8 pixels) is 0.390 in bdpt and 0.380 in ptnee (green), "
                    "each tight over its 8 renders (0.387–0.391 and 0.377–0.382). The sun (4 texels of sky.exr, 51% "
                    "of its power, radiance up to 8,750 at the scene's intensity) reaches the floor through or off "
                    "the glass only by ptnee's BSDF samples, so ptnee is heavy-tailed there and its typical render "
                    "low; where the camera sees the caustic through the sphere (SDS, s = 0 only) both methods are. "
                    "A third method sides with bdpt: lt (`--integrator lt --sampler independent --spp 2048 "
                    "--resolution 256x192 --max-depth -1`, seeds 5300–5303) gives that bin 0.390 ± 0.002 and agrees "
                    "with bdpt over the mask (image mean −0.03% to −0.07%, |Z| ≤ 1.2; 99.7% of bins within 3σ); with "
                    "a constant environment instead of the HDRI (`--env 0.5,0.5,0.5`) bdpt and ptnee agree to 0.01% "
                    "(Z 0.4). The combination follows bdpt there (0.387). The study judges the scene outside its "
                    "direct-delta mask, which leaves out the 8.7% of the pixels that show the glass sphere: the floor "
                    "seen there, lit through the glass by the sun, is SDS (s = 0 only, in bdpt as in ptnee)",
    "ring-caustic": "the largest bin |z| lies in the bottom rows (the floor nearest the camera), where lt's and "
                    "bdpt's t = 1 splats are largest and rare: single pixels there are heavy-tailed in both "
                    "(ptnee, which has no splats, is smooth there), so their σ from 8 renders is too small",
}


def load_db(path=None):
    path = path or os.path.join(REFS, "refs.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def _pct(x):
    return "%+.3f%%" % (100 * x)


def fmt_agreement(a):
    return ("%s vs %s: mean %s (Z %s); %.1f%% px, %.1f%% bins within 3σ, largest bin \\|z\\| %.1f" % (
        a["a"], a["b"], "/".join(_pct(x) for x in a["mean_rel_diff"]), "/".join("%.1f" % z for z in a["mean_z"]),
        100 * a["within_3se"], 100 * a["bin_within_3se"], a["bin_max_abs_z"]))


def row(name, e):
    methods = ", ".join("%s %d × %d%s" % (m["method"], m["renders"], m["spp"],
                                           " (outside the mask)" if m["covers"] != "every pixel" else "")
                        for m in e["methods"])
    agree = "<br>".join(fmt_agreement(a) for a in e["agreement"])
    if name in NOTES:
        agree += "<br>" + NOTES[name].replace("|z|", "\\|z\\|")
    if "mask_pixels_excluded" in e:
        agree += "<br>mask: %.1f%% of pixels see a mirror or glass directly (lt cannot)" % (100 * e["mask_pixels_excluded"])
    size = sum(f["bytes"] for f in e.get("files", {}).values())
    status = "" if e.get("complete", True) else " (cut by --budget)"
    margin = ("∞ (exact)" if e["noise_margin"] is None else
              "%.0f; worth %.0f spp" % (e["noise_margin"], e["equivalent_judged_spp"]))
    return "| ![](thumbs/%s.png) `%s` | %s%s | %s (test %s) | %s | %s | %.0f kB | %s |" % (
        name, name, methods, status, e["resolution"], e["test_resolution"], agree, margin, size / 1000, e["why"])


def write_readme(db):
    lines = [HEADER % (K, "/".join(str(s) for s in METHOD_SEED0), TEST_SPP),
             "| reference | methods, renders × spp | resolution | agreement | noise margin | files | why these methods |",
             "|---|---|---|---|---|---|---|"]
    for name in SCENES:
        if name in db:
            lines.append(row(name, db[name]))
        else:
            lines.append("| `%s` | *not rendered* | | | | | %s |" % (name, SCENES[name]["why"]))
    lines += ["", "Exact commands (`SEED` = each seed of the set; git revision of the renderer):", ""]
    for name in SCENES:
        e = db.get(name)
        if not e:
            continue
        lines.append("- `%s` (git %s):" % (name, e["git"][:12]))
        for m in e["methods"]:
            lines.append("  - %s (%s, %.0f s): `%s`" % (m["method"], m["seeds"], m["render_seconds"], m["command"]))
    lines.append("")
    with open(os.path.join(REFS, "README.md") + ".tmp", "w") as f:
        f.write("\n".join(lines))
    os.replace(os.path.join(REFS, "README.md") + ".tmp", os.path.join(REFS, "README.md"))


def rehash(names):
    import study_deps
    study_deps.ensure_packages(("numpy", "OpenImageIO"))
    import exr_io
    import OpenImageIO as oiio
    db_path = os.path.join(REFS, "refs.json")
    db = load_db(db_path)
    for name in names:
        new = fnv1a64_of_file(os.path.join(ROOT, SCENES[name]["scene"]))
        judged = db[name].get("integrator", "bdpt")
        for suffix in ("", "-stderr", "-%s-stderr" % judged):
            path = os.path.join(REFS, name + suffix + ".exr")
            if not os.path.exists(path):
                continue
            half = oiio.ImageInput.open(path).spec().format == oiio.HALF
            pixels, meta = exr_io.read_exr(path)
            meta = {k: v for k, v in meta.items() if k.startswith("tessera:")}
            meta["tessera:scene_hash"] = new
            exr_io.write_exr(path, pixels, meta, half=half)
        db[name]["scene_hash"] = new
        log("%s: scene_hash %s" % (name, new))
    with open(db_path, "w") as f:
        json.dump(db, f, indent=1)
        f.write("\n")
    write_readme(db)
    return 0
