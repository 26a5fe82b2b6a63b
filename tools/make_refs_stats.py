"""The statistics of tools/make_refs.py: combining independent methods into one reference, their
agreement, the judged integrator's noise at the test's resolution, and the storage precision.

Every image is float64 [H, W, 3]; a method's renders are a stack [K, H, W, 3] of independent renders
(same spp, different seeds), so its mean's standard error is the sample standard deviation across the
K renders / sqrt(K): valid for splatting integrators (lt, bdpt) and for other renderers (Cycles) alike.
"""
import numpy as np

HALF_MIN_NORMAL = 2.0 ** -14  # half's smallest normal: below it a denormals-are-zero reader reads 0
HALF_MAX = 65504.0


def mean_and_stderr(stack):
    k = stack.shape[0]
    return stack.mean(axis=0), stack.std(axis=0, ddof=1) / np.sqrt(k)


def box_downsample(img, f):
    """Mean over f x f blocks: what a render at 1/f resolution estimates (pixels are box filters)."""
    if f == 1:
        return img
    h, w = img.shape[-3], img.shape[-2]
    lead = img.shape[:-3]
    return img.reshape(lead + (h // f, f, w // f, f, img.shape[-1])).mean(axis=(-4, -2))


def box_blur(img, r):
    """Mean over the (2r+1)^2 neighbourhood, clipped at the borders (per channel)."""
    pad = np.pad(img, ((r, r), (r, r), (0, 0)), mode="edge")
    c = np.cumsum(np.cumsum(pad, axis=0), axis=1)
    c = np.pad(c, ((1, 0), (1, 0), (0, 0)))
    n = 2 * r + 1
    h, w = img.shape[:2]
    return (c[n:n + h, n:n + w] - c[:h, n:n + w] - c[n:n + h, :w] + c[:h, :w]) / (n * n)


def combine(means, stderrs, valid, smooth_radius=4):
    """Inverse-variance combination of independent unbiased estimates of the same image.

    The weights use each method's variance blurred over a (2r+1)^2 neighbourhood (9x9 pixels): a
    weight from the pixel's own K renders (7 degrees of freedom) would correlate with the value it
    weights (renders that happened to be low also tend to have a low sample variance), a bias; the
    blurred variance hardly depends on the pixel's own samples. valid[m] ([H, W] bool) says where
    method m samples every path; elsewhere it gets weight 0. The standard error treats the weights as
    fixed: se^2 = sum w_m^2 se_m^2 / (sum w_m)^2."""
    num = np.zeros_like(means[0])
    den = np.zeros_like(means[0])
    var = np.zeros_like(means[0])
    for m, s, v in zip(means, stderrs, valid):
        sv = box_blur(s * s, smooth_radius)
        floor = max(float(np.mean(sv)), 1e-30) * 1e-6  # a black neighbourhood: equal weights
        w = np.where(v[:, :, None], 1.0 / (sv + floor), 0.0)
        num += w * m
        den += w
        var += w * w * s * s
    ok = den > 0
    safe = np.where(ok, den, 1.0)
    return np.where(ok, num / safe, 0.0), np.where(ok, np.sqrt(var) / safe, 0.0)


def _z(a, sa, b, sb):
    se = np.sqrt(sa ** 2 + sb ** 2)
    diff = b - a
    ok = se > 0
    return np.where(ok, diff / np.where(ok, se, 1.0), np.where(np.abs(diff) > 1e-6, np.inf, 0.0))


def agreement(a, sa, b, sb, mask=None, bin_size=8):
    """How well two independent estimates a, b (standard errors sa, sb) of one image agree, over the
    pixels of `mask` ([H, W] bool, default all):
      within_3se       fraction of pixel channels with |z| < 3, z = (b - a) / sqrt(sa^2 + sb^2)
                       (normal: 99.73%; K = 8 renders give sigma 7 degrees of freedom, so ~99%)
      bin_within_3se   the same on 8x8-pixel bin means (near normal even for fireflies), and
      bin_max_abs_z    the largest |z| of a bin (Sidak bound for ~n bins at 1%: ~sqrt(2 ln(200 n)))
      mean_rel_diff    per channel mean(b) / mean(a) - 1 over the mask
      mean_z           per channel: that difference over its standard error (pixels independent)
      relmse           mean (a - b)^2 / (a^2 + 0.01)"""
    if mask is None:
        mask = np.ones(a.shape[:2], bool)
    m3 = np.broadcast_to(mask[:, :, None], a.shape)
    z = _z(a, sa, b, sb)[m3]
    n = max(int(mask.sum()), 1)
    ma, mb = (x[m3].reshape(-1, 3).sum(axis=0) / n for x in (a, b))
    se_mean = np.sqrt((sa ** 2 + sb ** 2)[m3].reshape(-1, 3).sum(axis=0)) / n
    # Bins: only those wholly inside the mask.
    h, w = a.shape[:2]
    hb, wb = h // bin_size, w // bin_size
    crop = (slice(0, hb * bin_size), slice(0, wb * bin_size))
    mb_in = box_downsample(mask[crop][:, :, None].astype(float), bin_size)[:, :, 0] > 0.999
    A, B = box_downsample(a[crop], bin_size), box_downsample(b[crop], bin_size)
    SA = np.sqrt(box_downsample(sa[crop] ** 2, bin_size)) / bin_size
    SB = np.sqrt(box_downsample(sb[crop] ** 2, bin_size)) / bin_size
    zb = _z(A, SA, B, SB)[np.broadcast_to(mb_in[:, :, None], A.shape)]
    return {
        "pixels": int(mask.sum()),
        "within_3se": float(np.mean(np.abs(z) < 3.0)) if z.size else 1.0,
        "max_abs_z": float(np.max(np.abs(z))) if z.size else 0.0,
        "bin_within_3se": float(np.mean(np.abs(zb) < 3.0)) if zb.size else 1.0,
        "bin_max_abs_z": float(np.max(np.abs(zb))) if zb.size else 0.0,
        "bins": int(zb.size // 3),
        "mean_rel_diff": [float(x) for x in (mb / np.maximum(ma, 1e-30) - 1.0)],
        "mean_z": [float(x) for x in np.where(se_mean > 0, (mb - ma) / np.where(se_mean > 0, se_mean, 1), 0.0)],
        "relmse": float(np.mean(((a - b) ** 2 / (a ** 2 + 0.01))[m3])),
    }


def judged_stderr(stack, f):
    """Standard error of the judged integrator's mean at 1/f resolution: each render box-downsampled
    first, so the splatting integrators' pixel-to-pixel covariance is in it."""
    return mean_and_stderr(box_downsample(stack, f))[1]


def storage_type(img, is_stderr):
    """'half' when half floats hold the image without loss that matters, else 'float'. Half rounds by
    at most 2^-11 relative (tests/reference_ztest.h allows for it); a value in half's subnormal range
    would read as 0 in a denormals-are-zero thread, so a mean with such values stays float. A standard
    error that small is lifted to HALF_MIN_NORMAL by lift_stderr (only makes a Z-test more lenient, by
    a noise below 1e-4 absolute) and so can always be half."""
    a = np.abs(img[np.isfinite(img)])
    if a.size and a.max() >= HALF_MAX:
        return "float"
    if is_stderr:
        return "half"
    nz = a[a > 0]
    return "half" if (nz.size == 0 or nz.min() >= HALF_MIN_NORMAL) else "float"


def lift_stderr(se):
    return np.where((se > 0) & (se < HALF_MIN_NORMAL), HALF_MIN_NORMAL, se)


def round_to_half_precision(img):
    """float32 values rounded to nearest with half's 11 significant bits (2^-11 relative, the rounding
    tests/reference_ztest.h allows for) but float32's range: the 13 noise bits dropped make ZIP
    compress a float image about as well as a half one, without half's subnormal range."""
    bits = np.ascontiguousarray(img, dtype=np.float32).view(np.uint32).astype(np.uint64)
    bits = ((bits + 0x1000) & ~np.uint64(0x1FFF)).astype(np.uint32)
    return bits.view(np.float32).astype(np.float64)
