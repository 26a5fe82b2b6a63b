"""The study's main loop: series of renders per scene x integrator (and x accelerator), then the
summaries, verdicts, CSV, charts and stability table."""
import hashlib
import json
import math
import os
import shlex
import sys
import tempfile
import time

import numpy as np

import exr_io
import study_metrics as sm
import study_refs
import study_render
import study_report

DEFAULT_ACCEL = "embree"
# Part of every cache key: bump when a metric's definition changes, so --resume recomputes.
STUDY_VERSION = "2"
# A non-default accelerator whose predicted time per spp exceeds this many times --max-seconds is
# left out of a scene (the brute-force reference on a million triangles would take hours).
ACCEL_SKIP_FACTOR = 10.0
# Scenes whose error at the study's budgets is made by rare paths: each of their series (every
# integrator and accelerator alike) aims its largest render at this many times --max-seconds. At
# the default budget their renders hold a handful of those paths each (none in some seeds, several
# in others), so relMSE jumps with them and a log-log slope over the series measures the luck of
# the draw rather than the estimator's rate; at 16x the three seeds of the largest budget agree
# within 1.4x on both (writeup, "Speed against accuracy"). --uniform-budgets turns this off.
RARE_EVENT_BUDGET_SCALE = {
    # The caustic under the glass sphere, seen in the mirror: specular-diffuse-specular, reached
    # only by hitting the small sphere light through the glass (s = 0 in bdpt, BSDF sampling in ptnee).
    "sds-caustic": 16,
    # The sun's caustic through the glass sphere, seen in the copper sphere's narrow lobe: s = 0
    # builds it nearly alone in bdpt, BSDF samples that hit the sun in ptnee (the glass sphere
    # itself, where the caustic is seen through the glass, is outside the scene's mask).
    "hdri-spheres": 16,
}


def budget_scale(args, name):
    return 1 if args.uniform_budgets else RARE_EVENT_BUDGET_SCALE.get(name, 1)


def log(msg):
    print(msg, file=sys.stderr, flush=True)


