"""CSV, PNG charts and the Markdown stability table of the convergence study."""
import csv
import io
import math
import os

import matplotlib

matplotlib.use("Agg")  # no display in CI
import matplotlib.pyplot as plt  # noqa: E402
from PIL import Image  # noqa: E402  (python3-pil comes with python3-matplotlib)

import study_metrics  # noqa: E402

RUN_FIELDS = ["scene", "integrator", "accel", "spp", "seed", "width", "height", "seconds",
              "build_seconds", "samples_per_second", "relmse", "rmse", "mean_test", "mean_ref",
              "firefly_share", "nonfinite_samples", "nonfinite_pixels", "ref_floor"]
SUMMARY_FIELDS = ["scene", "integrator", "accel", "renders", "spp_series", "seconds_top", "relmse_top",
                  "slope", "seed_spread", "work", "ref_mean", "bias", "bias_se", "bias_relative", "firefly_share",
                  "ref_firefly_share", "nonfinite_samples", "nonfinite_pixels", "dark_share",
                  "ref_floor", "ref_limited", "samples_per_second", "verdict"]

COLOURS = {"pt": "#d62728", "ptnee": "#1f77b4", "lt": "#ff7f0e", "bdpt": "#2ca02c",
           "bdpt-balance": "#9467bd", "sppm": "#8c564b", "embree": "#1f77b4", "bvh": "#2ca02c", "brute": "#7f7f7f",
           "kdtree": "#ff7f0e"}


