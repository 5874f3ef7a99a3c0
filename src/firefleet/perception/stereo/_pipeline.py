"""The whole pair: rectify, match, depth, cloud and range scan, and a summary."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from firefleet.errors import InputError
from firefleet.perception.stereo._calibration import StereoCalibration
from firefleet.perception.stereo._disparity import DisparityResult, compute_disparity
from firefleet.perception.stereo._geometry import (
    RangeScan,
    depth_from_disparity,
    point_cloud,
    range_scan,
)
from firefleet.perception.stereo._images import Float32Array, FloatArray, Image, check_pair
from firefleet.perception.stereo._rectify import (
    rectify_calibrated,
    rectify_pair,
    rectify_uncalibrated,
)


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
    """

    rect_left: Image
    rect_right: Image
    result: DisparityResult
    depth_m: Float32Array | None
    points: FloatArray
    colors: Image
    scan: RangeScan | None
    summary: dict[str, Any]


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
    num_disparities: int = 64,
    n_sectors: int = 32,
) -> StereoRun:
    """Rectify (or not), match, and turn a pair into depth, a cloud and a range scan.

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
    min_disparity, num_disparities : int
        Disparity search range [px] (ignored when uncalibrated: found from the matches).
    n_sectors : int
        Sectors of the range scan.

    Raises
    ------
    InputError
        On a bad pair, a calibration for another image size, a missing calibration, or
        a failed uncalibrated rectification.
    """
    lft, rgt = check_pair(left, right)
    h, w = lft.shape[:2]
    summary: dict[str, Any] = {"mode": mode, "width_px": w, "height_px": h}
    geometry: tuple[float, float, float, float, float] | None = None  # f, B, cx, cy, doffs
    if mode == "calibrated":
        if calib is None:
            raise InputError("calibrated mode needs a calibration (--calib FILE)")
        _check_calib_size(calib, (w, h))
        rect = rectify_calibrated(calib, num_disparities=num_disparities)
        rl, rr = rectify_pair(lft, rgt, rect)
        geometry = (rect.focal_px, rect.baseline_m, rect.cx_px, rect.cy_px, rect.doffs_px)
        lo, num = min_disparity, num_disparities
    elif mode == "uncalibrated":
        rect = rectify_uncalibrated(lft, rgt)
        rl, rr = rectify_pair(lft, rgt, rect)
        lo, num = rect.min_disparity, rect.num_disparities
        summary["inlier_matches"] = rect.inlier_count
    elif mode == "rectified":
        rl, rr = lft, rgt
        lo, num = min_disparity, num_disparities
        if calib is not None:
            _check_calib_size(calib, (w, h))
            rect = rectify_calibrated(calib, num_disparities=num_disparities)
            geometry = (rect.focal_px, rect.baseline_m, rect.cx_px, rect.cy_px, rect.doffs_px)
        elif focal_px is not None and baseline_m is not None:
            geometry = (focal_px, baseline_m, (w - 1) / 2.0, (h - 1) / 2.0, doffs_px)
    else:
        raise InputError(f"mode must be calibrated, uncalibrated or rectified, got {mode!r}")
    result = compute_disparity(rl, rr, min_disparity=lo, num_disparities=num)
    if mode != "rectified":  # no value where the rectified left image has no source
        mx, my = rect.map_left[..., 0], rect.map_left[..., 1]
        outside = ~((mx >= 0) & (mx <= w - 1) & (my >= 0) & (my <= h - 1))
        if outside.any():
            disparity = result.disparity.copy()
            disparity[outside] = np.nan
            measured = result.measured & ~outside
            confidence = np.where(outside, np.float32(0.0), result.confidence)
            result = DisparityResult(disparity, measured, confidence)
    d = result.disparity
    finite = d[np.isfinite(d)]
    summary.update(
        {
            "min_disparity_px": lo,
            "num_disparities": num,
            "measured_pct": 100.0 * float(result.measured.mean()),
            "with_value_pct": 100.0 * finite.size / d.size,
            "disparity_median_px": float(np.median(finite)) if finite.size else math.nan,
            "disparity_p05_px": float(np.percentile(finite, 5)) if finite.size else math.nan,
            "disparity_p95_px": float(np.percentile(finite, 95)) if finite.size else math.nan,
            "mean_confidence": float(result.confidence.mean()),
        }
    )
    depth = None
    points = np.zeros((0, 3))
    colors = np.zeros((0, 3), np.uint8)
    scan = None
    if geometry is not None:
        f, b, cx, cy, doffs = geometry
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
        scan = range_scan(points, n_sectors=n_sectors, fov_rad=fov)
        zf = depth[np.isfinite(depth) & result.measured]
        summary.update(
            {
                "focal_px": f,
                "baseline_m": b,
                "doffs_px": doffs,
                "depth_median_m": float(np.median(zf)) if zf.size else math.nan,
                "nearest_obstacle_m": float(np.min(scan.range_m)),
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
