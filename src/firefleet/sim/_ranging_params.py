"""The range sensors' parameters (:mod:`firefleet.sim.ranging` re-exports them)."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError

__all__ = ["LidarParams", "StereoScanParams", "UltrasonicParams"]


def _check(
    obj: Any, section: str, *, positive: tuple[str, ...], non_negative: tuple[str, ...] = ()
) -> None:
    """Each named field a finite number (> 0 or >= 0), else InputError naming it."""
    for name in positive + non_negative:
        value = getattr(obj, name)
        ok = (
            isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
        )
        if not ok or (value <= 0 if name in positive else value < 0):
            bound = "> 0" if name in positive else ">= 0"
            raise InputError(f"{section}.{name} must be a finite number {bound}, got {value!r}")


def _check_int(obj: Any, section: str, name: str, low: int) -> None:
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise InputError(f"{section}.{name} must be an integer >= {low}, got {value!r}")


@dataclass(frozen=True)
class UltrasonicParams:
    """An HC-SR04-like ultrasonic ring.

    Attributes
    ----------
    count : int
        Sensors, evenly around the robot, the first facing ahead.
    fov_deg : float
        Full width of each sensor's cone [deg] (HC-SR04: 15).
    min_range_m, max_range_m : float
        Nearest and farthest range measured [m] (HC-SR04: 0.02 and 4); nearer reads
        ``min_range_m``, farther ``inf``.
    noise_m : float
        Standard deviation of the Gaussian range noise [m].
    rays_per_cone : int
        Rays cast across each cone, its edges included (1: along the axis only).
    dropout : float
        ``p0``, the probability of a lost echo at normal incidence.
    dropout_incidence_deg : float
        ``i50``, the incidence angle at which half the echoes are lost [deg].
    dropout_width_deg : float
        ``w``, how gradually the loss rises about ``i50`` [deg].
    rate_hz : float
        Rate of a full ring of readings in the loop (:class:`RangeSensors`) [Hz]
        (HC-SR04: a 60 ms cycle, about 16 Hz).

    Examples
    --------
    >>> from firefleet.sim.ranging import UltrasonicParams
    >>> p = UltrasonicParams()
    >>> p.count, p.bearings_rad.round(3).tolist()[:3]
    (8, [0.0, 0.785, 1.571])
    """

    count: int = 8
    fov_deg: float = 15.0
    min_range_m: float = 0.02
    max_range_m: float = 4.0
    noise_m: float = 0.01
    rays_per_cone: int = 5
    dropout: float = 0.01
    dropout_incidence_deg: float = 50.0
    dropout_width_deg: float = 6.0
    rate_hz: float = 15.0

    def __post_init__(self) -> None:
        s = "ultrasonic"
        _check_int(self, s, "count", 1)
        _check_int(self, s, "rays_per_cone", 1)
        _check(
            self,
            s,
            positive=("fov_deg", "max_range_m", "dropout_width_deg", "rate_hz"),
            non_negative=("min_range_m", "noise_m", "dropout", "dropout_incidence_deg"),
        )
        if not self.min_range_m < self.max_range_m:
            raise InputError(
                f"ultrasonic.min_range_m must be < max_range_m ({self.max_range_m}), "
                f"got {self.min_range_m}"
            )
        if not self.dropout < 1.0:
            raise InputError(f"ultrasonic.dropout must be a probability < 1, got {self.dropout}")
        if not self.fov_deg < 180.0:
            raise InputError(f"ultrasonic.fov_deg must be < 180 degrees, got {self.fov_deg}")

    @property
    def bearings_rad(self) -> FloatArray:
        """Each sensor's axis from the heading, positive to the left [rad], shape (K,)."""
        return 2.0 * np.pi * np.arange(self.count) / self.count

    @property
    def ray_offsets_rad(self) -> FloatArray:
        """The rays of one cone about its axis [rad], shape (rays_per_cone,)."""
        if self.rays_per_cone == 1:
            return np.zeros(1)
        half = math.radians(self.fov_deg) / 2.0
        return np.linspace(-half, half, self.rays_per_cone)

    def dropout_probability(self, incidence_rad: ArrayLike) -> FloatArray:
        """Probability of a lost echo at each incidence angle [rad] (see the module notes).

        Examples
        --------
        >>> import numpy as np
        >>> from firefleet.sim.ranging import UltrasonicParams
        >>> p = UltrasonicParams(dropout=0.0, dropout_incidence_deg=50.0)
        >>> float(p.dropout_probability(np.radians(50.0)))
        0.5
        """
        i = np.asarray(incidence_rad, dtype=float)
        z = (i - math.radians(self.dropout_incidence_deg)) / math.radians(self.dropout_width_deg)
        return np.asarray(self.dropout + (1.0 - self.dropout) * 0.5 * (1.0 + np.tanh(z / 2.0)))


