"""Stereo vision: calibration, rectification, disparity, depth, point clouds, range scans.

The deliverable's pipeline (section 2.7.2): two webcams give an image pair, interest
points are collected in both images and matched, the pair is rectified so that
corresponding points lie on the same row, then depth is recovered for collision
avoidance and SLAM in reduced visibility. The deliverable used MATLAB and SURF; this
module uses OpenCV (SIFT, RANSAC, semi-global matching) and goes on to depth, a 3-D
point cloud and a virtual range scan.

Conventions
-----------
* Images are ``(H, W)`` grey or ``(H, W, 3)`` colour ``uint8`` arrays; colour is in
  OpenCV's BGR order (what ``cv2.imread`` returns). Sizes are ``(width, height)`` in
  pixels, as OpenCV has them.
* Disparity ``d`` is in pixels of the rectified left image: the left pixel ``(x, y)``
  corresponds to the right pixel ``(x - d, y)``. Float32, NaN where there is no value.
* Depth ``Z = f B / (d + d_offs)`` in metres (``f`` focal length [px], ``B`` baseline
  [m], ``d_offs`` the principal points' column difference ``cx_right - cx_left``
  [px], zero after calibrated rectification). Camera frame of the rectified left
  camera: X right, Y down, Z forward [m] (OpenCV's).
* Bearings of the range scan are measured from the optical axis, positive to the
  left (counter-clockwise seen from above, like the robots' heading).

References
----------
.. [1] H. Hirschmueller, "Stereo processing by semiglobal matching and mutual
   information", IEEE TPAMI 30(2), 2008 (SGBM, left-right check, sub-pixel).
.. [2] R. Hartley, "Theory and practice of projective rectification", IJCV 35(2),
   1999 (uncalibrated rectification, ``cv2.stereoRectifyUncalibrated``).
.. [3] Z. Zhang, "A flexible new technique for camera calibration", IEEE TPAMI
   22(11), 2000 (chessboard calibration, ``cv2.calibrateCamera``).
.. [4] D. Scharstein et al., "High-resolution stereo datasets with subpixel-accurate
   ground truth", GCPR 2014 (Middlebury 2014, the bad-2.0 measure).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError, as_float_array
from firefleet.outputs import write_text_atomic

__all__ = [
    "CALIBRATION_FORMAT",
    "DisparityResult",
    "RangeScan",
    "Rectification",
    "StereoCalibration",
    "StereoRun",
    "calibrate_stereo",
    "check_pair",
    "compute_disparity",
    "depth_from_disparity",
    "find_chessboard",
    "load_calibration",
    "match_features",
    "ply_bytes",
    "point_cloud",
    "process_pair",
    "range_scan",
    "read_image",
    "rectify_calibrated",
    "rectify_pair",
    "rectify_uncalibrated",
    "save_calibration",
    "sgbm_disparity",
    "write_run",
]

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
Float32Array = NDArray[np.float32]
Image = NDArray[np.uint8]

CALIBRATION_FORMAT = "firefleet-stereo-calibration/1"
"""Value of the ``format`` key that every calibration file starts with."""


# ----------------------------------------------------------------------- images


def read_image(path: str | Path) -> Image:
    """Read an image file as ``uint8`` BGR (or grey), raising :class:`InputError`.

    Raises
    ------
    InputError
        If the file is missing, empty or not an image OpenCV can decode.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such image file")
    data = np.fromfile(p, dtype=np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if image is None:
        raise InputError(f"{p}: not a readable image (empty or corrupt)")
    if image.dtype != np.uint8:
        raise InputError(f"{p}: expected an 8-bit image, got {image.dtype}")
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.asarray(image, dtype=np.uint8)


def _check_image(image: ArrayLike, name: str) -> Image:
    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        raise InputError(f"{name} must be a uint8 image, got dtype {arr.dtype}")
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[2] == 3)):
        raise InputError(f"{name} must have shape (H, W) or (H, W, 3), got {arr.shape}")
    if min(arr.shape[:2]) < 8:
        raise InputError(f"{name} is too small: {arr.shape[1]} x {arr.shape[0]} px")
    return np.ascontiguousarray(arr)


