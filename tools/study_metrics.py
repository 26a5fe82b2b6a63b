"""Metrics the renderer does not print, and the verdict rules of the stability table.

Definitions (writeup.md, section "Speed against accuracy", shows them at work):
- image mean m: mean over finite pixels and the three channels.
- bias = m_test - m_ref, pooled over every render of a series. Renders have independent seeds and
  Var(m_i) = sigma^2 / spp_i for an estimator that averages spp_i independent samples per pixel, so
  the pooled mean is the spp-weighted mean, sigma^2 is estimated from the spread of the m_i about it
  (n - 1 degrees of freedom) and SE_test = sqrt(sigma^2 / sum spp_i). The reference's own error
  adds: SE_ref = sqrt(sum_p se_p^2) / N_pixels with the channels taken as fully correlated
  (conservative). SE = sqrt(SE_test^2 + SE_ref^2).
- reference floor: E[(x - r)^2] = Var x + Var r for an unbiased x, so the measured relMSE contains
  mean(se^2 / (r^2 + 0.01)); it is subtracted before fitting, and a point with relMSE below 16x the
  floor is flagged (the rule: a reference must be >= 16x more accurate than what it judges).
- firefly share: share of the image's luminance in its brightest 0.01% of pixels (at least one).
- slope: least-squares slope of log relMSE (floor subtracted, mean over seeds) against log seconds.
- dark share: share of the reference's luminance in pixels where the pooled test image has under 10%
  of the reference value (where paths are missed, this is where they were).
"""
import math

import numpy as np

LUMA = np.array([0.2126, 0.7152, 0.0722])

# Verdict thresholds: stated in the table header (verdict_rules()) and used by verdict() alone.
BIAS_SIGMAS = 3.0          # |bias| > 3 SE ...
BIAS_SIGMAS_HEAVY = 5.0    # ... 5 SE when fireflies dominate (heavy tails: the spread underestimates SE)
BIAS_MIN_RELATIVE = 0.01   # ... and > 1% of the reference mean is a significant image-mean bias
SLOPE_CONVERGES = -0.7     # slope at least this steep: the error falls as 1/time (ideal -1)
SLOPE_PLATEAU = -0.4       # flatter than this without a mean bias: the error stops falling (local bias)
SLOW_FACTOR = 10.0         # relMSE x seconds at least 10x the scene's best unbiased method: slow
FIREFLY_FACTOR = 5.0       # test firefly share over 5x the reference's: fireflies dominate the error
SEED_SPREAD = 3.0          # relMSE max/min over the seeds of the largest budget: heavy tails
# Consistent, not unbiased (biased at any finite time, the bias shrinking with the merge radius):
# their verdict carries "(consistent)" and they are never the scene's best *unbiased* method.
CONSISTENT = ("sppm", "vcm")


def image_mean(rgb):
    finite = np.isfinite(rgb).all(axis=2)
    return float(rgb[finite].mean()) if finite.any() else float("nan")


def luminance(rgb):
    y = rgb @ LUMA
    return np.where(np.isfinite(y), np.maximum(y, 0.0), 0.0)


def firefly_share(rgb, fraction=1e-4):
    y = luminance(rgb).ravel()
    total = y.sum()
    if total <= 0:
        return 0.0
    k = max(1, int(round(fraction * y.size)))
    return float(np.partition(y, y.size - k)[y.size - k:].sum() / total)


def nonfinite_pixels(rgb):
    return int((~np.isfinite(rgb).all(axis=2)).sum())


def reference_floor(ref, ref_se):
    """Expected relMSE of the reference against the truth: mean(se^2 / (r^2 + 0.01))."""
    if ref_se is None:
        return 0.0
    return float(np.mean(ref_se ** 2 / (ref ** 2 + 0.01)))


def reference_mean_se(ref_se):
    if ref_se is None:
        return 0.0
    n = ref_se.shape[0] * ref_se.shape[1]
    return float(math.sqrt(np.sum(ref_se.mean(axis=2) ** 2)) / n)


