"""Stereo outputs: a colour-mapped disparity image, a rectified pair with epipolar rows,
and every file of a ``firefleet stereo`` run as bytes (:func:`run_files`; the CLI writes
them).

matplotlib is imported inside the functions (only when a figure is made), with the Agg
backend.
"""

from __future__ import annotations

import io
import math

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError
from firefleet.outputs import json_text
from firefleet.perception.stereo import StereoRun, ply_bytes

__all__ = ["disparity_png", "rectified_pair_png", "run_files"]


def _npy_bytes(array: NDArray[np.float32]) -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.asarray(array, dtype=np.float32), allow_pickle=False)
    return buf.getvalue()


def _png_bytes(image: NDArray[np.uint8], name: str) -> bytes:
    ok, buf = cv2.imencode(".png", image)
    if not ok:
        raise InputError(f"{name}: could not be encoded as PNG")
    return bytes(buf.tobytes())


def run_files(run: StereoRun) -> dict[str, bytes]:
    """The files of a :class:`~firefleet.perception.stereo.StereoRun`, name to content.

    ``rectified_left.png``, ``rectified_right.png``, ``disparity.npy`` (float32 [px],
    NaN where none), ``confidence.npy``, ``disparity.png``, ``rectified_pair.png`` (the
    pair side by side with rows drawn, to check the rectification by eye); with metric
    geometry also ``depth.npy`` (float32 [m], NaN where none), ``cloud.ply`` and
    ``scan.json``. ``summary.json`` is the caller's (it may add to it).
    """
    files = {
        "rectified_left.png": _png_bytes(run.rect_left, "rectified_left.png"),
        "rectified_right.png": _png_bytes(run.rect_right, "rectified_right.png"),
        "disparity.npy": _npy_bytes(run.result.disparity),
        "confidence.npy": _npy_bytes(run.result.confidence),
        "disparity.png": disparity_png(run.result.disparity),
        "rectified_pair.png": rectified_pair_png(run.rect_left, run.rect_right),
    }
    if run.depth_m is not None and run.scan is not None:
        files["depth.npy"] = _npy_bytes(run.depth_m)
        files["cloud.ply"] = ply_bytes(run.points, run.colors)
        files["scan.json"] = json_text(run.scan.to_dict()).encode("utf-8")
    return files


def disparity_png(
    disparity: ArrayLike,
    *,
    vmin: float | None = None,
    vmax: float | None = None,
    cmap: str = "turbo",
) -> bytes:
    """A PNG of a disparity map, one image pixel per map pixel, NaN drawn black.

    Parameters
    ----------
    disparity : array_like, shape (H, W)
        Disparity [px], NaN where none.
    vmin, vmax : float, optional
        Colour range [px]; by default the 1st and 99th percentiles of the values.
    cmap : str
        A matplotlib colour map (near disparities are red in ``turbo``).

    Returns
    -------
    bytes
        PNG data.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import colormaps
    from matplotlib.image import imsave

    d = np.asarray(disparity, dtype=np.float64)
    if d.ndim != 2:
        raise InputError(f"disparity must have shape (H, W), got {d.shape}")
    finite = d[np.isfinite(d)]
    lo = vmin if vmin is not None else (float(np.percentile(finite, 1)) if finite.size else 0.0)
    hi = vmax if vmax is not None else (float(np.percentile(finite, 99)) if finite.size else 1.0)
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        hi = lo + 1.0
    rgba = colormaps[cmap](np.clip((d - lo) / (hi - lo), 0.0, 1.0))
    rgba[~np.isfinite(d)] = (0.0, 0.0, 0.0, 1.0)
    buf = io.BytesIO()
    imsave(buf, (rgba[..., :3] * 255).round().astype(np.uint8), format="png")
    return buf.getvalue()


def rectified_pair_png(
    left: NDArray[np.uint8], right: NDArray[np.uint8], *, lines: int = 16
) -> bytes:
    """The rectified pair side by side with horizontal lines: matching points share a row.

    Parameters
    ----------
    left, right : ndarray of uint8, shape (H, W, 3) (BGR) or (H, W)
    lines : int
        Number of evenly spaced rows drawn across both images.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    if left.shape != right.shape:
        raise InputError(f"rectified images differ in shape: {left.shape} vs {right.shape}")
    h, w = left.shape[:2]

    def rgb(img: NDArray[np.uint8]) -> NDArray[np.uint8]:
        return np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img[..., ::-1]

    both = np.concatenate([rgb(left), rgb(right)], axis=1)
    fig = Figure(figsize=(2 * w / 100, h / 100 + 0.4), dpi=100)
    ax = fig.add_axes((0.0, 0.0, 1.0, h / (h + 40)))
    ax.imshow(both, interpolation="nearest")
    for y in np.linspace(0, h - 1, lines + 2)[1:-1]:
        ax.axhline(y, color="lime", lw=0.6, alpha=0.8)
    ax.axvline(w - 0.5, color="white", lw=1.0)
    ax.set_axis_off()
    fig.suptitle("rectified left | right: corresponding points lie on the same row", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
