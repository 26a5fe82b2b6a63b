"""Reference discovery and box downsampling for the convergence study.

A reference is refs/<name>.exr (any depth below refs/, except refs/study/) with, when present, its
per-pixel standard-error image beside it (refs/<name>.stderr.exr or one of the spellings in
STDERR_SUFFIXES) and, when present, a mask (refs/<name>-mask.exr: the pixels the scene is judged on). The scene it shows comes from the EXR's `tessera:scene` attribute, written by every
`tessera render`; failing that, from scenes/**/<name>.gltf. So new references join the study by being
committed, with no list to edit.
"""
import glob
import os

import numpy as np

from exr_io import read_exr

# Spellings of the standard-error companion image, tried in order ("<name><suffix>").
STDERR_SUFFIXES = [".stderr.exr", "-stderr.exr", "_stderr.exr", ".se.exr", "-se.exr", "_se.exr",
                   ".sem.exr", "-sem.exr"]
# Variance companions are accepted too (square-rooted on reading).
VARIANCE_SUFFIXES = [".variance.exr", "-variance.exr", "_variance.exr", ".var.exr", "-var.exr"]
# The mask companion (tools/make_refs.py): 1 where every method samples well; the study judges only
# those pixels (the others are zeroed in the reference and in every render before any metric).
MASK_SUFFIX = "-mask.exr"


class Reference:
    """One reference image: its name, scene, resolution, pixels and standard error (or None)."""

    def __init__(self, name, path, scene, rgb, stderr, meta, stderr_path, mask=None):
        self.name = name
        self.path = path
        self.scene = scene
        self.rgb = rgb  # float64 [H, W, 3]
        self.stderr = stderr  # float64 [H, W, 3] or None
        self.meta = meta
        self.stderr_path = stderr_path
        self.mask = mask  # bool [H, W] or None

    @property
    def width(self):
        return self.rgb.shape[1]

    @property
    def height(self):
        return self.rgb.shape[0]


def _is_companion(path):
    low = path.lower()
    return any(low.endswith(s) for s in STDERR_SUFFIXES + VARIANCE_SUFFIXES + [MASK_SUFFIX])


def _find_scene(root, name, meta):
    scene = meta.get("tessera:scene")
    if scene:
        for cand in (scene, os.path.join(root, scene)):
            if os.path.isfile(cand):
                return os.path.relpath(os.path.abspath(cand), root)
    for ext in ("gltf", "glb"):
        hits = sorted(glob.glob(os.path.join(root, "scenes", "**", f"{name}.{ext}"), recursive=True))
        if hits:
            return os.path.relpath(hits[0], root)
    return None


def discover(root, refs_dir, names=None, warn=print):
    """References under refs_dir whose scene exists, optionally only those in `names`."""
    found = []
    paths = sorted(glob.glob(os.path.join(refs_dir, "**", "*.exr"), recursive=True))
    for path in paths:
        rel = os.path.relpath(path, refs_dir)
        if rel.split(os.sep)[0] == "study" or _is_companion(path):
            continue
        name = os.path.basename(path)[:-4]
        if names and name not in names:
            continue
        rgb, meta = read_exr(path)
        scene = _find_scene(root, name, meta)
        if scene is None:
            warn(f"study: {path}: no scene found (no tessera:scene attribute, no scenes/**/{name}.gltf): skipped")
            continue
        stderr, stderr_path = None, None
        base = path[:-4]
        for suffix in STDERR_SUFFIXES + VARIANCE_SUFFIXES:
            if os.path.isfile(base + suffix):
                stderr_path = base + suffix
                stderr, _ = read_exr(stderr_path)
                if suffix in VARIANCE_SUFFIXES:
                    stderr = np.sqrt(np.maximum(stderr, 0.0))
                if stderr.shape != rgb.shape:
                    warn(f"study: {stderr_path}: size differs from {path}: ignored")
                    stderr, stderr_path = None, None
                break
        if stderr is None:
            warn(f"study: {path}: no standard-error image beside it: reference noise not subtracted")
        mask = None
        if os.path.isfile(base + MASK_SUFFIX):
            mask = read_exr(base + MASK_SUFFIX)[0][:, :, 0] > 0.5
            if mask.shape != rgb.shape[:2]:
                warn(f"study: {base + MASK_SUFFIX}: size differs from {path}: ignored")
                mask = None
        found.append(Reference(name, path, scene, rgb, stderr, meta, stderr_path, mask))
    if names:  # in the order asked for
        found.sort(key=lambda r: names.index(r.name))
        missing = sorted(set(names) - {r.name for r in found})
        for m in missing:
            warn(f"study: no reference for scene '{m}' under {refs_dir}")
    return found


def downsample_factor(width, height, wanted):
    """Largest f <= wanted dividing both sides (1 = full resolution)."""
    for f in range(max(1, wanted), 0, -1):
        if width % f == 0 and height % f == 0:
            return f
    return 1


def box_downsample(rgb, f):
    """Mean over f x f pixel blocks: exactly what a render at 1/f resolution estimates, because the
    renderer's pixels are box filters (camera samples are jittered uniformly over the pixel)."""
    if f == 1:
        return rgb
    h, w, c = rgb.shape
    return rgb.reshape(h // f, f, w // f, f, c).mean(axis=(1, 3))


def box_downsample_stderr(se, f):
    """Standard error of the block mean of independent pixels: sqrt(sum se^2) / f^2."""
    if se is None or f == 1:
        return se
    h, w, c = se.shape
    return np.sqrt((se.reshape(h // f, f, w // f, f, c) ** 2).sum(axis=(1, 3))) / (f * f)