def _save(fig, path):
    """PNG with a 64-colour palette: the charts are flat colours, and the repository keeps them."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    buf.seek(0)
    Image.open(buf).convert("RGB").convert("P", palette=Image.ADAPTIVE, colors=64).save(path, optimize=True)


def write_csv(path, fields, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def per_budget(runs):
    """[(spp, mean seconds, mean relMSE, min relMSE, max relMSE)] over seeds, by spp."""
    out = []
    for spp in sorted({r["spp"] for r in runs}):
        pts = [r for r in runs if r["spp"] == spp and math.isfinite(r["relmse"])]
        if not pts:
            continue
        rel = [r["relmse"] for r in pts]
        out.append((spp, sum(r["seconds"] for r in pts) / len(pts), sum(rel) / len(rel), min(rel), max(rel)))
    return out


def _series_plot(ax, runs_by_key, floor, title, labels=None):
    for key, runs in runs_by_key.items():
        pts = per_budget(runs)
        if not pts:
            continue
        x = [p[1] for p in pts]
        y = [p[2] for p in pts]
        # max(0, ·): the mean of equal values can round one ulp below their minimum.
        err = [[max(0.0, p[2] - p[3]) for p in pts], [max(0.0, p[4] - p[2]) for p in pts]]
        biased = labels and (labels.get(key) or "").split(" (")[0] in ("misses paths", "biased", "NaN")
        ax.errorbar(x, y, yerr=err, marker="o", ms=3, lw=1.2, capsize=2, ls="--" if biased else "-",
                    label=f"{key}: {labels[key]}" if labels and key in labels else key, color=COLOURS.get(key))
    if floor > 0:
        ax.axhline(floor, color="k", ls=":", lw=0.8, label="reference noise")
    # A slope -1 guide through the plot's centre.
    ax.set_xscale("log")
    ax.set_yscale("log")
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    xc, yc = math.sqrt(x0 * x1), math.sqrt(y0 * y1)
    ax.plot([xc / 4, xc * 4], [yc * 4, yc / 4], color="0.6", lw=0.8, ls="--", label="slope -1")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_xlabel("render seconds")
    ax.set_ylabel("relMSE")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="major", lw=0.3)
    ax.legend(fontsize=7, loc="best")


def scene_chart(path, scene, runs, accel_integrator, default_accel, floor, verdicts=None):
    """Left: one line per integrator (default accelerator). Right: one per accelerator (fixed integrator)."""
    by_int = {}
    by_acc = {}
    for r in runs:
        if r["accel"] == default_accel:
            by_int.setdefault(r["integrator"], []).append(r)
        if r["integrator"] == accel_integrator:
            by_acc.setdefault(r["accel"], []).append(r)
    ncols = 2 if len(by_acc) > 1 else 1
    fig, axes = plt.subplots(1, ncols, figsize=(4.6 * ncols, 3.5), dpi=80, squeeze=False)
    _series_plot(axes[0][0], by_int, floor, f"{scene}: integrators ({default_accel})", verdicts)
    if ncols == 2:
        _series_plot(axes[0][1], by_acc, floor, f"{scene}: accelerators ({accel_integrator})")
    fig.tight_layout()
    _save(fig, path)


def speed_chart(path, summary, accel_integrator):
    rows = [s for s in summary if s["integrator"] == accel_integrator]
    scenes = sorted({s["scene"] for s in rows})
    accels = sorted({s["accel"] for s in rows}, key=lambda a: (a != "embree", a))
    if not scenes or not accels:
        return
    fig, ax = plt.subplots(figsize=(max(4.0, 0.9 * len(scenes) + 1.5), 3.4), dpi=80)
    width = 0.8 / len(accels)
    for i, a in enumerate(accels):
        vals = []
        for sc in scenes:
            hit = [s for s in rows if s["scene"] == sc and s["accel"] == a]
            vals.append(hit[0]["samples_per_second"] / 1e6 if hit else 0.0)
        ax.bar([j + (i - (len(accels) - 1) / 2) * width for j in range(len(scenes))], vals, width,
               label=a, color=COLOURS.get(a))
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes, rotation=30, ha="right", fontsize=7)
    ax.set_ylabel(f"M samples/s ({accel_integrator})")
    ax.set_title("render speed per accelerator", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, axis="y", lw=0.3)
    fig.tight_layout()
    _save(fig, path)


def _fmt(v, spec=".3g"):
    return "–" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def stability_markdown(path, summary, default_accel, command, notes):
    lines = ["# Stability table", "",
             f"Produced by `{command}`. One row per scene x integrator ({default_accel}); the numbers "
             "are in `summary.csv`, every render in `runs.csv`.", "",
             study_metrics.verdict_rules(),
             "Columns: **slope** of log relMSE vs log seconds (reference noise subtracted); **bias** = "
             "pooled image mean minus the reference's, with its standard error and as a share of the "
             "reference mean; **relMSE** at the largest budget and its seconds; **work** = relMSE x "
             "seconds there, as a multiple of the scene's best unbiased method; **fireflies** = share "
             "of luminance in the brightest 0.01% of pixels, test / reference; **NaN** = non-finite "
             "samples dropped / pixels; **dark** = share of the reference's light in 4x4-pixel "
             "tiles the method (all its renders pooled) leaves under 10% bright.", ""]
    lines += ["| scene | integrator | verdict | slope | bias ± SE (rel.) | relMSE @ s | work | fireflies | NaN | dark |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        if s["accel"] != default_accel:
            continue
        bias = (f"{_fmt(s['bias'], '+.3g')} ± {_fmt(s['bias_se'], '.2g')} ({_fmt(100 * s['bias_relative'], '+.1f')}%)"
                if math.isfinite(s["bias"]) else "–")
        lim = " (ref-limited)" if s["ref_limited"] else ""
        lines.append(
            f"| {s['scene']} | {s['integrator']} | **{s['verdict']}** | {_fmt(s['slope'], '.2f')} | {bias} | "
            f"{_fmt(s['relmse_top'])} @ {_fmt(s['seconds_top'], '.2g')} s{lim} | {_fmt(s['work_ratio'], '.2g')}x | "
            f"{_fmt(s['firefly_share'], '.2g')} / {_fmt(s['ref_firefly_share'], '.2g')} | "
            f"{s['nonfinite_samples']} / {s['nonfinite_pixels']} | {_fmt(100 * s['dark_share'], '.0f')}% |")
    lines.append("")
    lines += notes
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
