"""The thermal camera's geometry: pinhole with Brown-Conrady distortion."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields

LEPTON_HFOV_RAD = math.radians(51.0)
"""Lepton 2.5 / 3.5 horizontal field of view (deliverable 2.7.1.2)."""


@dataclass(frozen=True)
class CameraModel:
    """Pinhole camera with Brown-Conrady lens distortion (OpenCV's convention).

    Pixel ``(row, col)`` has its centre at ``(row, col)``; the image spans
    ``[-0.5, width - 0.5]`` horizontally. The optical axis is horizontal and points
    along the robot's heading; bearings are positive to the left (counter-clockwise,
    the robot frame's convention).

    Attributes
    ----------
    width_px, height_px : int
        Image size [px] (Lepton 2.x: 80 x 60).
    hfov_rad : float
        Horizontal field of view of the undistorted pinhole [rad]; sets
        ``fx = (width / 2) / tan(hfov / 2)``, square pixels (``fy = fx``).
    cx_px, cy_px : float or None
        Principal point [px]; ``None`` is the image centre ``((W-1)/2, (H-1)/2)``.
    k1, k2, p1, p2 : float
        Radial and tangential distortion coefficients (OpenCV ``distCoeffs`` order
        k1, k2, p1, p2), on normalised coordinates.

    Examples
    --------
    >>> import math
    >>> from firefleet.perception.thermal import CameraModel
    >>> camera = CameraModel(width_px=80, height_px=60, hfov_rad=math.radians(90.0))
    >>> round(camera.fx_px, 6), camera.principal_point  # (80 / 2) / tan(45 deg)
    (40.0, (39.5, 29.5))
    >>> round(float(camera.bearing(29.5, 0.0)), 4)  # the left edge pixel's centre, positive left
    0.7791
    """

    width_px: int = 80
    height_px: int = 60
    hfov_rad: float = LEPTON_HFOV_RAD
    cx_px: float | None = None
    cy_px: float | None = None
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0

    def __post_init__(self) -> None:
        check_fields(self, "camera", positive=("width_px", "height_px", "hfov_rad"))
        if not self.hfov_rad < math.pi:
            raise InputError(f"camera.hfov_rad must be < pi, got {self.hfov_rad}")
        for name in ("k1", "k2", "p1", "p2"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"camera.{name} must be finite, got {getattr(self, name)}")

    @classmethod
    def for_frame(cls, shape: tuple[int, ...], *, hfov_deg: float = 51.0) -> CameraModel:
        """An undistorted camera of the frame's size (rows, cols) and a field of view [deg]."""
        if len(shape) != 2:
            raise InputError(f"frame shape must be (H, W), got {shape}")
        if not 0.0 < hfov_deg < 180.0:
            raise InputError(f"hfov_deg must be in (0, 180) degrees, got {hfov_deg}")
        return cls(width_px=int(shape[1]), height_px=int(shape[0]), hfov_rad=math.radians(hfov_deg))

    @property
    def fx_px(self) -> float:
        """Focal length [px]."""
        return 0.5 * self.width_px / math.tan(0.5 * self.hfov_rad)

    @property
    def principal_point(self) -> tuple[float, float]:
        """(cx, cy) [px]."""
        cx = 0.5 * (self.width_px - 1) if self.cx_px is None else self.cx_px
        cy = 0.5 * (self.height_px - 1) if self.cy_px is None else self.cy_px
        return cx, cy

    @property
    def pixel_angle_rad(self) -> float:
        """Mean angle of one pixel across the image, ``hfov / width`` [rad] (Lepton: 0.6375 deg)."""
        return self.hfov_rad / self.width_px

    @property
    def distorted(self) -> bool:
        """True if any distortion coefficient is non-zero."""
        return any((self.k1, self.k2, self.p1, self.p2))

    def _distort(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        r2 = x * x + y * y
        radial = 1.0 + r2 * (self.k1 + self.k2 * r2)
        xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x)
        yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y
        return xd, yd

    def normalized(self, rows: ArrayLike, cols: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Undistorted normalised coordinates ``(x, y)`` (x right, y down) of pixel positions.

        Parameters
        ----------
        rows, cols : array_like, broadcastable
            Pixel positions [px], sub-pixel allowed.

        Returns
        -------
        x, y : ndarray
            Ray direction ``(x, y, 1)`` in the camera frame. With distortion, the
            fixed-point iteration of OpenCV's ``undistortPoints`` (20 iterations).
        """
        cx, cy = self.principal_point
        f = self.fx_px
        xd = (np.asarray(cols, dtype=np.float64) - cx) / f
        yd = (np.asarray(rows, dtype=np.float64) - cy) / f
        xd, yd = np.broadcast_arrays(xd, yd)
        if not self.distorted:
            return xd.copy(), yd.copy()
        x, y = xd.copy(), yd.copy()
        for _ in range(20):
            r2 = x * x + y * y
            radial = 1.0 + r2 * (self.k1 + self.k2 * r2)
            dx = 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x)
            dy = self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y
            x = (xd - dx) / radial
            y = (yd - dy) / radial
        return x, y

    def project(self, x: ArrayLike, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Pixel ``(rows, cols)`` of normalised coordinates (distortion applied)."""
        cx, cy = self.principal_point
        xd, yd = self._distort(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
        return cy + self.fx_px * yd, cx + self.fx_px * xd

    def bearing(self, rows: ArrayLike, cols: ArrayLike) -> FloatArray:
        """Azimuth of pixel positions [rad], positive to the left of the optical axis."""
        x, _ = self.normalized(rows, cols)
        return np.asarray(-np.arctan(x), dtype=np.float64)