class SceneStudy:
    def __init__(self, args, tess, ref, tmp):
        self.args, self.tess, self.ref, self.tmp = args, tess, ref, tmp
        self.budget_scale = budget_scale(args, ref.name)
        self.max_seconds = args.max_seconds * self.budget_scale
        f = study_refs.downsample_factor(ref.width, ref.height, args.downsample)
        self.factor = f
        self.rgb = study_refs.box_downsample(ref.rgb, f)
        self.se = study_refs.box_downsample_stderr(ref.stderr, f)
        # A masked reference: only pixels wholly inside the mask count; the rest is zeroed here and in
        # every render (one(), before `tessera compare` and the metrics).
        self.mask = None
        if ref.mask is not None:
            self.mask = study_refs.box_downsample(ref.mask[:, :, None].astype(float), f)[:, :, 0] > 0.999
            self.rgb = np.where(self.mask[:, :, None], self.rgb, 0.0)
            if self.se is not None:
                self.se = np.where(self.mask[:, :, None], self.se, 0.0)
        self.resolution = (self.rgb.shape[1], self.rgb.shape[0])
        self.ref_path = os.path.join(tmp, f"{ref.name}-ref.exr")
        exr_io.write_exr(self.ref_path, self.rgb)
        self.floor = sm.reference_floor(self.rgb, self.se)
        self.ref_mean = sm.image_mean(self.rgb)
        self.ref_mean_se = sm.reference_mean_se(self.se)
        self.ref_firefly = sm.firefly_share(self.rgb)
        md = ref.meta.get("tessera:max_depth")
        self.max_depth = int(md) if md not in (None, "") else None
        self.seed_counter = 0
        self.runs = []
        self.pooled = {}  # (integrator, accel) -> [spp-weighted image sum, spp sum]
        self.failures = []

    def next_seed(self):
        self.seed_counter += 1
        return self.seed_counter

    def one(self, integrator, accel, spp, seed):
        exr = os.path.join(self.tmp, f"{self.ref.name}-{integrator}-{accel}-{spp}-{seed}.exr")
        j = self.tess.render(self.ref.scene, exr, integrator, accel, spp, seed, self.resolution, self.max_depth)
        if self.mask is not None:
            rgb, _ = exr_io.read_exr(exr)
            exr_io.write_exr(exr, np.where(self.mask[:, :, None], rgb, 0.0))
        c = self.tess.compare(exr, self.ref_path)
        rgb, _ = exr_io.read_exr(exr)
        os.remove(exr)
        row = {"scene": self.ref.name, "integrator": integrator, "accel": accel, "spp": j["spp"], "seed": seed,
               "width": self.resolution[0], "height": self.resolution[1], "seconds": float(j["seconds"]),
               "build_seconds": float(j.get("build_seconds", 0.0)),
               "samples_per_second": float(j.get("samples_per_second", 0.0)),
               "relmse": float(c["relmse"]), "rmse": float(c["rmse"]), "mean_test": sm.image_mean(rgb),
               "mean_ref": self.ref_mean, "firefly_share": sm.firefly_share(rgb),
               "nonfinite_samples": int(j.get("nonfinite_dropped", 0)), "nonfinite_pixels": sm.nonfinite_pixels(rgb),
               "ref_floor": self.floor}
        acc = self.pooled.setdefault((integrator, accel), [np.zeros_like(self.rgb), 0])
        acc[0] += j["spp"] * np.where(np.isfinite(rgb), rgb, 0.0)
        acc[1] += j["spp"]
        self.runs.append(row)
        log(f"  {self.ref.name:<22} {integrator:<12} {accel:<7} spp {j['spp']:>5} seed {seed:>3}: "
            f"{row['seconds']:7.2f} s  relMSE {row['relmse']:.3g}  mean {row['mean_test']:.4g} (ref {self.ref_mean:.4g})")
        return row

    def series(self, integrator, accel, plan=None):
        """Calibrate with one 1-spp render, then `budgets` spp levels x `seeds` seeds. With `plan`
        (a list of (spp, seed)), render exactly those instead (the accelerator series)."""
        a = self.args
        try:
            if plan is None:
                cal = self.one(integrator, accel, 1, self.next_seed())
                spps = study_render.spp_series(max(cal["seconds"], 1e-4), self.max_seconds, a.budgets, 1 << 20)
                plan = [(spp, self.next_seed()) for spp in spps for _ in range(a.seeds)]
            for spp, seed in plan:
                self.one(integrator, accel, spp, seed)
        except study_render.RenderError as e:
            self.failures.append(f"{self.ref.name} {integrator} {accel}: {e}")
            log(f"study: {e}")

    def accel_too_slow(self, accel):
        """Probe a 1-spp render at 1/16 of the pixels; predict the full-size time per spp."""
        w, h = self.resolution
        probe = (max(1, w // 4), max(1, h // 4))
        exr = os.path.join(self.tmp, f"probe-{accel}.exr")
        try:
            tess = study_render.Tessera(self.tess.binary, self.tess.threads,
                                        min(self.tess.timeout, ACCEL_SKIP_FACTOR * self.max_seconds))
            j = tess.render(self.ref.scene, exr, self.args.accel_integrator, accel, 1, 0, probe, self.max_depth)
        except study_render.RenderError:
            return f"{accel}: a 1-spp probe at {probe[0]}x{probe[1]} did not finish in time"
        predicted = j["seconds"] * (w * h) / (probe[0] * probe[1])
        if predicted > ACCEL_SKIP_FACTOR * self.max_seconds:
            return f"{accel}: predicted {predicted:.0f} s per spp at {w}x{h} (over {ACCEL_SKIP_FACTOR:g}x --max-seconds)"
        return None


def summarise(study, integrator, accel):
    runs = [r for r in study.runs if r["integrator"] == integrator and r["accel"] == accel]
    if not runs:
        return None
    pts = study_report.per_budget(runs)
    floor = study.floor
    slope = sm.loglog_slope([p[1] for p in pts], [p[2] - floor for p in pts])
    top = [r for r in runs if r["spp"] == max(r2["spp"] for r2 in runs)]
    relmse_top = sum(r["relmse"] for r in top) / len(top)
    seconds_top = sum(r["seconds"] for r in top) / len(top)
    bias, bias_se = sm.pooled_bias([r["mean_test"] for r in runs], [r["spp"] for r in runs],
                                   study.ref_mean, study.ref_mean_se)
    img, w = study.pooled[(integrator, accel)]
    return {
        "scene": study.ref.name, "integrator": integrator, "accel": accel, "renders": len(runs),
        "spp_series": " ".join(str(p[0]) for p in pts), "seconds_top": seconds_top, "relmse_top": relmse_top,
        "slope": slope, "work": max(relmse_top - floor, 0.0) * seconds_top, "ref_mean": study.ref_mean,
        "bias": bias, "bias_se": bias_se, "bias_relative": bias / study.ref_mean if study.ref_mean else float("nan"),
        "firefly_share": sum(r["firefly_share"] for r in top) / len(top), "ref_firefly_share": study.ref_firefly,
        "nonfinite_samples": sum(r["nonfinite_samples"] for r in runs),
        "nonfinite_pixels": sum(r["nonfinite_pixels"] for r in runs),
        "dark_share": sm.dark_share(img / max(w, 1), study.rgb), "ref_floor": floor,
        "ref_limited": floor > 0 and relmse_top < 16 * floor,
        "samples_per_second": sum(r["samples_per_second"] for r in top) / len(top),
    }


def add_verdicts(summary):
    """Verdicts need the scene's best unbiased work (relMSE x seconds), so they come last."""
    for scene in {s["scene"] for s in summary}:
        rows = [s for s in summary if s["scene"] == scene and s["accel"] == DEFAULT_ACCEL]
        unbiased = [s["work"] for s in rows if sm.verdict(s, 0.0) in ("converges", "converges slowly") and s["work"] > 0]
        best = min(unbiased) if unbiased else 0.0
        for s in [s for s in summary if s["scene"] == scene]:
            s["work_ratio"] = s["work"] / best if best > 0 else float("nan")
            s["verdict"] = sm.verdict(s, best)


def study_scene(args, tess, ref, tmp, integrators, accels):
    """Every series of one scene; returns its runs, summaries (no verdicts yet), floor and notes."""
    notes = []
    study = SceneStudy(args, tess, ref, tmp)
    log(f"study: {ref.name} ({ref.scene}) at {study.resolution[0]}x{study.resolution[1]}"
        f"{'' if study.factor == 1 else f' (1/{study.factor} of the reference)'}, "
        f"reference noise relMSE {study.floor:.2g}")
    for integrator in integrators:
        study.series(integrator, DEFAULT_ACCEL)
    if args.accel_integrator not in integrators:
        study.series(args.accel_integrator, DEFAULT_ACCEL)
    # Same spp and seeds as the default accelerator, one seed per budget: the images agree with the
    # default accelerator's, only the time moves.
    base_plan = {}
    for r in study.runs:
        if r["integrator"] == args.accel_integrator and r["accel"] == DEFAULT_ACCEL:
            base_plan.setdefault(r["spp"], r["seed"])
    base_plan = sorted(base_plan.items())
    for accel in accels:
        if accel == DEFAULT_ACCEL:
            continue
        why = study.accel_too_slow(accel)
        if why:
            notes.append(f"{ref.name}: {why}: left out.")
            log(f"study: {ref.name}: {why}: left out")
            continue
        study.series(args.accel_integrator, accel, base_plan)
    summary = [s for s in (summarise(study, *k) for k in study.pooled) if s]
    if ref.stderr is None:
        notes.append(f"{ref.name}: no standard-error image for the reference: its noise is not subtracted.")
    if study.mask is not None:
        notes.append(mask_note(ref.name, study.mask))
    if study.budget_scale != 1:
        notes.append(f"{ref.name}: rare-event scene: every series aims its largest render at ~{study.max_seconds:g} s "
                     f"({study.budget_scale:g}x the other scenes' budget; tools/study_run.py, RARE_EVENT_BUDGET_SCALE).")
    return {"runs": study.runs, "summary": summary, "floor": study.floor, "failures": study.failures, "notes": notes}


def add_missing_series(args, tess, ref, tmp, integrators, part, cache_path):
    """--add-integrators: renders the series of the integrators a cached scene lacks and adds them to
    its rows (the verdicts are recomputed with every row of the scene afterwards)."""
    have = {s["integrator"] for s in part["summary"] if s["accel"] == DEFAULT_ACCEL}
    missing = [i for i in integrators if i not in have]
    if not missing:
        return
    t0 = time.time()
    study = SceneStudy(args, tess, ref, tmp)
    study.seed_counter = max((r["seed"] for r in part["runs"]), default=0)  # seeds of their own
    log(f"study: {ref.name}: adding {', '.join(missing)} to the cached rows")
    for integrator in missing:
        study.series(integrator, DEFAULT_ACCEL)
    part["runs"] += study.runs
    part["summary"] += [s for s in (summarise(study, *k) for k in study.pooled) if s]
    part["failures"] += study.failures
    part["minutes"] = part.get("minutes", 0.0) + (time.time() - t0) / 60
    with open(cache_path, "w") as f:
        json.dump(part, f)


def mask_note(name, mask):
    return (f"{name}: judged on the {100 * mask.mean():.1f}% of pixels that refs/{name}-mask.exr keeps (no mirror "
            f"or glass seen directly): every render and the reference are zeroed elsewhere before any metric.")


def cache_key(args, ref, integrators, accels):
    """What a cached scene depends on: reference and scene bytes, study code version and settings. Not
    the renderer binary: a resumed study trusts that merges in between did not change its images."""
    h = hashlib.sha256()
    mask_path = ref.path[:-4] + study_refs.MASK_SUFFIX
    for path in (ref.path, ref.stderr_path, ref.scene) + ((mask_path,) if os.path.isfile(mask_path) else ()):
        if path and os.path.isfile(path):
            with open(path, "rb") as f:
                h.update(f.read())
    h.update(STUDY_VERSION.encode())
    h.update(json.dumps([integrators, accels, args.accel_integrator, args.seeds, args.budgets, args.max_seconds,
                         args.downsample, args.threads]).encode())
    scale = budget_scale(args, ref.name)
    if scale != 1:  # only then: the keys of every other scene stay those of earlier studies
        h.update(f"budget scale {scale:g}".encode())
    return h.hexdigest()


def load_cache(path, key):
    try:
        with open(path) as f:
            part = json.load(f)
    except (OSError, ValueError):
        return None
    return part if part.get("key") == key else None


_INT_FIELDS = {"spp", "seed", "width", "height", "renders", "nonfinite_samples", "nonfinite_pixels"}
_STR_FIELDS = {"scene", "integrator", "accel", "spp_series", "verdict"}


def _typed(row):
    out = {}
    for k, v in row.items():
        if k in _STR_FIELDS:
            out[k] = v
        elif k in _INT_FIELDS:
            out[k] = int(v)
        elif k == "ref_limited":
            out[k] = v == "True"
        else:
            out[k] = float(v) if v not in ("", "nan") else float("nan")
    return out


def seed_cache_from_tables(args, refs, integrators, accels):
    """--seed-cache: writes a cache entry (as --resume reads it) for every scene that has rows in the
    tables already in --out (runs.csv, summary.csv, the per-scene notes of stability.md) and no
    cache entry yet, keyed on today's reference, scene and settings. A following --resume then
    renders only the scenes that are new or changed, and the tables keep every other scene's rows:
    how a committed study gains a scene without re-running 35 minutes of renders."""
    import csv
    try:
        with open(os.path.join(args.out, "runs.csv")) as f:
            runs = [_typed(r) for r in csv.DictReader(f)]
        with open(os.path.join(args.out, "summary.csv")) as f:
            summary = [_typed(r) for r in csv.DictReader(f)]
    except OSError as e:
        log(f"study: --seed-cache: no tables in {args.out} ({e}); nothing seeded")
        return
    scene_notes = []
    try:
        with open(os.path.join(args.out, "stability.md")) as f:
            scene_notes = [line[2:].strip() for line in f if line.startswith("- ")]
    except OSError:
        pass
    minutes_total, table_scales = 0.0, {}
    try:
        with open(os.path.join(args.out, "study.json")) as f:
            study_json = json.load(f)
        minutes_total = float(study_json.get("minutes", 0.0))
        table_scales = study_json.get("budget_scales", {})
    except (OSError, ValueError):
        pass
    seconds_all = sum(r["seconds"] for r in runs) or 1.0
    os.makedirs(args.cache, exist_ok=True)
    for ref in refs:
        path = os.path.join(args.cache, f"{ref.name}.json")
        rows = [r for r in runs if r["scene"] == ref.name]
        sums = [s for s in summary if s["scene"] == ref.name]
        if os.path.exists(path) or not rows or not sums:
            continue
        if table_scales.get(ref.name, 1) != budget_scale(args, ref.name):
            log(f"study: {ref.name}: the tables in {args.out} were rendered at another budget: not seeded")
            continue
        for s in sums:
            s.pop("verdict", None)  # recomputed with the other rows of the scene
        part = {"runs": rows, "summary": sums, "floor": sums[0]["ref_floor"], "failures": [],
                "notes": [n for n in scene_notes if n.startswith(ref.name + ":")],
                "key": cache_key(args, ref, integrators, accels),
                "minutes": minutes_total * sum(r["seconds"] for r in rows) / seconds_all}
        with open(path, "w") as f:
            json.dump(part, f)
        log(f"study: {ref.name}: cache seeded from {args.out}/ ({len(rows)} renders)")


def run(args, tess, refs, notes, argv):
    t_start = time.time()
    args.binary = tess.binary
    integrators = args.integrators or tess.integrators()
    if args.samplers:
        integrators = [f"{i}/{s}" for i in integrators for s in args.samplers]
    accels = args.accels or (["embree", "bvh"] if args.quick else tess.accels())
    if DEFAULT_ACCEL not in accels:
        accels = [DEFAULT_ACCEL] + accels
    command = "tools/study " + " ".join(shlex.quote(a) for a in argv)
    all_runs, summary, failures, floors, minutes = [], [], [], {}, 0.0
    if args.seed_cache:
        seed_cache_from_tables(args, refs, integrators, accels)
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="study-") as tmp:
        for ref in refs:
            key = cache_key(args, ref, integrators, accels)
            cache_path = os.path.join(args.cache, f"{ref.name}.json")
            cached = load_cache(cache_path, key) if args.resume else None
            if cached:
                log(f"study: {ref.name}: reusing {cache_path} (same reference, scene and settings)")
                part = cached
                if args.add_integrators and not args.only_cached:
                    add_missing_series(args, tess, ref, tmp, integrators, part, cache_path)
            elif args.only_cached:
                notes.append(f"{ref.name}: has a reference but was not studied (no cached results).")
                log(f"study: {ref.name}: no cached results: left out (--only-cached)")
                continue
            else:
                t0 = time.time()
                part = study_scene(args, tess, ref, tmp, integrators, accels)
                part["key"], part["minutes"] = key, (time.time() - t0) / 60
                os.makedirs(args.cache, exist_ok=True)
                with open(cache_path, "w") as f:
                    json.dump(part, f)
            summary += part["summary"]
            floors[ref.name] = part["floor"]
            all_runs += part["runs"]
            failures += part["failures"]
            notes += part["notes"]
            minutes += part.get("minutes", 0.0)
    for s in summary:
        rows = [r for r in all_runs if (r["scene"], r["integrator"], r["accel"]) == (s["scene"], s["integrator"], s["accel"])]
        # The slope over the series' budgets only: the lone 1-spp calibration render (one seed) is
        # left out unless the series starts there, as its error is the least representative.
        pts = [p for p in study_report.per_budget(rows)
               if sum(1 for r in rows if r["spp"] == p[0]) > 1 or args.seeds == 1 or s["accel"] != DEFAULT_ACCEL]
        s["slope"] = sm.loglog_slope([p[1] for p in pts], [p[2] - floors[s["scene"]] for p in pts])
        # Seed agreement at the largest budget (a heavy-tail sign for the verdicts).
        top = max(r["spp"] for r in rows)
        rel = [r["relmse"] for r in rows if r["spp"] == top and r["relmse"] > 0]
        s["seed_spread"] = max(rel) / min(rel) if rel else float("nan")
    add_verdicts(summary)
    for name, floor in floors.items():
        verdicts = {s["integrator"]: s["verdict"] for s in summary if s["scene"] == name and s["accel"] == DEFAULT_ACCEL}
        study_report.scene_chart(os.path.join(args.out, f"{name}.png"), name,
                                 [r for r in all_runs if r["scene"] == name], args.accel_integrator,
                                 DEFAULT_ACCEL, floor, verdicts)
    order = {n: i for i, n in enumerate(integrators)}
    summary.sort(key=lambda s: (s["scene"], s["accel"] != DEFAULT_ACCEL, order.get(s["integrator"], 99), s["accel"]))
    study_report.write_csv(os.path.join(args.out, "runs.csv"), study_report.RUN_FIELDS, all_runs)
    study_report.write_csv(os.path.join(args.out, "summary.csv"), study_report.SUMMARY_FIELDS, summary)
    study_report.speed_chart(os.path.join(args.out, "speed.png"), summary, args.accel_integrator)
    elapsed = time.time() - t_start
    scales = {r.name: budget_scale(args, r.name) for r in refs if budget_scale(args, r.name) != 1}
    scaled = "".join(f", {v:g}x on {k}" for k, v in sorted(scales.items()))
    notes = list(notes) + [f"{len(all_runs)} renders, {minutes:.1f} min wall in all on {args.threads} threads; "
                           f"seeds {args.seeds}, budgets {args.budgets}, largest render ~{args.max_seconds:g} s{scaled}, "
                           f"resolution 1/{args.downsample} of each reference (box-downsampled)."]
    notes += [f"FAILED: {f}" for f in failures]
    study_report.stability_markdown(os.path.join(args.out, "stability.md"), summary, DEFAULT_ACCEL, command,
                                    ["## Notes", ""] + [f"- {n}" for n in notes])
    with open(os.path.join(args.out, "study.json"), "w") as f:
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
        rel = lambda v: os.path.relpath(v, root) if isinstance(v, str) and v.startswith(root) else v
        json.dump({"command": command, "args": {k: rel(v) for k, v in vars(args).items()},
                   "scenes": [r.name for r in refs], "integrators": integrators, "accels": accels,
                   "minutes": minutes, "failures": failures, "budget_scales": scales}, f, indent=1)
    log(f"study: {len(all_runs)} renders in {elapsed:.0f} s -> {args.out}/ (stability.md, summary.csv, runs.csv, *.png)")
    for s in summary:
        if s["accel"] == DEFAULT_ACCEL:
            log(f"  {s['scene']:<22} {s['integrator']:<12} {s['verdict']:<17} slope {s['slope']:6.2f}  "
                f"bias {100 * s['bias_relative']:+6.2f}% ± {100 * s['bias_se'] / max(abs(s['ref_mean']), 1e-30):.2f}%")
    if failures:
        log(f"study: {len(failures)} series failed (see stability.md notes)")
        return 2 if args.quick else 0
    return 0
