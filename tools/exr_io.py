"""EXR input and output for the Python tools (tools/make_refs.py, tools/study): the one place they
read and write images, through OpenImageIO's Python binding (python3-openimageio)."""
import os

import numpy as np
import OpenImageIO as oiio


def read_exr(path):
    """(float64 RGB array [H, W, 3], metadata dict) of an image OpenImageIO can read. A one-channel
    image is repeated into three; channels past the third (alpha) are dropped."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(f"{path}: cannot open: {oiio.geterror()}")
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, min(spec.nchannels, 3), oiio.FLOAT)
    meta = {a.name: a.value for a in spec.extra_attribs}
    inp.close()
    if pixels is None:
        raise RuntimeError(f"{path}: cannot read pixels")
    pixels = np.asarray(pixels, dtype=np.float64).reshape(spec.height, spec.width, -1)
    if pixels.shape[2] == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    return pixels[:, :, :3], meta


def write_exr(path, rgb, meta=None, half=False):
    """Float32 RGB EXR (ZIP) with string metadata, written to a temporary file and renamed into place.
    half=True stores half floats: only for images with no value in half's subnormal range (below
    6.1e-5), which a reader running with denormals-are-zero (as renderer threads do) reads as 0
    (tools/make_refs_stats.py's storage_type decides)."""
    h, w, _ = rgb.shape
    spec = oiio.ImageSpec(w, h, 3, oiio.HALF if half else oiio.FLOAT)
    spec.channelnames = ("R", "G", "B")
    spec.attribute("compression", "zip")
    for k, v in (meta or {}).items():
        spec.attribute(k, str(v))
    tmp = path + ".tmp.exr"
    out = oiio.ImageOutput.create(tmp)
    if out is None or not out.open(tmp, spec):
        raise RuntimeError(f"{path}: cannot write: {oiio.geterror()}")
    out.write_image(np.ascontiguousarray(rgb, dtype=np.float32))
    out.close()
    os.replace(tmp, path)


def write_thumbnail(path, rgb, width=128):
    """An sRGB PNG `width` pixels wide of linear RGB (clamped to [0, 1])."""
    h, w, _ = rgb.shape
    lin = np.clip(rgb, 0.0, None)
    srgb = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(lin, 1 / 2.4) - 0.055)
    src = oiio.ImageBuf(oiio.ImageSpec(w, h, 3, oiio.FLOAT))
    src.set_pixels(oiio.ROI(0, w, 0, h), np.clip(srgb, 0, 1).astype(np.float32))
    th = max(1, round(h * width / w))
    dst = oiio.ImageBufAlgo.resize(src, roi=oiio.ROI(0, width, 0, th, 0, 1, 0, 3))
    dst.set_write_format(oiio.UINT8)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    if not dst.write(path):
        raise RuntimeError("cannot write " + path)
