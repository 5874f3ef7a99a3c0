"""Stereo figures: a colour-mapped disparity image and a rectified pair with epipolar rows.

matplotlib is imported inside the functions (only when a figure is made), with the Agg
backend.
"""

from __future__ import annotations

import io
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError

__all__ = ["disparity_png", "rectified_pair_png"]


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
