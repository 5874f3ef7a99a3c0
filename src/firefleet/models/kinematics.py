"""Differential-drive and unicycle kinematics (deliverable section 2.2, eqs. 1-4).

Team poses are ``(N, 3)`` arrays of x [m], y [m], theta [rad]; wheel speeds are
``(N, 2)`` arrays of right, left wheel angular speed [rad/s].

The steps integrate the kinematics exactly for inputs held over the step (the robot
moves on a circular arc, or a straight line when omega = 0), so a circle's radius is
v / omega to rounding error at any step size.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import as_float_array, check_fields

__all__ = [
    "RobotGeometry",
    "arc_step_one",
    "body_to_wheels",
    "diff_drive_step",
    "diff_drive_step_one",
    "unicycle_step",
    "wheels_to_body",
    "wrap_angle",
    "wrap_angle_one",
]


@dataclass(frozen=True)
class RobotGeometry:
    """Geometry of a differential-drive robot (deliverable Table 2).

    Attributes
    ----------
    wheel_radius_m : float
        Wheel radius r [m].
    axle_length_m : float
        Distance between the wheels L [m].

    Examples
    --------
    >>> from firefleet.models import RobotGeometry
    >>> g = RobotGeometry(wheel_radius_m=0.05, axle_length_m=0.3)
    >>> g.wheel_radius_m, g.axle_length_m
    (0.05, 0.3)
    """

    wheel_radius_m: float = 0.045
    axle_length_m: float = 0.2

    def __post_init__(self) -> None:
        check_fields(self, "robot", positive=("wheel_radius_m", "axle_length_m"))


def wrap_angle(angle_rad: ArrayLike) -> FloatArray:
    """Wrap angles to [-pi, pi) [rad].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import wrap_angle
    >>> np.round(wrap_angle([0.0, 3 * np.pi / 2, np.pi, -np.pi]), 4).tolist()
    [0.0, -1.5708, -3.1416, -3.1416]
    """
    a = np.asarray(angle_rad, dtype=np.float64)
    w = (a + np.pi) % (2.0 * np.pi) - np.pi
    # a hair below an odd multiple of -pi, the modulo rounds up to 2 pi: give -pi, not +pi
    return np.asarray(np.where(w >= np.pi, w - 2.0 * np.pi, w), dtype=np.float64)


@numba.njit(cache=True)
def wrap_angle_one(angle_rad: float) -> float:  # pragma: no cover - compiled
    """:func:`wrap_angle` of one angle, compiled (numba) for the simulator's kernels.

    The same operations as the array form, so the same result bit for bit. An angle
    already in [-pi, pi) skips the modulo: ``fmod(x, 2 pi)`` of ``0 <= x < 2 pi`` is
    ``x`` itself, so that shortcut changes no bit (tests/models/test_kinematics.py).
    """
    shifted = angle_rad + math.pi
    if not 0.0 <= shifted < 2.0 * math.pi:
        shifted = shifted % (2.0 * math.pi)
    w = shifted - math.pi
    return w - 2.0 * math.pi if w >= math.pi else w


def body_to_wheels(v_m_s: ArrayLike, omega_rad_s: ArrayLike, geometry: RobotGeometry) -> FloatArray:
    """Wheel angular speeds from body velocities (eqs. 3, 4 and v = r omega_wheel).

    Parameters
    ----------
    v_m_s : array_like, shape (N,)
        Linear speed [m/s].
    omega_rad_s : array_like, shape (N,)
        Angular speed [rad/s].
    geometry : RobotGeometry

    Returns
    -------
    ndarray, shape (N, 2)
        Right, left wheel angular speeds [rad/s]:
        ``(2 v +- omega L) / (2 r)``.

    Examples
    --------
    >>> from firefleet.models import RobotGeometry, body_to_wheels
    >>> g = RobotGeometry(wheel_radius_m=0.05, axle_length_m=0.2)
    >>> body_to_wheels([1.0, 0.0], [0.0, 1.0], g).tolist()
    [[20.0, 20.0], [2.0, -2.0]]
    """
    v = np.asarray(v_m_s, dtype=np.float64)
    w = np.asarray(omega_rad_s, dtype=np.float64)
    r, L = geometry.wheel_radius_m, geometry.axle_length_m
    return np.stack([(2.0 * v + w * L) / (2.0 * r), (2.0 * v - w * L) / (2.0 * r)], axis=-1)


def wheels_to_body(
    wheel_rad_s: ArrayLike, geometry: RobotGeometry
) -> tuple[FloatArray, FloatArray]:
    """Body velocities from wheel angular speeds (eq. 1): the inverse of eqs. 3-4.

    Parameters
    ----------
    wheel_rad_s : array_like, shape (N, 2)
        Right, left wheel angular speeds [rad/s].
    geometry : RobotGeometry

    Returns
    -------
    v_m_s, omega_rad_s : ndarray, shape (N,)
        ``v = r (w_R + w_L) / 2`` and ``omega = r (w_R - w_L) / L``.

    Examples
    --------
    >>> from firefleet.models import RobotGeometry, wheels_to_body
    >>> g = RobotGeometry(wheel_radius_m=0.05, axle_length_m=0.2)
    >>> v, omega = wheels_to_body([[22.0, 18.0]], g)
    >>> round(float(v[0]), 4), round(float(omega[0]), 4)
    (1.0, 1.0)
    """
    w = as_float_array(wheel_rad_s, "wheel_rad_s", (None, 2))
    r, L = geometry.wheel_radius_m, geometry.axle_length_m
    return r * (w[:, 0] + w[:, 1]) / 2.0, r * (w[:, 0] - w[:, 1]) / L


def _arc_step(pose: FloatArray, ds: FloatArray, dtheta: FloatArray) -> FloatArray:
    """Move along an arc of length ``ds`` turning by ``dtheta`` (exact)."""
    theta = pose[:, 2]
    half = 0.5 * dtheta
    # sin(half)/half, with its Taylor series near zero (relative error < 1e-16 below 1e-4)
    small = np.abs(half) < 1e-4
    safe = np.where(small, 1.0, half)
    sinc = np.where(small, 1.0 - half * half / 6.0, np.sin(safe) / safe)
    chord = ds * sinc
    out = np.empty_like(pose)
    out[:, 0] = pose[:, 0] + chord * np.cos(theta + half)
    out[:, 1] = pose[:, 1] + chord * np.sin(theta + half)
    out[:, 2] = wrap_angle(theta + dtheta)
    return out


@numba.njit(cache=True)
def arc_step_one(
    x_m: float, y_m: float, theta_rad: float, ds_m: float, dtheta_rad: float
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """One pose moved along an arc of length ``ds_m`` turning by ``dtheta_rad`` (exact).

    The scalar, compiled (numba) form of the arc step of :func:`unicycle_step` and
    :func:`diff_drive_step`, for the simulator's kernels: the same operations in the
    same order, the same Taylor branch of sin(h)/h below ``|h| < 1e-4``. Its sin and cos
    are the C library's; NumPy's vectorised ones may differ in the last bit.

    Returns
    -------
    x_m, y_m, theta_rad : float
        The pose after the step, theta wrapped to [-pi, pi).
    """
    half = 0.5 * dtheta_rad
    sinc = 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half
    chord = ds_m * sinc
    heading = theta_rad + half
    return (
        x_m + chord * math.cos(heading),
        y_m + chord * math.sin(heading),
        wrap_angle_one(theta_rad + dtheta_rad),
    )


@numba.njit(cache=True)
def diff_drive_step_one(
    x_m: float,
    y_m: float,
    theta_rad: float,
    dphi_right_rad: float,
    dphi_left_rad: float,
    wheel_radius_m: float,
    axle_length_m: float,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """:func:`diff_drive_step` of one robot, compiled (numba) for the simulator's kernels.

    Parameters
    ----------
    x_m, y_m, theta_rad : float
        The pose.
    dphi_right_rad, dphi_left_rad : float
        Angles turned by the right and left wheels during the step [rad].
    wheel_radius_m, axle_length_m : float
        The geometry (:class:`RobotGeometry`).

    Returns
    -------
    x_m, y_m, theta_rad : float
        The pose after the step (:func:`arc_step_one`).
    """
    ds = wheel_radius_m * (dphi_right_rad + dphi_left_rad) / 2.0
    dtheta = wheel_radius_m * (dphi_right_rad - dphi_left_rad) / axle_length_m
    return arc_step_one(x_m, y_m, theta_rad, ds, dtheta)


def unicycle_step(
    pose: ArrayLike, v_m_s: ArrayLike, omega_rad_s: ArrayLike, dt_s: float
) -> FloatArray:
    """Advance unicycle robots one step (eq. 2), exact for v, omega held over the step.

    Parameters
    ----------
    pose : array_like, shape (N, 3)
        x [m], y [m], theta [rad].
    v_m_s, omega_rad_s : array_like, shape (N,)
        Linear [m/s] and angular [rad/s] speed held over the step.
    dt_s : float
        Step [s].

    Returns
    -------
    ndarray, shape (N, 3)
        The poses after the step, theta wrapped to [-pi, pi).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import unicycle_step
    >>> pose = unicycle_step([[0.0, 0.0, 0.0]], 1.0, np.pi / 2, 1.0)
    >>> np.round(pose, 4).tolist()
    [[0.6366, 0.6366, 1.5708]]
    """
    p = as_float_array(pose, "pose", (None, 3))
    n = p.shape[0]
    v = as_float_array(np.broadcast_to(v_m_s, (n,)), "v_m_s", (n,))
    w = as_float_array(np.broadcast_to(omega_rad_s, (n,)), "omega_rad_s", (n,))
    return _arc_step(p, v * dt_s, w * dt_s)


def diff_drive_step(pose: ArrayLike, dphi_rad: ArrayLike, geometry: RobotGeometry) -> FloatArray:
    """Advance differential-drive robots by the wheel angles turned in a step (eq. 1).

    Parameters
    ----------
    pose : array_like, shape (N, 3)
        x [m], y [m], theta [rad].
    dphi_rad : array_like, shape (N, 2)
        Angle turned by the right and left wheels during the step [rad]
        (``wheel_speed * dt`` for speeds held over the step).
    geometry : RobotGeometry

    Returns
    -------
    ndarray, shape (N, 3)
        The poses after the step: exact when the two wheel speeds keep their ratio over
        the step (an arc), the usual odometry update otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import RobotGeometry, diff_drive_step
    >>> g = RobotGeometry(wheel_radius_m=0.05, axle_length_m=0.2)
    >>> np.round(diff_drive_step([[0.0, 0.0, 0.0]], [[10.0, 10.0]], g), 4).tolist()
    [[0.5, 0.0, 0.0]]
    >>> np.round(diff_drive_step([[0.0, 0.0, 0.0]], [[1.0, -1.0]], g), 4).tolist()
    [[0.0, 0.0, 0.5]]
    """
    p = as_float_array(pose, "pose", (None, 3))
    d = as_float_array(dphi_rad, "dphi_rad", (p.shape[0], 2))
    r, L = geometry.wheel_radius_m, geometry.axle_length_m
    ds = r * (d[:, 0] + d[:, 1]) / 2.0
    dtheta = r * (d[:, 0] - d[:, 1]) / L
    return _arc_step(p, ds, dtheta)