def dark_share(pooled, ref, block=4):
    """Share of the reference's luminance in block x block tiles where the pooled test image has under
    10% of the reference's: averaging over tiles keeps the noise of a few dozen spp from reading as
    missing light, while a missed region (a caustic, what a mirror shows) stays dark."""
    h, w = ref.shape[0] // block * block, ref.shape[1] // block * block
    yr = luminance(ref[:h, :w]).reshape(h // block, block, w // block, block).mean(axis=(1, 3))
    yt = luminance(pooled[:h, :w]).reshape(h // block, block, w // block, block).mean(axis=(1, 3))
    total = yr.sum()
    if total <= 0:
        return 0.0
    return float(yr[yt < 0.1 * yr].sum() / total)


def pooled_bias(means, spps, ref_mean, ref_mean_se):
    """(bias, SE) of the image mean, pooled over independent renders (see module docstring)."""
    m = np.asarray(means, float)
    w = np.asarray(spps, float)
    ok = np.isfinite(m)
    m, w = m[ok], w[ok]
    if m.size == 0:
        return float("nan"), float("nan")
    pooled = float((w * m).sum() / w.sum())
    if m.size > 1:
        sigma2 = float((w * (m - pooled) ** 2).sum() / (m.size - 1))
        se_test = math.sqrt(sigma2 / w.sum())
    else:
        se_test = float("nan")
    return pooled - ref_mean, math.sqrt(se_test ** 2 + ref_mean_se ** 2)


def loglog_slope(seconds, relmse):
    """Least-squares slope of log relMSE against log seconds over the points with relMSE > 0."""
    x = np.asarray(seconds, float)
    y = np.asarray(relmse, float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def verdict_rules():
    return (
        "Verdict rules, applied in this order to the numbers in the row:\n"
        f"1. **NaN**: any non-finite sample dropped by the renderer or non-finite pixel in any render.\n"
        f"2. A significant image-mean bias is |bias| > {BIAS_SIGMAS:g} SE ({BIAS_SIGMAS_HEAVY:g} SE when the "
        f"firefly share is over {FIREFLY_FACTOR:g}x the reference's: heavy tails make the seed spread "
        f"underestimate SE) and |bias| > {BIAS_MIN_RELATIVE:.0%} of the reference mean. Every integrator "
        "is unbiased for the paths it "
        "can sample, so a significant **deficit** means **misses paths** (the dark share says where), "
        "and a significant **excess** means **biased**.\n"
        f"3. No significant mean bias but the fitted slope is flatter than {SLOPE_PLATEAU:g}: the error "
        "stops falling with time although the mean is right: **biased** (locally: energy in the wrong "
        "place), unless the signs of heavy tails are there: the slope is positive (the expected error "
        "of an average cannot rise with samples, so the low early errors are rare large samples not yet "
        f"drawn), the seeds disagree (relMSE max/min over {SEED_SPREAD:g}x at the largest budget) or "
        f"the firefly share is over {FIREFLY_FACTOR:g}x the reference's; then **converges slowly**.\n"
        f"4. Slope between {SLOPE_PLATEAU:g} and {SLOPE_CONVERGES:g}, or relMSE x seconds (work-normalised "
        f"error at the largest budget) at least {SLOW_FACTOR:g}x the best unbiased method's on the "
        f"scene, or a firefly share over {FIREFLY_FACTOR:g}x the reference's: **converges slowly**.\n"
        f"5. Otherwise (slope {SLOPE_CONVERGES:g} or steeper, ideal -1, and within {SLOW_FACTOR:g}x of "
        "the best): **converges**.\n"
        f"Photon-mapping integrators ({', '.join(CONSISTENT)}) are consistent, not unbiased: biased at any "
        "finite time by their merge kernel, the bias shrinking as the radius does (their slope tends to "
        "-alpha = -0.75 while variance dominates, -0.5 once the squared bias does). The same rules apply "
        "and their verdict says **(consistent)**; they are not counted as the scene's best unbiased "
        "method.\n"
    )


def verdict(row, best_work):
    """The verdict for one summary row (a dict from summarise()), by verdict_rules()."""
    v = _unlabelled_verdict(row, best_work)
    return f"{v} (consistent)" if row.get("integrator") in CONSISTENT else v


def _unlabelled_verdict(row, best_work):
    if row["nonfinite_samples"] > 0 or row["nonfinite_pixels"] > 0:
        return "NaN"
    bias, se, ref_mean = row["bias"], row["bias_se"], row["ref_mean"]
    fireflies = row["firefly_share"] > FIREFLY_FACTOR * max(row["ref_firefly_share"], 1e-12)
    sigmas = BIAS_SIGMAS_HEAVY if fireflies else BIAS_SIGMAS
    significant = (math.isfinite(bias) and math.isfinite(se) and abs(bias) > sigmas * se
                   and abs(bias) > BIAS_MIN_RELATIVE * abs(ref_mean))
    if significant:
        return "misses paths" if bias < 0 else "biased"
    slope = row["slope"]
    heavy = fireflies or row.get("seed_spread", 1.0) > SEED_SPREAD or (math.isfinite(slope) and slope > 0)
    if not math.isfinite(slope) or slope > SLOPE_PLATEAU:
        return "converges slowly" if heavy else "biased"
    if slope > SLOPE_CONVERGES or fireflies:
        return "converges slowly"
    if best_work > 0 and row["work"] >= SLOW_FACTOR * best_work:
        return "converges slowly"
    return "converges"
