"""Rectification of a pair: calibrated (Bouguet) and uncalibrated (Hartley)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import Float32Array, FloatArray
from firefleet.errors import InputError
from firefleet.perception.stereo._calibration import StereoCalibration
from firefleet.perception.stereo._disparity import _check_num_disparities
from firefleet.perception.stereo._images import (
    Image,
    _grey,
    check_pair,
)

log = logging.getLogger("firefleet.perception.stereo")


@dataclass(frozen=True, eq=False)
class Rectification:
    """How to rectify a pair, and the geometry of the rectified pair.

    Attributes
    ----------
    image_size : tuple of int
        ``(width, height)`` of the input and of the rectified images [px].
    map_left, map_right : ndarray of float32, shape (H, W, 2)
        For each rectified pixel, the ``(x, y)`` position to sample in the input image.
    h_left, h_right : ndarray, shape (3, 3) or None
        The projective rectifying transforms (input pixels to rectified pixels) of the
        uncalibrated method; None after calibrated rectification (which also removes
        lens distortion, so it is not a homography).
    focal_px, baseline_m, cx_px, cy_px, doffs_px : float
        Rectified geometry: focal length [px], baseline [m], left principal point [px],
        ``cx_right - cx_left`` [px]. NaN when uncalibrated (no metric depth).
    min_disparity, num_disparities : int
        A disparity search range for :func:`compute_disparity` covering the scene
        (from the matched points when uncalibrated); ``num_disparities`` is a multiple
        of 16.
    inlier_count : int
        Interest-point matches consistent with the epipolar geometry (uncalibrated; 0
        when calibrated).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import StereoCalibration, rectify_calibrated
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> rect = rectify_calibrated(calib)
    >>> rect.image_size, rect.map_left.shape, round(rect.baseline_m, 6)
    ((160, 120), (120, 160, 2), 0.1)
    """

    image_size: tuple[int, int]
    map_left: Float32Array
    map_right: Float32Array
    h_left: FloatArray | None = None
    h_right: FloatArray | None = None
    focal_px: float = math.nan
    baseline_m: float = math.nan
    cx_px: float = math.nan
    cy_px: float = math.nan
    doffs_px: float = 0.0
    min_disparity: int = 0
    num_disparities: int = 64
    inlier_count: int = 0

    @property
    def calibrated(self) -> bool:
        """True when the rectified geometry is metric (depth can be computed)."""
        return math.isfinite(self.focal_px) and math.isfinite(self.baseline_m)


def rectify_calibrated(
    calib: StereoCalibration, *, alpha: float = 0.0, num_disparities: int = 64
) -> Rectification:
    """Rectifying maps from a calibration (Bouguet's method, ``cv2.stereoRectify``).

    Parameters
    ----------
    calib : StereoCalibration
    alpha : float
        0 keeps only valid pixels in the rectified images, 1 keeps every input pixel.
    num_disparities : int
        Disparity search range recorded in the result (multiple of 16).

    Returns
    -------
    Rectification
        With ``doffs_px = 0`` (principal points aligned, ``CALIB_ZERO_DISPARITY``).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import StereoCalibration, rectify_calibrated
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> rect = rectify_calibrated(calib)  # an ideal rig: rectification changes nothing
    >>> round(rect.focal_px, 6), round(rect.baseline_m, 6), rect.doffs_px
    (100.0, 0.1, 0.0)
    """
    if not 0.0 <= alpha <= 1.0:
        raise InputError(f"alpha must be in [0, 1], got {alpha}")
    _check_num_disparities(num_disparities, calib.image_size[0])
    size = calib.image_size
    R1, R2, P1, P2, _, _, _ = cv2.stereoRectify(
        calib.k_left,
        calib.dist_left,
        calib.k_right,
        calib.dist_right,
        size,
        calib.rotation,
        calib.translation_m,
        flags=cv2.CALIB_ZERO_DISPARITY,
        alpha=alpha,
    )
    maps = []
    for k, d, r, p in (
        (calib.k_left, calib.dist_left, R1, P1),
        (calib.k_right, calib.dist_right, R2, P2),
    ):
        mx, my = cv2.initUndistortRectifyMap(k, d, r, p, size, cv2.CV_32FC1)
        maps.append(np.dstack([mx, my]).astype(np.float32))
    return Rectification(
        image_size=size,
        map_left=maps[0],
        map_right=maps[1],
        focal_px=float(P1[0, 0]),
        baseline_m=float(abs(P2[0, 3] / P2[0, 0])),
        cx_px=float(P1[0, 2]),
        cy_px=float(P1[1, 2]),
        doffs_px=float(P2[0, 2] - P1[0, 2]),
        min_disparity=0,
        num_disparities=num_disparities,
    )


def match_features(
    left: ArrayLike,
    right: ArrayLike,
    *,
    detector: str = "sift",
    ratio: float = 0.75,
    max_features: int = 4000,
) -> tuple[Float32Array, Float32Array]:
    """Interest points matched between two images (section 2.7.2.5).

    Parameters
    ----------
    left, right : ndarray of uint8
        Images of the same size.
    detector : {"sift", "orb", "akaze"}
        Detector and descriptor. SIFT (patent expired 2020) replaces the
        deliverable's SURF, which is absent from OpenCV's wheels.
    ratio : float
        Lowe's ratio test: keep a match only if its descriptor distance is below
        ``ratio`` times that of the second-best candidate.
    max_features : int
        Most interest points kept per image (SIFT, ORB).

    Returns
    -------
    pts_left, pts_right : ndarray of float32, shape (M, 2)
        Matched positions [px]; mutual best matches only.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import match_features
    >>> left = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> pts_left, pts_right = match_features(left, np.roll(left, -8, axis=1))
    >>> pts_left.shape[1], float(np.median(pts_left[:, 0] - pts_right[:, 0]))
    (2, 8.0)
    """
    lft, rgt = check_pair(left, right)
    if not 0.0 < ratio < 1.0:
        raise InputError(f"ratio must be in (0, 1), got {ratio}")
    if detector == "sift":
        det: Any = cv2.SIFT.create(nfeatures=max_features)
        norm = cv2.NORM_L2
    elif detector == "orb":
        det = cv2.ORB.create(nfeatures=max_features)
        norm = cv2.NORM_HAMMING
    elif detector == "akaze":
        det = cv2.AKAZE.create()
        norm = cv2.NORM_HAMMING
    else:
        raise InputError(f"detector must be 'sift', 'orb' or 'akaze', got {detector!r}")
    kp_l, des_l = det.detectAndCompute(_grey(lft), None)
    kp_r, des_r = det.detectAndCompute(_grey(rgt), None)
    empty = np.zeros((0, 2), np.float32)
    if des_l is None or des_r is None or len(kp_l) < 2 or len(kp_r) < 2:
        return empty, empty
    matcher = cv2.BFMatcher(norm)
    fwd = matcher.knnMatch(des_l, des_r, k=2)
    back = {m[0].queryIdx: m[0].trainIdx for m in matcher.knnMatch(des_r, des_l, k=1) if m}
    good = [
        m[0]
        for m in fwd
        if len(m) == 2
        and m[0].distance < ratio * m[1].distance
        and back.get(m[0].trainIdx) == m[0].queryIdx
    ]
    if not good:
        return empty, empty
    pts_l = np.array([kp_l[m.queryIdx].pt for m in good], np.float32)
    pts_r = np.array([kp_r[m.trainIdx].pt for m in good], np.float32)
    return pts_l, pts_r


def _apply_h(h: FloatArray, pts: ArrayLike) -> FloatArray:
    p = np.asarray(pts, dtype=np.float64)
    q = p @ h[:, :2].T + h[:, 2]
    return q[:, :2] / q[:, 2:3]


def _maps_from_h(h: FloatArray, size: tuple[int, int]) -> Float32Array:
    w, hgt = size
    xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(hgt, dtype=np.float64))
    src = _apply_h(
        np.asarray(np.linalg.inv(h), dtype=np.float64), np.column_stack([xs.ravel(), ys.ravel()])
    )
    return src.reshape(hgt, w, 2).astype(np.float32)


def rectify_uncalibrated(
    left: ArrayLike,
    right: ArrayLike,
    *,
    detector: str = "sift",
    ratio: float = 0.75,
    ransac_threshold_px: float = 1.0,
    min_inliers: int = 16,
) -> Rectification:
    """Rectify a pair without calibration, as the deliverable did (section 2.7.2.6).

    Interest points are matched (:func:`match_features`), the fundamental matrix is
    estimated with RANSAC, and projective transforms ``H1``, ``H2`` that send the
    epipoles to infinity along the rows are found (Hartley [2]_,
    ``cv2.stereoRectifyUncalibrated``). Corrections follow, each keeping rows aligned:
    a transform that mirrors an image is composed with a mirror (Hartley's transforms
    are defined up to one); both are composed with a common affinity that maps rows to
    rows, fitted so that the left image's corners stay where they were (no image is
    sent off-frame); and the right image is shifted along the rows so that the
    matched points' disparities start a margin above zero (Hartley's matching
    transform centres them on zero).

    Returns
    -------
    Rectification
        Maps, ``h_left``/``h_right``, a disparity range covering the inliers (with a
        margin), and NaN metric geometry.

    Raises
    ------
    InputError
        If too few consistent matches are found (untextured images, different scenes).

    Examples
    --------
    >>> import numpy as np
    >>> import cv2
    >>> from firefleet.perception.stereo import rectify_uncalibrated
    >>> noise = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> left = cv2.GaussianBlur(noise, (3, 3), 0)
    >>> rect = rectify_uncalibrated(left, np.roll(left, -8, axis=1))
    >>> rect.h_left.shape, rect.inlier_count >= 16, bool(np.isnan(rect.baseline_m))
    ((3, 3), True, True)
    """
    lft, rgt = check_pair(left, right)
    if ransac_threshold_px <= 0:
        raise InputError(f"ransac_threshold_px must be > 0, got {ransac_threshold_px}")
    hgt, w = lft.shape[:2]
    pts_l, pts_r = match_features(lft, rgt, detector=detector, ratio=ratio)
    if len(pts_l) < max(min_inliers, 8):
        raise InputError(
            f"uncalibrated rectification: only {len(pts_l)} interest-point matches "
            f"(need >= {max(min_inliers, 8)}); are the images of the same scene and textured?"
        )
    try:
        F, mask = cv2.findFundamentalMat(
            pts_l, pts_r, cv2.FM_RANSAC, ransac_threshold_px, 0.999, 5000
        )
    except cv2.error:  # OpenCV asserts on degenerate point sets (all on one line, ...)
        F, mask = None, None
    if F is None or mask is None or F.shape != (3, 3):
        raise InputError("uncalibrated rectification: no fundamental matrix fits the matches")
    inl = mask.ravel().astype(bool)
    if inl.sum() < min_inliers:
        raise InputError(
            f"uncalibrated rectification: only {int(inl.sum())} matches agree with one "
            f"epipolar geometry (need >= {min_inliers})"
        )
    pl, pr = pts_l[inl], pts_r[inl]
    try:
        ok, h1_raw, h2_raw = cv2.stereoRectifyUncalibrated(pl, pr, F, (w, hgt))
    except cv2.error:  # an assertion inside OpenCV on degenerate input: no rectification
        ok = False
    if not ok:
        raise InputError("uncalibrated rectification failed (degenerate geometry)")
    H1: FloatArray = np.asarray(h1_raw, dtype=np.float64)
    H2: FloatArray = np.asarray(h2_raw, dtype=np.float64)
    # Hartley's transforms are defined up to a mirror of each image along the rows and
    # a common mirror across them: undo any, so neither image is shown mirrored.
    centre = np.array([[(w - 1) / 2.0, (hgt - 1) / 2.0]])
    step = centre + np.array([[1.0, 0.0], [0.0, 1.0]])
    flip_x = np.diag([-1.0, 1.0, 1.0])
    if (_apply_h(H1, step[:1]) - _apply_h(H1, centre))[0, 0] < 0:
        H1 = flip_x @ H1
    if (_apply_h(H2, step[:1]) - _apply_h(H2, centre))[0, 0] < 0:
        H2 = flip_x @ H2
    if (_apply_h(H1, step[1:]) - _apply_h(H1, centre))[0, 1] < 0:
        H1, H2 = np.diag([1.0, -1.0, 1.0]) @ H1, np.diag([1.0, -1.0, 1.0]) @ H2
    # Keep the rectified left image in frame: an affine map of the rectified plane that
    # is the same for both images and keeps rows rows (x' = a x + b y + c, y' = e y + f)
    # fitted so that the left image's corners land near their original positions.
    corners = np.array([[0, 0], [w - 1, 0], [w - 1, hgt - 1], [0, hgt - 1]], np.float64)
    rc = _apply_h(H1, corners)
    ax, *_ = np.linalg.lstsq(np.column_stack([rc, np.ones(4)]), corners[:, 0], rcond=None)
    ay, *_ = np.linalg.lstsq(np.column_stack([rc[:, 1], np.ones(4)]), corners[:, 1], rcond=None)
    A = np.array([[ax[0], ax[1], ax[2]], [0.0, ay[0], ay[1]], [0.0, 0.0, 1.0]])
    H1, H2 = A @ H1, A @ H2
    disp = _apply_h(H1, pl)[:, 0] - _apply_h(H2, pr)[:, 0]
    # Hartley's matching transform centres the disparities on zero; the shift below
    # moves them into SGBM's non-negative range (relative depth order is kept).
    lo, hi = np.percentile(disp, [1.0, 99.0])
    span = hi - lo
    margin = max(8.0, 0.25 * span)
    shift = math.floor(lo - margin)  # shift the right image so disparities start >= 0
    H2 = np.array([[1.0, 0.0, float(shift)], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) @ H2
    num = int(16 * math.ceil((span + 2 * margin) / 16.0))
    num = min(num, 16 * max(1, (w // 2) // 16))
    log.info("uncalibrated rectification: %d inliers of %d matches", int(inl.sum()), len(pts_l))
    return Rectification(
        image_size=(w, hgt),
        map_left=_maps_from_h(H1, (w, hgt)),
        map_right=_maps_from_h(H2, (w, hgt)),
        h_left=H1,
        h_right=H2,
        min_disparity=0,
        num_disparities=num,
        inlier_count=int(inl.sum()),
    )


def rectify_pair(left: ArrayLike, right: ArrayLike, rect: Rectification) -> tuple[Image, Image]:
    """Apply a :class:`Rectification` to a pair (bilinear resampling, black outside).

    Raises
    ------
    InputError
        If the images are not the size the rectification was made for (a calibration
        file that does not match the images).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import StereoCalibration, rectify_calibrated, rectify_pair
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> image = (np.random.default_rng(0).random((120, 160)) * 255).astype(np.uint8)
    >>> rect_left, rect_right = rectify_pair(image, image, rectify_calibrated(calib))
    >>> inner = (slice(10, -10), slice(10, -10))  # away from the border
    >>> rect_left.shape, int(np.abs(rect_left[inner].astype(int) - image[inner]).max())
    ((120, 160), 0)
    """
    lft, rgt = check_pair(left, right)
    size = (lft.shape[1], lft.shape[0])
    if size != rect.image_size:
        raise InputError(
            f"images are {size[0]} x {size[1]} px but the calibration is for "
            f"{rect.image_size[0]} x {rect.image_size[1]} px"
        )
    out = []
    for img, m in ((lft, rect.map_left), (rgt, rect.map_right)):
        out.append(
            np.asarray(
                cv2.remap(
                    img, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT
                ),
                dtype=np.uint8,
            )
        )
    return out[0], out[1]
