"""Smoke along a ray: the optical depth of the smoke field and where it reaches a limit
(compiled).

Smoke's extinction coefficient ``sigma`` [1/m] (:data:`firefleet.world.SMOKE`: optical
density per metre on the field grid) dims light along a path by Beer-Lambert's law,
``T = exp(-tau)`` with the optical depth ``tau = integral of sigma ds``. On the field
grid ``sigma`` is constant in each cell, so the integral is exact: the ray walks the
cells it crosses in order (Amanatides and Woo's traversal, as the range sensors'
:mod:`._ranging_cast` on the map) and adds ``sigma`` times the length of the ray in each.
Cells off the grid hold no smoke.

A sensor that needs ``T^passes >= threshold`` to get a return (``passes`` 2 for a lidar:
out and back; 1 for a camera looking at a lit surface) sees through an optical depth of
at most ``tau_max = -ln(threshold) / passes``: :class:`SmokeOptics`. The range at which
the ray's optical depth reaches ``tau_max`` (:func:`smoke_reach`) is where it goes
blind: in uniform smoke ``ln(threshold) / (-passes sigma)``.

:func:`smoke_walk` is the scalar function; :func:`smoke_reach_team` runs it for every
robot and every bearing and :func:`optical_depth_segments` for every segment (the
batched paths are that same function in a loop).

References
----------
J. Amanatides, A. Woo, "A fast voxel traversal algorithm for ray tracing",
Eurographics 1987.
D. Drysdale, An Introduction to Fire Dynamics, 3rd ed., Wiley 2011, ch. 11 (smoke
optical density, Beer-Lambert's law).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array
from firefleet.sim._ranging_cast import axis_step
from firefleet.world import OccupancyGrid

__all__ = [
    "LIDAR_OPTICS",
    "STEREO_OPTICS",
    "SmokeField",
    "SmokeOptics",
    "optical_depth_segments",
    "smoke_reach",
    "smoke_reach_team",
    "smoke_walk",
]


@dataclass(frozen=True)
class SmokeOptics:
    """How much smoke a visible-light sensor sees through.

    Attributes
    ----------
    passes : int
        Times the light crosses the smoke between source and detector: 2 for an active
        sensor (a lidar's pulse out and back), 1 for a camera looking at a lit scene.
    threshold : float
        Least transmittance ``exp(-passes tau)`` that still gives a reading, in (0, 1).

    Examples
    --------
    >>> from firefleet.sim._smoke_cast import SmokeOptics
    >>> round(SmokeOptics(passes=2, threshold=0.01).max_depth, 4)  # -ln(0.01) / 2
    2.3026
    """

    passes: int
    threshold: float

    def __post_init__(self) -> None:
        if isinstance(self.passes, bool) or self.passes not in (1, 2):
            raise InputError(f"smoke optics: passes must be 1 or 2, got {self.passes!r}")
        if not (0.0 < self.threshold < 1.0):
            raise InputError(f"smoke optics: threshold must be in (0, 1), got {self.threshold}")

    @property
    def max_depth(self) -> float:
        """The largest one-way optical depth the sensor sees through, ``-ln(t) / passes``."""
        return -math.log(self.threshold) / self.passes


LIDAR_OPTICS = SmokeOptics(passes=2, threshold=0.01)
"""A lidar's return is lost when the smoke takes more than 99 % of its two-way light
(one-way optical depth 2.3): an assumption of this model, in line with lidars ranging
in light smoke and failing in dense smoke (Starr and Lattimer 2014)."""

STEREO_OPTICS = SmokeOptics(passes=1, threshold=math.exp(-3.0))
"""The stereo pair matches a lit surface while its contrast, dimmed one way by
``exp(-tau)``, stays above the eye-like threshold of Jin's law for a light-reflecting
object: ``tau <= 3`` (visibility ``V = 3 / sigma``; Jin 1978)."""


@dataclass(frozen=True, eq=False)
class SmokeField:
    """The smoke the visible-light sensors look through.

    Attributes
    ----------
    grid : OccupancyGrid
        The field grid's geometry (resolution, origin, shape); its walls do not matter
        here (the map's walls stop the rays).
    extinction_per_m : ndarray, shape (H, W)
        Extinction coefficient [1/m] per cell, >= 0.
    lidar, stereo : SmokeOptics
        What each sensor sees through.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim._smoke_cast import SmokeField
    >>> from firefleet.world import OccupancyGrid
    >>> free = np.zeros((4, 4), dtype=bool)
    >>> smoke = SmokeField(OccupancyGrid(free, ~free, resolution_m=0.5), np.full((4, 4), 0.5))
    >>> smoke.extinction_per_m.shape
    (4, 4)
    """

    grid: OccupancyGrid
    extinction_per_m: FloatArray
    lidar: SmokeOptics = LIDAR_OPTICS
    stereo: SmokeOptics = STEREO_OPTICS

    def __post_init__(self) -> None:
        sigma = np.ascontiguousarray(self.extinction_per_m, dtype=np.float64)
        if sigma.shape != self.grid.shape:
            raise InputError(
                f"smoke: extinction {sigma.shape} must have the field grid's shape "
                f"{self.grid.shape}"
            )
        if not (np.isfinite(sigma).all() and (sigma >= 0.0).all()):
            raise InputError("smoke: the extinction must be finite and >= 0 [1/m]")
        object.__setattr__(self, "extinction_per_m", sigma)


@numba.njit(cache=True)
def smoke_walk(
    extinction: np.ndarray,
    resolution_m: float,
    origin_x_m: float,
    origin_y_m: float,
    x: float,
    y: float,
    angle_rad: float,
    length_m: float,
    depth_limit: float,
) -> tuple[float, float]:
    """Optical depth of one ray over ``[0, length_m]`` and where it reaches a limit.

    ``extinction`` (H, W) [1/m], row 0 at the top. Returns ``(tau, reach_m)``: ``tau``
    the optical depth from the start to ``min(length_m, reach_m)``, ``reach_m`` the
    distance at which it first reaches ``depth_limit`` (``inf`` if not within
    ``length_m``; ``depth_limit = inf``: the plain integral).
    """
    dx = math.cos(angle_rad)
    dy = math.sin(angle_rad)
    h, w = extinction.shape
    u = (x - origin_x_m) / resolution_m
    v = (y - origin_y_m) / resolution_m
    i = math.floor(u)
    j = math.floor(v)
    step_i, t_next_i, dt_i = axis_step(u, i, dx)
    step_j, t_next_j, dt_j = axis_step(v, j, dy)
    limit = length_m / resolution_m  # in cells
    t = 0.0
    tau = 0.0
    while t < limit:
        t_exit = min(t_next_i, t_next_j, limit)
        if 0 <= i < w and 0 <= j < h:
            sigma = extinction[h - 1 - j, i]
            if sigma > 0.0:
                seg = (t_exit - t) * resolution_m
                if tau + sigma * seg >= depth_limit:
                    return depth_limit, t * resolution_m + (depth_limit - tau) / sigma
                tau += sigma * seg
        elif (i < 0 and step_i <= 0) or (i >= w and step_i >= 0):
            break  # off the grid and leaving it: no more smoke
        elif (j < 0 and step_j <= 0) or (j >= h and step_j >= 0):
            break
        if t_exit >= limit:
            break
        if t_next_i < t_next_j:
            t = t_next_i
            t_next_i += dt_i
            i += step_i
        else:
            t = t_next_j
            t_next_j += dt_j
            j += step_j
    return tau, math.inf


@numba.njit(cache=True)
def _reach_team(
    extinction: np.ndarray,
    resolution_m: float,
    origin_x_m: float,
    origin_y_m: float,
    poses: np.ndarray,
    bearings_rad: np.ndarray,
    max_range_m: float,
    depth_limit: float,
    out: np.ndarray,
) -> None:
    for a in range(poses.shape[0]):
        for q in range(bearings_rad.shape[0]):
            out[a, q] = smoke_walk(
                extinction,
                resolution_m,
                origin_x_m,
                origin_y_m,
                poses[a, 0],
                poses[a, 1],
                poses[a, 2] + bearings_rad[q],
                max_range_m,
                depth_limit,
            )[1]


def smoke_reach_team(
    smoke: SmokeField,
    poses: FloatArray,
    bearings_rad: FloatArray,
    max_range_m: float,
    optics: SmokeOptics,
) -> FloatArray:
    """Where each robot's rays go blind in the smoke [m], shape (N, K) (``inf``: not
    within ``max_range_m``).

    Ray ``q`` of robot ``a`` starts at its centre, at ``theta_a + bearings_rad[q]``; it
    goes blind where its optical depth reaches ``optics.max_depth``.
    """
    p = np.ascontiguousarray(poses, dtype=np.float64)
    b = np.ascontiguousarray(bearings_rad, dtype=np.float64)
    out = np.empty((p.shape[0], b.shape[0]))
    g = smoke.grid
    _reach_team(
        smoke.extinction_per_m,
        float(g.resolution_m),
        float(g.origin_m[0]),
        float(g.origin_m[1]),
        p,
        b,
        float(max_range_m),
        float(optics.max_depth),
        out,
    )
    return out


def smoke_reach(
    smoke: SmokeField, poses: ArrayLike, bearings_rad: ArrayLike, optics: SmokeOptics
) -> FloatArray:
    """Distance [m] at which each ray goes blind in the smoke, shape (N, K).

    Parameters
    ----------
    smoke : SmokeField
    poses : array_like, shape (N, 3)
        x [m], y [m], theta [rad].
    bearings_rad : array_like, shape (K,)
        Ray bearings from the heading [rad].
    optics : SmokeOptics

    Returns
    -------
    ndarray, shape (N, K)
        ``inf`` where the ray never goes blind on the grid.

    Examples
    --------
    Uniform smoke of 0.5 1/m: a lidar (two passes, threshold 0.01) goes blind at
    ``ln(0.01) / (-2 x 0.5) = 4.6 m``.

    >>> import numpy as np
    >>> from firefleet.sim._smoke_cast import LIDAR_OPTICS, SmokeField, smoke_reach
    >>> from firefleet.world import OccupancyGrid
    >>> free = np.zeros((40, 40), dtype=bool)
    >>> smoke = SmokeField(OccupancyGrid(free, ~free, resolution_m=0.25), np.full((40, 40), 0.5))
    >>> smoke_reach(smoke, [[0.1, 5.0, 0.0]], [0.0], LIDAR_OPTICS).round(4).tolist()
    [[4.6052]]
    """
    p = as_float_array(poses, "poses", (None, 3))
    b = np.atleast_1d(np.asarray(bearings_rad, dtype=float))
    g = smoke.grid
    diag = float(np.hypot(*g.shape)) * g.resolution_m
    far = float(np.max(np.hypot(p[:, 0] - g.origin_m[0], p[:, 1] - g.origin_m[1]), initial=0.0))
    return smoke_reach_team(smoke, p, b, far + diag, optics)


@numba.njit(cache=True)
def _depth_segments(
    extinction: np.ndarray,
    resolution_m: float,
    origin_x_m: float,
    origin_y_m: float,
    start: np.ndarray,
    end: np.ndarray,
    out: np.ndarray,
) -> None:
    for k in range(start.shape[0]):
        ex = end[k, 0] - start[k, 0]
        ey = end[k, 1] - start[k, 1]
        out[k] = smoke_walk(
            extinction,
            resolution_m,
            origin_x_m,
            origin_y_m,
            start[k, 0],
            start[k, 1],
            math.atan2(ey, ex),
            math.hypot(ex, ey),
            math.inf,
        )[0]


def optical_depth_segments(smoke: SmokeField, start_m: ArrayLike, end_m: ArrayLike) -> FloatArray:
    """Optical depth ``integral of sigma ds`` along each segment, shape (M,).

    Parameters
    ----------
    smoke : SmokeField
    start_m, end_m : array_like, shape (M, 2)
        Segment ends x [m], y [m].

    Returns
    -------
    ndarray, shape (M,)
        Optical depth (dimensionless); the transmittance is ``exp(-depth)``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim._smoke_cast import SmokeField, optical_depth_segments
    >>> from firefleet.world import OccupancyGrid
    >>> free = np.zeros((8, 8), dtype=bool)
    >>> smoke = SmokeField(OccupancyGrid(free, ~free, resolution_m=0.5), np.full((8, 8), 0.2))
    >>> optical_depth_segments(smoke, [[0.5, 0.5]], [[3.5, 3.5]]).round(6).tolist()  # 0.6 sqrt 2
    [0.848528]
    """
    a = as_float_array(start_m, "start_m", (None, 2))
    b = as_float_array(end_m, "end_m", (a.shape[0], 2))
    out = np.empty(a.shape[0])
    g = smoke.grid
    _depth_segments(
        smoke.extinction_per_m,
        float(g.resolution_m),
        float(g.origin_m[0]),
        float(g.origin_m[1]),
        np.ascontiguousarray(a),
        np.ascontiguousarray(b),
        out,
    )
    return out
