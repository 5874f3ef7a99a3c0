"""Disparity of a rectified pair: plain SGBM and ours (checks, confidence, filling)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import Float32Array
from firefleet.errors import InputError
from firefleet.perception.stereo._images import (
    Image,
    _check_image,
    _grey,
    check_pair,
)


@dataclass(frozen=True, eq=False)
class DisparityResult:
    """Disparity of a rectified pair, with where it was measured and how much to trust it.

    Attributes
    ----------
    disparity : ndarray of float32, shape (H, W)
        Disparity [px] of the left image; NaN where there is no value.
    measured : ndarray of bool, shape (H, W)
        True where the matcher's value passed its checks (uniqueness, left-right,
        speckle); False where the value was filled in or is missing.
    confidence : ndarray of float32, shape (H, W)
        In [0, 1]: 0 where not measured; elsewhere the share of measured neighbours in
        a 5 x 5 window times ``1 / (1 + var)``, ``var`` the local disparity variance
        [px^2] of those neighbours (smooth, well-supported surfaces near 1).
    saturated : ndarray of bool, shape (H, W), or None
        True where the best match lay at the largest disparity searched
        (``min + num - 1``): the surface is at least that near, maybe nearer, so the
        value is no measurement; these pixels are NaN in ``disparity`` (never filled).
    textureless : ndarray of bool, shape (H, W), or None
        True where the left image has too little horizontal texture to match (a flat
        area wider than the matching window); not ``measured``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import compute_disparity
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> result = compute_disparity(left, np.roll(left, -8, axis=1), num_disparities=32)
    >>> result.disparity.shape, result.measured.dtype, result.confidence.dtype
    ((120, 160), dtype('bool'), dtype('float32'))
    """

    disparity: Float32Array
    measured: NDArray[np.bool_]
    confidence: Float32Array
    saturated: NDArray[np.bool_] | None = None
    textureless: NDArray[np.bool_] | None = None

    @property
    def saturated_share(self) -> float:
        """Share of pixels whose best match lay at the near end of the search range."""
        return 0.0 if self.saturated is None else float(self.saturated.mean())


def _check_num_disparities(num: int, width: int) -> None:
    if num <= 0 or num % 16 or num >= width:
        raise InputError(
            f"num_disparities must be a positive multiple of 16 below the image width "
            f"{width}, got {num}"
        )


def _sgbm_raw(
    left: Image,
    right: Image,
    *,
    min_disparity: int,
    num_disparities: int,
    block_size: int,
    p1_per_channel: int,
    p2_per_channel: int,
    uniqueness_pct: int,
    speckle_window_px: int,
    speckle_range_px: int,
    lr_max_diff_px: int,
    mode: int,
) -> Float32Array:
    _check_num_disparities(num_disparities, left.shape[1])
    if block_size < 1 or block_size % 2 == 0:
        raise InputError(f"block_size must be odd and >= 1, got {block_size}")
    cn = 1 if left.ndim == 2 else 3
    matcher = cv2.StereoSGBM.create(
        minDisparity=min_disparity,
        numDisparities=num_disparities,
        blockSize=block_size,
        P1=p1_per_channel * cn * block_size**2,
        P2=p2_per_channel * cn * block_size**2,
        disp12MaxDiff=lr_max_diff_px,
        uniquenessRatio=uniqueness_pct,
        speckleWindowSize=speckle_window_px,
        speckleRange=speckle_range_px,
        mode=mode,
    )
    raw = matcher.compute(left, right)
    disp: Float32Array = np.asarray(raw, dtype=np.float32) * np.float32(1.0 / 16.0)
    disp[raw < min_disparity * 16] = np.nan
    return disp


def sgbm_disparity(
    left: ArrayLike,
    right: ArrayLike,
    *,
    min_disparity: int = 0,
    num_disparities: int = 64,
    block_size: int = 5,
) -> Float32Array:
    """Plain OpenCV semi-global matching, with the parameters a user would choose.

    The reference that :func:`compute_disparity` is measured against. Parameters follow
    OpenCV's documentation and its ``stereo_match.py`` sample: the default full-range
    mode (``MODE_SGBM``, five directions), ``P1 = 8 cn b^2``, ``P2 = 32 cn b^2``
    (``cn`` channels, ``b`` block size), ``disp12MaxDiff = 1``, ``uniquenessRatio = 10``,
    ``speckleWindowSize = 100``, ``speckleRange = 32``; the images are passed as they
    come (colour if colour). No post-processing.

    Returns
    -------
    ndarray of float32, shape (H, W)
        Disparity [px] (1/16 px steps), NaN where SGBM gives none.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import sgbm_disparity
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> right = np.roll(left, -8, axis=1)  # everything 8 px to the left in the right image
    >>> float(np.nanmedian(sgbm_disparity(left, right, num_disparities=32)[:, 40:]))
    8.0
    """
    lft, rgt = check_pair(left, right)
    return _sgbm_raw(
        lft,
        rgt,
        min_disparity=min_disparity,
        num_disparities=num_disparities,
        block_size=block_size,
        p1_per_channel=8,
        p2_per_channel=32,
        uniqueness_pct=10,
        speckle_window_px=100,
        speckle_range_px=32,
        lr_max_diff_px=1,
        mode=cv2.STEREO_SGBM_MODE_SGBM,
    )


def _fill_background(disp: Float32Array) -> Float32Array:
    """Fill NaN runs of each row with the smaller of the two nearest values on that row.

    Holes left by the checks are mostly occlusions, which belong to the farther
    surface (the smaller disparity) beside them [1]_. Rows without any value stay NaN.
    """
    w = disp.shape[1]
    ok = ~np.isnan(disp)
    holes_y, holes_x = np.nonzero(~ok)
    if holes_y.size == 0:
        return disp
    cols = np.arange(w, dtype=np.int32)
    last = np.where(ok, cols, -1)
    np.maximum.accumulate(last, axis=1, out=last)
    nxt = np.where(ok, cols, w)[:, ::-1]
    np.minimum.accumulate(nxt, axis=1, out=nxt)
    nxt = nxt[:, ::-1]
    flat = np.concatenate([disp.ravel(), np.array([np.nan], np.float32)])
    base = holes_y * w
    li, ri = last[holes_y, holes_x], nxt[holes_y, holes_x]
    lv = flat[np.where(li >= 0, base + li, flat.size - 1)]
    rv = flat[np.where(ri < w, base + ri, flat.size - 1)]
    out = disp.copy()
    out[holes_y, holes_x] = np.fmin(lv, rv)
    return out


def _confidence(disp: Float32Array, measured: NDArray[np.bool_]) -> Float32Array:
    m = measured.astype(np.float32)
    d = np.where(measured, disp, 0.0).astype(np.float32)
    k = (5, 5)
    share = cv2.boxFilter(m, -1, k, normalize=True, borderType=cv2.BORDER_REPLICATE)
    s1 = cv2.boxFilter(d, -1, k, normalize=True, borderType=cv2.BORDER_REPLICATE)
    s2 = cv2.boxFilter(d * d, -1, k, normalize=True, borderType=cv2.BORDER_REPLICATE)
    safe = np.maximum(share, 1e-6)
    var = np.maximum(s2 / safe - (s1 / safe) ** 2, 0.0)
    conf = share / (1.0 + var)
    conf[~measured] = 0.0
    return np.asarray(conf, dtype=np.float32)


def texture(image: ArrayLike, *, window_px: int = 7) -> Float32Array:
    """Horizontal texture of an image: the local mean of ``|dI/dx|`` [grey levels / px].

    The central difference ``(I[x+1] - I[x-1]) / 2`` of the grey image, its absolute
    value averaged over a ``window_px`` square. Matching along rows needs it: where it
    is about zero (a flat wall, a black frame, the sky) every disparity fits equally.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W) or (H, W, 3)
    window_px : int
        Side of the averaging window [px] (odd).

    Returns
    -------
    ndarray of float32, shape (H, W)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import texture
    >>> flat = np.full((20, 30), 128, np.uint8)
    >>> noisy = (np.random.default_rng(0).random((20, 30)) * 255).astype(np.uint8)
    >>> float(texture(flat).max()), bool(texture(noisy).mean() > 10)
    (0.0, True)
    """
    img = _check_image(image, "image")
    if window_px < 1 or window_px % 2 == 0:
        raise InputError(f"window_px must be odd and >= 1, got {window_px}")
    g = _grey(img).astype(np.float32)
    dx = np.zeros_like(g)
    dx[:, 1:-1] = 0.5 * np.abs(g[:, 2:] - g[:, :-2])
    k = (window_px, window_px)
    return np.asarray(
        cv2.boxFilter(dx, -1, k, normalize=True, borderType=cv2.BORDER_REPLICATE),
        dtype=np.float32,
    )


def compute_disparity(
    left: ArrayLike,
    right: ArrayLike,
    *,
    min_disparity: int = 0,
    num_disparities: int = 64,
    block_size: int = 3,
    uniqueness_pct: int = 10,
    lr_max_diff_px: int = 1,
    speckle_window_px: int = 100,
    speckle_range_px: int = 2,
    fill_holes: bool = True,
    median_px: int = 5,
    min_texture: float = 0.5,
) -> DisparityResult:
    """Disparity of a rectified pair: SGBM, then checks, confidence and hole filling.

    1. Semi-global matching [1]_ in OpenCV's parallel three-way mode
       (``MODE_SGBM_3WAY``), colour if given, ``P1 = 8 cn b^2``, ``P2 = 24 cn b^2``,
       sub-pixel by parabola fitting (1/16 px).
    2. A best match at either end of the search range is no measurement: at the far
       end (``min``) the surface may be farther, at the near end (``min + num - 1``) it
       may be nearer (``saturated``: kept NaN, never filled). Pixels with less
       horizontal texture than ``min_texture`` (:func:`texture`) are not measured.
       Checks: uniqueness (the best cost ``uniqueness_pct`` % below the second best),
       left-right consistency (``disp12MaxDiff``: the right view's disparity, taken from
       the same aggregated costs as in [1]_, within ``lr_max_diff_px``), and a tight
       speckle filter (regions under ``speckle_window_px`` pixels whose disparity
       varies by more than ``speckle_range_px`` are rejected).
    3. Confidence (see :class:`DisparityResult`).
    4. Hole filling: rejected pixels take the smaller (farther) of the nearest measured
       values left and right on their row: occlusions belong to the background.
    5. An edge-preserving 5 x 5 median removes the streaks that row-wise filling leaves.

    On the Middlebury Motorcycle pair this gives about a third fewer bad-2.0 pixels than
    :func:`sgbm_disparity` at about its speed (``bench/stereo.py``).

    Parameters
    ----------
    left, right : ndarray of uint8, shape (H, W) or (H, W, 3)
        Rectified pair.
    min_disparity, num_disparities : int
        Search range ``[min, min + num)`` [px]; ``num`` a multiple of 16.
    fill_holes : bool
        Step 4 (and 5); without it, rejected pixels are NaN.
    median_px : int
        Median window, 0 (none), 3 or 5.
    min_texture : float
        Least mean ``|dI/dx|`` in a 7 x 7 window for a pixel to count as measured
        [grey levels / px]; 0 disables the test.

    Returns
    -------
    DisparityResult

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import compute_disparity
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> result = compute_disparity(left, np.roll(left, -8, axis=1), num_disparities=32)
    >>> float(np.nanmedian(result.disparity[result.measured]))
    8.0
    """
    lft, rgt = check_pair(left, right)
    if median_px not in (0, 3, 5):
        raise InputError(f"median_px must be 0, 3 or 5, got {median_px}")
    disp = _sgbm_raw(
        lft,
        rgt,
        min_disparity=min_disparity,
        num_disparities=num_disparities,
        block_size=block_size,
        p1_per_channel=8,
        p2_per_channel=24,
        uniqueness_pct=uniqueness_pct,
        speckle_window_px=speckle_window_px,
        speckle_range_px=speckle_range_px,
        lr_max_diff_px=lr_max_diff_px,
        mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY,
    )
    if not (math.isfinite(min_texture) and min_texture >= 0):
        raise InputError(f"min_texture must be >= 0, got {min_texture}")
    # SGBM gives exact integers at the ends of the range (no sub-pixel fit there)
    near_end = np.float32(min_disparity + num_disparities - 1)
    saturated = disp == near_end
    disp[saturated | (disp == np.float32(min_disparity))] = np.nan
    textureless = texture(lft) < min_texture
    measured = ~np.isnan(disp) & ~textureless
    confidence = _confidence(disp, measured)
    if fill_holes:
        disp = _fill_background(disp)
        if median_px:
            nan = np.isnan(disp)
            med = cv2.medianBlur(np.where(nan, np.float32(0.0), disp), median_px)
            disp = np.where(nan, np.float32(np.nan), med)
        disp[saturated] = np.nan
    return DisparityResult(
        disparity=np.asarray(disp, dtype=np.float32),
        measured=measured,
        confidence=confidence,
        saturated=saturated,
        textureless=textureless,
    )