@dataclass(frozen=True)
class LidarParams:
    """A planar scanning lidar.

    Attributes
    ----------
    beams : int
        Beams, evenly over the field of view.
    fov_deg : float
        Field of view centred on the heading [deg], up to 360 (then the beams are
        ``2 pi / beams`` apart, the first straight behind).
    max_range_m : float
        Farthest range [m]; farther reads ``inf``.
    noise_m : float
        Standard deviation of the Gaussian range noise [m].
    rate_hz : float
        Scan rate in the loop (:class:`RangeSensors`) [Hz].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.ranging import LidarParams
    >>> np.degrees(LidarParams(beams=4).bearings_rad).tolist()
    [-180.0, -90.0, 0.0, 90.0]
    >>> np.degrees(LidarParams(beams=3, fov_deg=180.0).bearings_rad).tolist()
    [-90.0, 0.0, 90.0]
    """

    beams: int = 90
    fov_deg: float = 360.0
    max_range_m: float = 10.0
    noise_m: float = 0.01
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        _check_int(self, "lidar", "beams", 1)
        _check(
            self, "lidar", positive=("fov_deg", "max_range_m", "rate_hz"), non_negative=("noise_m",)
        )
        if self.fov_deg > 360.0:
            raise InputError(f"lidar.fov_deg must be <= 360 degrees, got {self.fov_deg}")

    @property
    def bearings_rad(self) -> FloatArray:
        """Each beam's bearing from the heading, positive to the left [rad], shape (B,)."""
        fov = math.radians(self.fov_deg)
        if self.fov_deg >= 360.0:
            return -np.pi + 2.0 * np.pi * np.arange(self.beams) / self.beams
        if self.beams == 1:
            return np.zeros(1)
        return np.linspace(-fov / 2.0, fov / 2.0, self.beams)


@dataclass(frozen=True)
class StereoScanParams:
    """The stereo pair's virtual range scan (``firefleet stereo``), looking ahead.

    Attributes
    ----------
    sectors : int
        S, equal bearing sectors across the field of view (the ``stereo`` command's 32).
    width_px : int
        Image width W [px].
    focal_px : float
        Rectified focal length f [px]; the field of view is ``2 atan(W / (2 f))``.
    baseline_m : float
        Baseline B [m].
    disparity_noise_px : float
        ``sigma_d``, the matcher's disparity noise [px] (sub-pixel SGBM: a few tenths).
    min_range_m : float
        Nearest range measured (the disparity search's near limit) [m]; nearer reads
        ``min_range_m``.
    max_range_m : float
        Farthest range reported [m]; farther reads ``inf``.
    rays_per_sector : int
        Rays across each sector, its edges included.
    rate_hz : float
        Frame rate in the loop (:class:`RangeSensors`) [Hz].

    Examples
    --------
    >>> import math
    >>> from firefleet.sim.ranging import StereoScanParams
    >>> p = StereoScanParams()
    >>> round(math.degrees(p.fov_rad), 1), p.bearings_rad.shape
    (56.1, (32,))
    """

    sectors: int = 32
    width_px: int = 640
    focal_px: float = 600.0
    baseline_m: float = 0.1
    disparity_noise_px: float = 0.25
    min_range_m: float = 0.3
    max_range_m: float = 8.0
    rays_per_sector: int = 3
    rate_hz: float = 10.0

    def __post_init__(self) -> None:
        s = "stereo"
        _check_int(self, s, "sectors", 1)
        _check_int(self, s, "width_px", 1)
        _check_int(self, s, "rays_per_sector", 1)
        _check(
            self,
            s,
            positive=("focal_px", "baseline_m", "max_range_m", "rate_hz"),
            non_negative=("disparity_noise_px", "min_range_m"),
        )
        if not self.min_range_m < self.max_range_m:
            raise InputError(
                f"stereo.min_range_m must be < max_range_m ({self.max_range_m}), "
                f"got {self.min_range_m}"
            )

    @property
    def fov_rad(self) -> float:
        """Horizontal field of view ``2 atan(W / (2 f))`` [rad]."""
        return 2.0 * math.atan(self.width_px / (2.0 * self.focal_px))

    @property
    def edges_rad(self) -> FloatArray:
        """Sector boundaries from the heading, increasing [rad], shape (S + 1,)."""
        return np.linspace(-self.fov_rad / 2.0, self.fov_rad / 2.0, self.sectors + 1)

    @property
    def bearings_rad(self) -> FloatArray:
        """Each sector's centre from the heading, positive to the left [rad], shape (S,)."""
        e = self.edges_rad
        return 0.5 * (e[:-1] + e[1:])

    def depth_sigma_m(self, depth_m: ArrayLike) -> FloatArray:
        """``sigma_Z = Z^2 sigma_d / (f B)`` [m] at each depth [m].

        Examples
        --------
        >>> from firefleet.sim.ranging import StereoScanParams
        >>> p = StereoScanParams(focal_px=600.0, baseline_m=0.1, disparity_noise_px=0.3)
        >>> float(p.depth_sigma_m(2.0))  # 2^2 0.3 / (600 0.1)
        0.02
        """
        z = np.asarray(depth_m, dtype=float)
        return np.asarray(z**2 * self.disparity_noise_px / (self.focal_px * self.baseline_m))

    def ray_bearings_rad(self) -> FloatArray:
        """The rays of every sector [rad], shape (S, rays_per_sector)."""
        e = self.edges_rad
        if self.rays_per_sector == 1:
            return self.bearings_rad[:, None]
        f = np.linspace(0.0, 1.0, self.rays_per_sector)
        return e[:-1, None] + f[None, :] * (e[1:] - e[:-1])[:, None]
