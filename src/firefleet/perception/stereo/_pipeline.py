"""The whole pair: rectify, match, depth, cloud and range scan, and a summary."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import Float32Array, FloatArray
from firefleet.errors import InputError
from firefleet.perception.stereo._calibration import StereoCalibration
from firefleet.perception.stereo._disparity import DisparityResult, compute_disparity
from firefleet.perception.stereo._geometry import (
    RangeScan,
    depth_from_disparity,
    point_cloud,
    range_scan,
)
from firefleet.perception.stereo._images import (
    Image,
    check_pair,
)
from firefleet.perception.stereo._rectify import (
    Rectification,
    rectify_calibrated,
    rectify_pair,
    rectify_uncalibrated,
)

log = logging.getLogger("firefleet.perception.stereo")


@dataclass(frozen=True, eq=False)
class StereoRun:
    """Everything :func:`process_pair` computes for one pair.

    Attributes
    ----------
    rect_left, rect_right : ndarray of uint8
        The rectified pair (the input pair itself in ``"rectified"`` mode).
    result : DisparityResult
        Disparity of ``rect_left`` [px].
    depth_m : ndarray of float32, shape (H, W), or None
        Depth [m] when the geometry is metric.
    points, colors : ndarray, shapes (M, 3)
        Point cloud [m] of the measured pixels and their RGB colours (empty if no depth).
    scan : RangeScan or None
        Virtual range scan of ``points`` (None if no depth).
    summary : dict
        Named numbers (SI units, unit in the key's suffix) for ``summary.json``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import process_pair
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> run = process_pair(left, np.roll(left, -8, axis=1), mode="rectified", focal_px=600.0,
    ...                    baseline_m=0.1, num_disparities=32)
    >>> run.rect_left.shape, run.depth_m.shape, run.points.shape[1], "measured_pct" in run.summary
    ((120, 160), (120, 160), 3, True)
    """

    rect_left: Image
    rect_right: Image
    result: DisparityResult
    depth_m: Float32Array | None
    points: FloatArray
    colors: Image
    scan: RangeScan | None
    summary: dict[str, Any]


SATURATED_SHARE = 0.002
"""Share of pixels at the near end of the search range from which a search counts as
saturated: something is nearer than the range can measure (0.2 %, some 600 pixels of a
640 x 480 image; a few stray edge matches stay below it)."""


def _ceil16(value: float) -> int:
    return int(16 * math.ceil(value / 16.0))


def _max_num_disparities(width: int, min_disparity: int) -> int:
    """The widest search: half the image width, a multiple of 16 (>= 16)."""
    return max(16, 16 * ((width // 2 - max(min_disparity, 0)) // 16))


def search_range_for(
    *,
    focal_px: float,
    baseline_m: float,
    doffs_px: float = 0.0,
    min_depth_m: float = 0.3,
    min_disparity: int = 0,
    width_px: int,
) -> int:
    """Disparities to search so that a surface ``min_depth_m`` away is inside the range.

    The nearest depth ``Z_min`` has disparity ``f B / Z_min - d_offs`` [px]; the range
    ``[min, min + num)`` must hold it with one pixel to spare (a best match at its last
    disparity is no measurement), rounded up to a multiple of 16 and capped at half
    the image width (then the near limit is farther than asked: see
    :func:`depth_limits`).

    Parameters
    ----------
    focal_px, baseline_m, doffs_px : float
        Rectified geometry [px, m, px].
    min_depth_m : float
        Nearest depth to measure [m].
    min_disparity : int
        Start of the range [px].
    width_px : int
        Image width [px].

    Returns
    -------
    int
        ``num_disparities``, a multiple of 16.

    Examples
    --------
    >>> search_range_for(focal_px=600.0, baseline_m=0.1, min_depth_m=0.3, width_px=640)
    208
    """
    if not (math.isfinite(min_depth_m) and min_depth_m > 0):
        raise InputError(f"min_depth_m must be a positive number [m], got {min_depth_m}")
    d_near = focal_px * baseline_m / min_depth_m - doffs_px
    num = _ceil16(max(d_near - min_disparity + 2.0, 16.0))
    return min(num, _max_num_disparities(width_px, min_disparity))


def depth_limits(
    *,
    focal_px: float,
    baseline_m: float,
    doffs_px: float = 0.0,
    min_disparity: int,
    num_disparities: int,
) -> tuple[float, float]:
    """Nearest and farthest depth a search range measures [m].

    A best match at either end of ``[min, min + num)`` is no measurement, so the
    measurable disparities are ``min + 1 ... min + num - 2`` [px] and the depths
    ``f B / (d + d_offs)``; the far limit is ``inf`` when ``min + 1 + d_offs <= 0``.

    Examples
    --------
    >>> near, far = depth_limits(focal_px=600.0, baseline_m=0.1, min_disparity=0,
    ...                          num_disparities=64)
    >>> round(near, 4), round(far, 1)
    (0.9677, 60.0)
    """
    fb = focal_px * baseline_m
    d_near = min_disparity + num_disparities - 2 + doffs_px
    d_far = min_disparity + 1 + doffs_px
    near = fb / d_near if d_near > 0 else math.inf
    far = fb / d_far if d_far > 0 else math.inf
    return near, far


def _coarse_range(left: Image, right: Image, *, min_disparity: int, num_full: int) -> int:
    """Disparities to search at full resolution, from a search of the whole range at half.

    The pair is halved (``cv2.pyrDown``) and searched over ``num_full / 2``; the
    largest disparity found there (99.5th percentile of the measured ones, doubled,
    plus 8 px) sets the full-resolution range, at least 64 px, at most ``num_full``.
    A coarse search saturated at its near end asks for the whole range.
    """
    cols = left.shape[1] // 2
    num_c = _ceil16(num_full / 2.0)
    lo_c = min_disparity // 2
    if left.shape[0] < 32 or num_c >= cols:
        return num_full
    small = compute_disparity(
        cv2.pyrDown(left),
        cv2.pyrDown(right),
        min_disparity=lo_c,
        num_disparities=num_c,
        fill_holes=False,
    )
    if small.saturated_share > SATURATED_SHARE:
        return num_full
    found = small.disparity[small.measured]
    if found.size == 0:
        return min(num_full, 64)
    d_max = 2.0 * float(np.percentile(found, 99.5)) + 8.0
    return min(num_full, max(64, _ceil16(d_max - min_disparity + 2.0)))


def process_pair(
    left: ArrayLike,
    right: ArrayLike,
    *,
    calib: StereoCalibration | None = None,
    mode: str = "calibrated",
    focal_px: float | None = None,
    baseline_m: float | None = None,
    doffs_px: float = 0.0,
    min_disparity: int = 0,
    num_disparities: int | None = None,
    min_depth_m: float = 0.3,
    n_sectors: int = 32,
    scan_min_points: int = 20,
    scan_min_share: float = 0.02,
) -> StereoRun:
    """Rectify (or not), match, and turn a pair into depth, a cloud and a range scan.

    The disparity search range: given (``num_disparities``), or found coarse to fine.
    The whole range is searched on the pair halved: with metric geometry, the range
    that reaches ``min_depth_m`` (:func:`search_range_for`), else half the image width.
    The largest disparity found there sets the range at full resolution (at least
    64 px; a narrow range leaves fewer columns at the left edge without a match). A
    search whose near end catches more than :data:`SATURATED_SHARE` of the pixels
    (something is nearer than it measures) is widened, doubling up to the whole range,
    unless the range was given. If it stays saturated, the summary says so
    (``search_saturated``) and gives no nearest obstacle (``nearest_obstacle_m`` None,
    ``obstacle_nearer_than_m`` the near limit): a clipped disparity is not a distance.

    Parameters
    ----------
    left, right : ndarray of uint8
        The pair as captured.
    calib : StereoCalibration, optional
        Required in ``"calibrated"`` mode; in ``"rectified"`` mode it supplies the
        rectified geometry (the pair was rectified with it).
    mode : {"calibrated", "uncalibrated", "rectified"}
        How to rectify: with ``calib``, from matched interest points, or not at all.
    focal_px, baseline_m, doffs_px : float, optional
        Geometry of an already rectified pair (``"rectified"`` mode without ``calib``),
        for depth; the principal point is taken at the image centre.
    min_disparity : int
        Start of the disparity search range [px] (ignored when uncalibrated).
    num_disparities : int or None
        Disparities searched [px] (a multiple of 16); None: found as above (ignored
        when uncalibrated: found from the matches).
    min_depth_m : float
        Nearest depth the found range must measure [m].
    n_sectors : int
        Sectors of the range scan.
    scan_min_points, scan_min_share : int, float
        A sector of the range scan reports its ``scan_min_points``-th nearest point or,
        if more, the nearest ``scan_min_share`` of its points' farthest, so a few stray
        matches make no phantom obstacle (:func:`range_scan`).

    Returns
    -------
    StereoRun
        ``summary`` holds ``measured_pct``, ``saturated_pct``, ``textureless_pct``,
        ``search_saturated``, and with metric geometry ``depth_near_limit_m`` and
        ``depth_far_limit_m`` (the measurable depth range), ``depth_median_m`` and
        ``nearest_obstacle_m`` (both None when saturated).

    Raises
    ------
    InputError
        On a bad pair, a calibration for another image size, a missing calibration, or
        a failed uncalibrated rectification.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import process_pair
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> run = process_pair(left, np.roll(left, -8, axis=1), mode="rectified", focal_px=600.0,
    ...                    baseline_m=0.1, num_disparities=32)
    >>> round(run.summary["depth_median_m"], 3)  # f B / d = 600 * 0.1 / 8
    7.5
    """
    lft, rgt = check_pair(left, right)
    h, w = lft.shape[:2]
    if scan_min_points < 1:
        raise InputError(f"scan_min_points must be >= 1, got {scan_min_points}")
    summary: dict[str, Any] = {"mode": mode, "width_px": w, "height_px": h}
    geometry: tuple[float, float, float, float, float] | None = None  # f, B, cx, cy, doffs
    rect: Rectification | None = None
    if mode == "calibrated":
        if calib is None:
            raise InputError("calibrated mode needs a calibration (--calib FILE)")
        _check_calib_size(calib, (w, h))
        rect = rectify_calibrated(calib)
        rl, rr = rectify_pair(lft, rgt, rect)
        geometry = (rect.focal_px, rect.baseline_m, rect.cx_px, rect.cy_px, rect.doffs_px)
    elif mode == "uncalibrated":
        rect = rectify_uncalibrated(lft, rgt)
        rl, rr = rectify_pair(lft, rgt, rect)
        summary["inlier_matches"] = rect.inlier_count
    elif mode == "rectified":
        rl, rr = lft, rgt
        if calib is not None:
            _check_calib_size(calib, (w, h))
            cal_rect = rectify_calibrated(calib)
            geometry = (
                cal_rect.focal_px,
                cal_rect.baseline_m,
                cal_rect.cx_px,
                cal_rect.cy_px,
                cal_rect.doffs_px,
            )
        elif focal_px is not None and baseline_m is not None:
            geometry = (focal_px, baseline_m, (w - 1) / 2.0, (h - 1) / 2.0, doffs_px)
    else:
        raise InputError(f"mode must be calibrated, uncalibrated or rectified, got {mode!r}")
    widen = False
    top = _max_num_disparities(w, min_disparity)
    if mode == "uncalibrated":
        assert rect is not None
        lo, num = rect.min_disparity, rect.num_disparities
    else:
        lo = min_disparity
        if num_disparities is not None:
            num = num_disparities
        else:
            if geometry is not None:
                top = search_range_for(
                    focal_px=geometry[0],
                    baseline_m=geometry[1],
                    doffs_px=geometry[4],
                    min_depth_m=min_depth_m,
                    min_disparity=lo,
                    width_px=w,
                )
            num = _coarse_range(rl, rr, min_disparity=lo, num_full=top)
            widen = True
    result = compute_disparity(rl, rr, min_disparity=lo, num_disparities=num)
    while widen and result.saturated_share > SATURATED_SHARE and num < top:
        num = min(2 * num, top)
        result = compute_disparity(rl, rr, min_disparity=lo, num_disparities=num)
    if rect is not None:  # no value where the rectified left image has no source
        mx, my = rect.map_left[..., 0], rect.map_left[..., 1]
        outside = ~((mx >= 0) & (mx <= w - 1) & (my >= 0) & (my <= h - 1))
        if outside.any():
            disparity = result.disparity.copy()
            disparity[outside] = np.nan
            result = replace(
                result,
                disparity=disparity,
                measured=result.measured & ~outside,
                confidence=np.where(outside, np.float32(0.0), result.confidence),
                saturated=None if result.saturated is None else result.saturated & ~outside,
            )
    d = result.disparity
    finite = d[np.isfinite(d)]
    saturated = result.saturated_share > SATURATED_SHARE
    textureless = 0.0 if result.textureless is None else float(result.textureless.mean())
    summary.update(
        {
            "min_disparity_px": lo,
            "num_disparities": num,
            "measured_pct": 100.0 * float(result.measured.mean()),
            "saturated_pct": 100.0 * result.saturated_share,
            "textureless_pct": 100.0 * textureless,
            "search_saturated": saturated,
            "with_value_pct": 100.0 * finite.size / d.size,
            "disparity_median_px": float(np.median(finite)) if finite.size else math.nan,
            "disparity_p05_px": float(np.percentile(finite, 5)) if finite.size else math.nan,
            "disparity_p95_px": float(np.percentile(finite, 95)) if finite.size else math.nan,
            "mean_confidence": float(result.confidence.mean()),
        }
    )
    if saturated:  # the summary carries the flag; the CLI says it in its own words
        log.info(
            "%.1f %% of the pixels matched at the end of the disparity search range "
            "(%d px): something is nearer than it measures",
            100.0 * result.saturated_share,
            lo + num - 1,
        )
    depth = None
    points = np.zeros((0, 3))
    colors = np.zeros((0, 3), np.uint8)
    scan = None
    if geometry is not None:
        f, b, cx, cy, doffs = geometry
        near, far = depth_limits(
            focal_px=f, baseline_m=b, doffs_px=doffs, min_disparity=lo, num_disparities=num
        )
        depth = depth_from_disparity(d, focal_px=f, baseline_m=b, doffs_px=doffs)
        points, colors = point_cloud(
            d,
            focal_px=f,
            baseline_m=b,
            cx_px=cx,
            cy_px=cy,
            doffs_px=doffs,
            mask=result.measured,
            colors=rl,
        )
        fov = 2.0 * math.atan(w / (2.0 * f))
        scan = range_scan(
            points,
            n_sectors=n_sectors,
            fov_rad=fov,
            min_points=scan_min_points,
            min_share=scan_min_share,
        )
        zf = depth[np.isfinite(depth) & result.measured]
        nearest = float(np.min(scan.range_m))
        summary.update(
            {
                "focal_px": f,
                "baseline_m": b,
                "doffs_px": doffs,
                "min_depth_m": min_depth_m if num_disparities is None else None,
                "depth_near_limit_m": near,
                "depth_far_limit_m": far,
                "depth_median_m": None
                if saturated
                else (float(np.median(zf)) if zf.size else math.nan),
                "nearest_obstacle_m": None if saturated else nearest,
                "obstacle_nearer_than_m": near if saturated else None,
                "points": len(points),
                "fov_rad": fov,
            }
        )
    return StereoRun(rl, rr, result, depth, points, colors, scan, summary)


def _check_calib_size(calib: StereoCalibration, size: tuple[int, int]) -> None:
    if calib.image_size != size:
        raise InputError(
            f"the calibration is for {calib.image_size[0]} x {calib.image_size[1]} px images, "
            f"these are {size[0]} x {size[1]} px"
        )