def check_pair(left: ArrayLike, right: ArrayLike) -> tuple[Image, Image]:
    """Check a stereo pair: two ``uint8`` images of the same size and channel count.

    Returns
    -------
    left, right : ndarray of uint8
        Contiguous ``(H, W)`` or ``(H, W, 3)`` arrays.

    Raises
    ------
    InputError
        If an image is not ``uint8`` grey or 3-channel, or the two differ in shape.
    """
    lft, rgt = _check_image(left, "left image"), _check_image(right, "right image")
    if lft.shape != rgt.shape:
        raise InputError(
            f"left and right images differ in size: {lft.shape[1]} x {lft.shape[0]} "
            f"vs {rgt.shape[1]} x {rgt.shape[0]} px"
            + (" (their channel counts differ)" if lft.shape[:2] == rgt.shape[:2] else "")
        )
    return lft, rgt


def _grey(image: Image) -> Image:
    return image if image.ndim == 2 else np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))


# ------------------------------------------------------------------ calibration


@dataclass(frozen=True, eq=False)
class StereoCalibration:
    """Intrinsics, distortion and extrinsics of a stereo camera pair.

    Attributes
    ----------
    image_size : tuple of int
        ``(width, height)`` of the images the calibration belongs to [px].
    k_left, k_right : ndarray, shape (3, 3)
        Camera matrices ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`` [px].
    dist_left, dist_right : ndarray, shape (5,)
        Distortion coefficients ``(k1, k2, p1, p2, k3)`` of OpenCV's model (Brown-Conrady).
    rotation : ndarray, shape (3, 3)
        Rotation from the left camera's frame to the right camera's.
    translation_m : ndarray, shape (3,)
        Translation of the same transform [m]: ``X_right = R X_left + t``; for a
        side-by-side rig ``t`` is about ``(-B, 0, 0)``.
    rms_px : float
        RMS reprojection error of the stereo calibration [px] (NaN if unknown).
    """

    image_size: tuple[int, int]
    k_left: FloatArray
    dist_left: FloatArray
    k_right: FloatArray
    dist_right: FloatArray
    rotation: FloatArray
    translation_m: FloatArray
    rms_px: float = math.nan

    def __post_init__(self) -> None:
        w, h = self.image_size
        if not (int(w) == w and int(h) == h and w > 0 and h > 0):
            raise InputError(f"calibration.image_size must be two positive integers, got {w, h}")
        for name, shape in (
            ("k_left", (3, 3)),
            ("k_right", (3, 3)),
            ("dist_left", (5,)),
            ("dist_right", (5,)),
            ("rotation", (3, 3)),
            ("translation_m", (3,)),
        ):
            arr = as_float_array(getattr(self, name), f"calibration.{name}", shape)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        for name in ("k_left", "k_right"):
            k = getattr(self, name)
            if not (k[0, 0] > 0 and k[1, 1] > 0 and k[2, 2] == 1.0):
                raise InputError(f"calibration.{name} must have fx, fy > 0 and K[2, 2] = 1")
        if not np.allclose(self.rotation @ self.rotation.T, np.eye(3), atol=1e-6):
            raise InputError("calibration.rotation must be a rotation matrix (R R^T = I)")
        if not np.linalg.norm(self.translation_m) > 0:
            raise InputError("calibration.translation_m must be non-zero (the baseline)")
        object.__setattr__(self, "image_size", (int(w), int(h)))

    @property
    def focal_px(self) -> float:
        """Mean focal length of the left camera, ``(fx + fy) / 2`` [px]."""
        return float(0.5 * (self.k_left[0, 0] + self.k_left[1, 1]))

    @property
    def baseline_m(self) -> float:
        """Distance between the two optical centres, ``|t|`` [m]."""
        return float(np.linalg.norm(self.translation_m))


