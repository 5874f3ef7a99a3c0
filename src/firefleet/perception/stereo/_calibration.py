"""Stereo calibration: the rig's parameters, their YAML file, chessboards, Zhang's method."""

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
from numpy.typing import ArrayLike

from firefleet._typing import Float32Array, FloatArray
from firefleet.errors import InputError, as_float_array
from firefleet.perception.stereo._images import (
    _check_image,
    _grey,
    check_pair,
)

log = logging.getLogger("firefleet.perception.stereo")

CALIBRATION_FORMAT = "firefleet-stereo-calibration/1"
"""Value of the ``format`` key that every calibration file starts with."""


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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import StereoCalibration
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> calib.image_size, float(np.linalg.norm(calib.translation_m))
    ((160, 120), 0.1)
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


def calibration_yaml(calib: StereoCalibration) -> str:
    """A calibration as YAML text, the file :func:`load_calibration` reads.

    The library writes no file: the caller saves the text where it chooses, e.g.
    ``Path("rig.yaml").write_text(calibration_yaml(calib))``.

    The text (``format: firefleet-stereo-calibration/1``) holds ``image_size``
    ``[width, height]`` [px]; ``left`` and ``right``, each with ``camera_matrix`` (3 rows
    of 3) [px] and ``distortion`` ``[k1, k2, p1, p2, k3]``; ``rotation`` (3 rows of 3)
    and ``translation_m`` ``[tx, ty, tz]`` [m] from the left camera's frame to the
    right's; ``rms_reprojection_px`` (null if unknown).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import CALIBRATION_FORMAT, StereoCalibration
    >>> from firefleet.perception.stereo import calibration_yaml
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> CALIBRATION_FORMAT in calibration_yaml(calib)
    True
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
    return str(yaml.safe_dump(doc, sort_keys=False))


def load_calibration(path: str | Path) -> StereoCalibration:
    """Read a calibration file (the YAML text of :func:`calibration_yaml`).

    Raises
    ------
    InputError
        If the file is missing, not YAML, not of this format, or a field is missing or
        malformed (the message names it).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from firefleet.perception.stereo import StereoCalibration, calibration_yaml
    >>> from firefleet.perception.stereo import load_calibration
    >>> k = np.array([[100.0, 0.0, 79.5], [0.0, 100.0, 59.5], [0.0, 0.0, 1.0]])
    >>> calib = StereoCalibration(image_size=(160, 120), k_left=k, dist_left=np.zeros(5),
    ...     k_right=k, dist_right=np.zeros(5), rotation=np.eye(3),
    ...     translation_m=np.array([-0.1, 0.0, 0.0]))
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "rig.yaml"
    >>> _ = path.write_text(calibration_yaml(calib))
    >>> again = load_calibration(path)
    >>> again.image_size, bool(np.array_equal(again.k_left, k)), again.translation_m.tolist()
    ((160, 120), True, [-0.1, 0.0, 0.0])
    >>> folder.cleanup()
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import find_chessboard
    >>> squares = np.kron(np.indices((7, 10)).sum(0) % 2 * 255, np.ones((20, 20)))
    >>> board = np.pad(squares.astype(np.uint8), 20, constant_values=255)  # 9 x 6 inner corners
    >>> find_chessboard(board, pattern_size=(9, 6)).shape
    (54, 2)
    >>> find_chessboard(np.full((100, 100), 255, np.uint8)) is None
    True
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.errors import InputError
    >>> from firefleet.perception.stereo import calibrate_stereo
    >>> squares = np.kron(np.indices((7, 10)).sum(0) % 2 * 255, np.ones((20, 20)))
    >>> board = np.pad(squares.astype(np.uint8), 20, constant_values=255)
    >>> try:  # one view of the board is not enough
    ...     calibrate_stereo([board], [board])
    ... except InputError as error:
    ...     print(error)
    calibration needs at least 3 pairs showing the whole 9 x 6 board in both images, found 1
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