def save_calibration(calib: StereoCalibration, path: str | Path) -> None:
    """Write a calibration as YAML (written to a temporary name, then renamed).

    The file (``format: firefleet-stereo-calibration/1``) holds ``image_size``
    ``[width, height]`` [px]; ``left`` and ``right``, each with ``camera_matrix`` (3 rows
    of 3) [px] and ``distortion`` ``[k1, k2, p1, p2, k3]``; ``rotation`` (3 rows of 3)
    and ``translation_m`` ``[tx, ty, tz]`` [m] from the left camera's frame to the
    right's; ``rms_reprojection_px`` (null if unknown).
    """
    doc = {
        "format": CALIBRATION_FORMAT,
        "image_size": list(calib.image_size),
        "left": {
            "camera_matrix": calib.k_left.tolist(),
            "distortion": calib.dist_left.tolist(),
        },
        "right": {
            "camera_matrix": calib.k_right.tolist(),
            "distortion": calib.dist_right.tolist(),
        },
        "rotation": calib.rotation.tolist(),
        "translation_m": calib.translation_m.tolist(),
        "rms_reprojection_px": None if math.isnan(calib.rms_px) else float(calib.rms_px),
    }
    write_text_atomic(path, yaml.safe_dump(doc, sort_keys=False))


def load_calibration(path: str | Path) -> StereoCalibration:
    """Read a calibration written by :func:`save_calibration`.

    Raises
    ------
    InputError
        If the file is missing, not YAML, not of this format, or a field is missing or
        malformed (the message names it).
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such calibration file")
    try:
        doc = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: not a YAML calibration file ({type(exc).__name__})") from None
    if not isinstance(doc, dict) or doc.get("format") != CALIBRATION_FORMAT:
        raise InputError(f"{p}: not a calibration file (expected format: {CALIBRATION_FORMAT})")

    def field(*keys: str) -> Any:
        node: Any = doc
        for key in keys:
            if not isinstance(node, dict) or key not in node:
                raise InputError(f"{p}: missing field {'.'.join(keys)}")
            node = node[key]
        return node

    size = field("image_size")
    if not (isinstance(size, list) and len(size) == 2 and all(isinstance(v, int) for v in size)):
        raise InputError(f"{p}: image_size must be [width, height] in pixels, got {size!r}")
    rms = doc.get("rms_reprojection_px")
    try:
        return StereoCalibration(
            image_size=(size[0], size[1]),
            k_left=np.asarray(field("left", "camera_matrix"), dtype=float),
            dist_left=np.asarray(field("left", "distortion"), dtype=float),
            k_right=np.asarray(field("right", "camera_matrix"), dtype=float),
            dist_right=np.asarray(field("right", "distortion"), dtype=float),
            rotation=np.asarray(field("rotation"), dtype=float),
            translation_m=np.asarray(field("translation_m"), dtype=float),
            rms_px=math.nan if rms is None else float(rms),
        )
    except (TypeError, ValueError) as exc:
        raise InputError(f"{p}: {exc}") from None


def find_chessboard(
    image: ArrayLike, *, pattern_size: tuple[int, int] = (9, 6)
) -> Float32Array | None:
    """Chessboard inner corners to sub-pixel accuracy, or None if the board is not found.

    Parameters
    ----------
    image : ndarray of uint8, shape (H, W) or (H, W, 3)
    pattern_size : tuple of int
        Inner corners per row and per column, ``(columns, rows)``.

    Returns
    -------
    ndarray of float32, shape (columns * rows, 2) or None
        Corner positions [px], row by row (OpenCV's order).
    """
    grey = _grey(_check_image(image, "chessboard image"))
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(grey, pattern_size, flags=flags)
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)
    corners = cv2.cornerSubPix(grey, corners, (5, 5), (-1, -1), criteria)
    return np.asarray(corners.reshape(-1, 2), dtype=np.float32)


def calibrate_stereo(
    left_images: Sequence[ArrayLike],
    right_images: Sequence[ArrayLike],
    *,
    pattern_size: tuple[int, int] = (9, 6),
    square_size_m: float = 0.025,
) -> StereoCalibration:
    """Calibrate a stereo pair from chessboard image pairs (Zhang's method [3]_).

    Each camera is calibrated alone (``cv2.calibrateCamera``: intrinsics and the five
    distortion coefficients), then the pair jointly (``cv2.stereoCalibrate`` with the
    intrinsics as the initial guess), which refines everything and gives the rotation
    and translation between the cameras.

    Parameters
    ----------
    left_images, right_images : sequence of ndarray of uint8
        Pairs taken at the same time, same size; pairs where the board is not found in
        both images are skipped (logged).
    pattern_size : tuple of int
        Inner corners ``(columns, rows)`` of the board.
    square_size_m : float
        Side of one square [m]; it sets the scale of the translation.

    Returns
    -------
    StereoCalibration

    Raises
    ------
    InputError
        If the sequences differ in length, images differ in size, or fewer than three
        pairs show the whole board in both images.
    """
    if len(left_images) != len(right_images):
        raise InputError(
            f"calibration needs pairs: {len(left_images)} left vs {len(right_images)} right images"
        )
    if not (math.isfinite(square_size_m) and square_size_m > 0):
        raise InputError(f"square_size_m must be > 0, got {square_size_m}")
    cols, rows = pattern_size
    board = np.zeros((cols * rows, 3), np.float32)
    board[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_size_m
    obj, pts_l, pts_r = [], [], []
    size: tuple[int, int] | None = None
    for i, (lft_raw, rgt_raw) in enumerate(zip(left_images, right_images, strict=True)):
        lft, rgt = check_pair(lft_raw, rgt_raw)
        this = (lft.shape[1], lft.shape[0])
        if size is not None and this != size:
            raise InputError(f"calibration pair {i} is {this[0]} x {this[1]} px, not {size}")
        size = this
        c_l = find_chessboard(lft, pattern_size=pattern_size)
        c_r = find_chessboard(rgt, pattern_size=pattern_size)
        if c_l is None or c_r is None:
            log.info("calibration pair %d: board not found in both images, skipped", i)
            continue
        obj.append(board)
        pts_l.append(c_l.reshape(-1, 1, 2))
        pts_r.append(c_r.reshape(-1, 1, 2))
    if size is None or len(obj) < 3:
        raise InputError(
            f"calibration needs at least 3 pairs showing the whole {cols} x {rows} board in "
            f"both images, found {len(obj)}"
        )
    k0, d0 = np.eye(3), np.zeros(5)
    _, k_l, d_l, _, _ = cv2.calibrateCamera(obj, pts_l, size, k0.copy(), d0.copy())
    _, k_r, d_r, _, _ = cv2.calibrateCamera(obj, pts_r, size, k0.copy(), d0.copy())
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-9)
    rms, k_l, d_l, k_r, d_r, R, T, _, _ = cv2.stereoCalibrate(
        obj,
        pts_l,
        pts_r,
        k_l,
        d_l,
        k_r,
        d_r,
        size,
        criteria=criteria,
        flags=cv2.CALIB_USE_INTRINSIC_GUESS,
    )
    return StereoCalibration(
        image_size=size,
        k_left=np.asarray(k_l, dtype=np.float64),
        dist_left=np.asarray(d_l, dtype=np.float64).ravel()[:5],
        k_right=np.asarray(k_r, dtype=np.float64),
        dist_right=np.asarray(d_r, dtype=np.float64).ravel()[:5],
        rotation=np.asarray(R, dtype=np.float64),
        translation_m=np.asarray(T, dtype=np.float64).ravel(),
        rms_px=float(rms),
    )


# ---------------------------------------------------------------- rectification


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
    F, mask = cv2.findFundamentalMat(pts_l, pts_r, cv2.FM_RANSAC, ransac_threshold_px, 0.999, 5000)
    if F is None or F.shape != (3, 3):
        raise InputError("uncalibrated rectification: no fundamental matrix fits the matches")
    inl = mask.ravel().astype(bool)
    if inl.sum() < min_inliers:
        raise InputError(
            f"uncalibrated rectification: only {int(inl.sum())} matches agree with one "
            f"epipolar geometry (need >= {min_inliers})"
        )
    pl, pr = pts_l[inl], pts_r[inl]
    ok, h1_raw, h2_raw = cv2.stereoRectifyUncalibrated(pl, pr, F, (w, hgt))
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


# -------------------------------------------------------------------- disparity


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
    """

    disparity: Float32Array
    measured: NDArray[np.bool_]
    confidence: Float32Array


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
) -> DisparityResult:
    """Disparity of a rectified pair: SGBM, then checks, confidence and hole filling.

    1. Semi-global matching [1]_ in OpenCV's parallel three-way mode
       (``MODE_SGBM_3WAY``), colour if given, ``P1 = 8 cn b^2``, ``P2 = 24 cn b^2``,
       sub-pixel by parabola fitting (1/16 px).
    2. Checks: uniqueness (the best cost ``uniqueness_pct`` % below the second best),
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

    Returns
    -------
    DisparityResult
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
    measured = ~np.isnan(disp)
    confidence = _confidence(disp, measured)
    if fill_holes:
        disp = _fill_background(disp)
        if median_px:
            nan = np.isnan(disp)
            med = cv2.medianBlur(np.where(nan, np.float32(0.0), disp), median_px)
            disp = np.where(nan, np.float32(np.nan), med)
    return DisparityResult(
        disparity=np.asarray(disp, dtype=np.float32), measured=measured, confidence=confidence
    )


# ------------------------------------------------------------ depth and clouds


def depth_from_disparity(
    disparity: ArrayLike, *, focal_px: float, baseline_m: float, doffs_px: float = 0.0
) -> Float32Array:
    """Depth ``Z = f B / (d + d_offs)`` [m] from disparity [px].

    Parameters
    ----------
    disparity : array_like, shape (H, W)
        Disparity [px]; NaN where none.
    focal_px : float
        Focal length of the rectified cameras [px].
    baseline_m : float
        Baseline [m].
    doffs_px : float
        ``cx_right - cx_left`` of the rectified cameras [px] (Middlebury's ``doffs``).

    Returns
    -------
    ndarray of float32, shape (H, W)
        Depth [m]; NaN where the disparity is NaN or ``d + d_offs <= 0`` (at infinity).
    """
    d = np.asarray(disparity, dtype=np.float32)
    if d.ndim != 2:
        raise InputError(f"disparity must have shape (H, W), got {d.shape}")
    for name, v in (("focal_px", focal_px), ("baseline_m", baseline_m)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name} must be > 0, got {v}")
    if not math.isfinite(doffs_px):
        raise InputError(f"doffs_px must be finite, got {doffs_px}")
    den = d + np.float32(doffs_px)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.float32(focal_px * baseline_m) / den
    z[~(den > 0)] = np.nan
    return np.asarray(z, dtype=np.float32)


def point_cloud(
    disparity: ArrayLike,
    *,
    focal_px: float,
    baseline_m: float,
    cx_px: float,
    cy_px: float,
    doffs_px: float = 0.0,
    mask: ArrayLike | None = None,
    colors: ArrayLike | None = None,
) -> tuple[FloatArray, Image]:
    """3-D points of the left camera's pixels (section 2.7.2.1: one point per pixel).

    ``X = (x - cx) Z / f``, ``Y = (y - cy) Z / f``, ``Z`` from
    :func:`depth_from_disparity`, in the rectified left camera's frame (X right,
    Y down, Z forward) [m].

    Parameters
    ----------
    disparity : array_like, shape (H, W)
    mask : array_like of bool, shape (H, W), optional
        Pixels to keep (for example ``DisparityResult.measured``); NaN depths are
        always dropped.
    colors : ndarray of uint8, shape (H, W, 3) or (H, W), optional
        BGR (or grey) colours of the left image.

    Returns
    -------
    points : ndarray, shape (M, 3)
        [m].
    rgb : ndarray of uint8, shape (M, 3)
        Colours as RGB (grey 128 if none were given).
    """
    z = depth_from_disparity(disparity, focal_px=focal_px, baseline_m=baseline_m, doffs_px=doffs_px)
    keep = ~np.isnan(z)
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        if m.shape != z.shape:
            raise InputError(f"mask must have shape {z.shape}, got {m.shape}")
        keep &= m
    ys, xs = np.nonzero(keep)
    zz = z[ys, xs].astype(np.float64)
    pts = np.column_stack([(xs - cx_px) * zz / focal_px, (ys - cy_px) * zz / focal_px, zz])
    if colors is None:
        rgb = np.full((len(ys), 3), 128, np.uint8)
    else:
        c = np.asarray(colors)
        if c.shape[:2] != z.shape or c.dtype != np.uint8:
            raise InputError(f"colors must be uint8 of shape {z.shape} (+ 3), got {c.shape}")
        sel = c[ys, xs]
        rgb = np.repeat(sel[:, None], 3, axis=1) if c.ndim == 2 else sel[:, ::-1]
    return pts, np.ascontiguousarray(rgb, dtype=np.uint8)


def ply_bytes(points: ArrayLike, colors: ArrayLike | None = None) -> bytes:
    """A binary little-endian PLY file of points with optional RGB colours.

    Vertex properties ``float x, y, z`` [m] and ``uchar red, green, blue``: the layout
    MeshLab, CloudCompare, Open3D and PCL read.

    Parameters
    ----------
    points : array_like, shape (M, 3)
    colors : array_like of uint8, shape (M, 3), optional
        RGB.
    """
    pts = as_float_array(points, "points", (None, 3))
    fields: list[tuple[str, str]] = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    rgb = None
    if colors is not None:
        rgb = np.asarray(colors)
        if rgb.shape != pts.shape or rgb.dtype != np.uint8:
            raise InputError(f"colors must be uint8 of shape {pts.shape}, got {rgb.shape}")
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    rec = np.empty(len(pts), dtype=np.dtype(fields))
    for i, axis in enumerate("xyz"):
        rec[axis] = pts[:, i]
    if rgb is not None:
        for i, ch in enumerate(("red", "green", "blue")):
            rec[ch] = rgb[:, i]
    kinds = {"<f4": "float", "u1": "uchar"}
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment firefleet stereo point cloud, metres\n"
        f"element vertex {len(pts)}\n"
        + "".join(f"property {kinds[t]} {n}\n" for n, t in fields)
        + "end_header\n"
    )
    return header.encode("ascii") + rec.tobytes()


# ------------------------------------------------------------------ range scan


@dataclass(frozen=True, eq=False)
class RangeScan:
    """A virtual range scan: the nearest obstacle in each bearing sector.

    Attributes
    ----------
    bearing_rad : ndarray, shape (K,)
        Centre of each sector, from the optical axis, positive to the left [rad].
    edges_rad : ndarray, shape (K + 1,)
        Sector boundaries, increasing [rad].
    range_m : ndarray, shape (K,)
        Horizontal distance ``sqrt(X^2 + Z^2)`` to the nearest point in the sector
        [m]; ``inf`` where the sector holds no point.
    count : ndarray of int, shape (K,)
        Points in each sector.
    """

    bearing_rad: FloatArray
    edges_rad: FloatArray
    range_m: FloatArray
    count: NDArray[np.int64]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (``inf`` ranges become ``None`` through ``json_text``)."""
        return {
            "sectors": int(self.range_m.size),
            "bearing_rad": self.bearing_rad.tolist(),
            "edges_rad": self.edges_rad.tolist(),
            "range_m": self.range_m.tolist(),
            "points": self.count.tolist(),
        }


def range_scan(
    points: ArrayLike,
    *,
    n_sectors: int = 32,
    fov_rad: float,
    height_band_m: tuple[float, float] | None = None,
    max_range_m: float = math.inf,
    min_points: int = 1,
) -> RangeScan:
    """The nearest obstacle distance in each of K bearing sectors (a virtual laser scan).

    Parameters
    ----------
    points : array_like, shape (M, 3)
        Points in the camera frame (X right, Y down, Z forward) [m].
    n_sectors : int
        K, sectors of equal width across the field of view.
    fov_rad : float
        Horizontal field of view, centred on the optical axis [rad]; for a pinhole
        camera ``2 atan(W / (2 f))``.
    height_band_m : tuple of float, optional
        ``(low, high)`` heights above the camera centre [m] (``-Y``) of the points that
        count as obstacles (for example from just above the floor to the robot's top).
    max_range_m : float
        Points farther than this are ignored [m].
    min_points : int
        A sector reports its ``min_points``-th nearest point (1: the nearest), so a
        few stray points do not make a phantom obstacle.

    Returns
    -------
    RangeScan
    """
    pts = as_float_array(points, "points", (None, 3))
    if n_sectors < 1:
        raise InputError(f"n_sectors must be >= 1, got {n_sectors}")
    if not (0 < fov_rad < 2 * math.pi):
        raise InputError(f"fov_rad must be in (0, 2 pi), got {fov_rad}")
    if min_points < 1:
        raise InputError(f"min_points must be >= 1, got {min_points}")
    edges = np.linspace(-fov_rad / 2, fov_rad / 2, n_sectors + 1)
    bearing = np.arctan2(-pts[:, 0], pts[:, 2])
    rng = np.hypot(pts[:, 0], pts[:, 2])
    keep = (pts[:, 2] > 0) & (rng <= max_range_m) & (bearing >= edges[0]) & (bearing < edges[-1])
    if height_band_m is not None:
        low, high = height_band_m
        if not low < high:
            raise InputError(f"height_band_m must be (low, high) with low < high, got {low, high}")
        up = -pts[:, 1]
        keep &= (up >= low) & (up <= high)
    sector = np.clip(np.searchsorted(edges, bearing[keep], side="right") - 1, 0, n_sectors - 1)
    r = rng[keep]
    order = np.lexsort((r, sector))
    sector, r = sector[order], r[order]
    count = np.bincount(sector, minlength=n_sectors).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    ranges = np.full(n_sectors, np.inf)
    has = count >= min_points
    ranges[has] = r[start[has] + min_points - 1]
    return RangeScan(
        bearing_rad=0.5 * (edges[:-1] + edges[1:]), edges_rad=edges, range_m=ranges, count=count
    )


# --------------------------------------------------------------------- pipeline


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


def write_run(run: StereoRun, folder: Path) -> list[str]:
    """Write a :class:`StereoRun`'s files into ``folder``; returns their names.

    ``rectified_left.png``, ``rectified_right.png``, ``disparity.npy`` (float32 [px],
    NaN where none), ``disparity.png``, ``confidence.npy``, ``rectified_pair.png`` (the
    pair side by side with rows drawn, to check the rectification by eye); with metric geometry also
    ``depth.npy`` (float32 [m], NaN where none), ``cloud.ply`` and ``scan.json``.
    ``summary.json`` is written by the caller (it may add to it).
    """
    from firefleet.outputs import json_text
    from firefleet.report.stereo import disparity_png, rectified_pair_png

    folder.mkdir(parents=True, exist_ok=True)
    names = []
    for name, img in (
        ("rectified_left.png", run.rect_left),
        ("rectified_right.png", run.rect_right),
    ):
        ok, buf = cv2.imencode(".png", img)
        if not ok:
            raise InputError(f"{name}: could not be encoded")
        (folder / name).write_bytes(buf.tobytes())
        names.append(name)
    np.save(folder / "disparity.npy", run.result.disparity.astype(np.float32))
    np.save(folder / "confidence.npy", run.result.confidence.astype(np.float32))
    (folder / "disparity.png").write_bytes(disparity_png(run.result.disparity))
    (folder / "rectified_pair.png").write_bytes(rectified_pair_png(run.rect_left, run.rect_right))
    names += ["disparity.npy", "confidence.npy", "disparity.png", "rectified_pair.png"]
    if run.depth_m is not None and run.scan is not None:
        np.save(folder / "depth.npy", run.depth_m.astype(np.float32))
        (folder / "cloud.ply").write_bytes(ply_bytes(run.points, run.colors))
        (folder / "scan.json").write_text(json_text(run.scan.to_dict()), encoding="utf-8")
        names += ["depth.npy", "cloud.ply", "scan.json"]
    return names
