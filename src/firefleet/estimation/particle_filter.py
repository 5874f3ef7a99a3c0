"""Monte Carlo localisation: a particle filter on a known landmark map (seed section 2.7.3).

The deliverable's filter is sequential importance sampling with the posterior
proportional to likelihood times prior::

    p(x_t | o_t) ~ p(o_t | x_t) p(x_t | x_{t-1})

Here the prior ``p(x_t | x_{t-1})`` is the *odometry motion model* (a relative motion
``delta = (dx, dy, dtheta)`` measured by the wheel encoders, in the frame of the pose it
starts from, with a Gaussian error of covariance ``cov``), the likelihood is a
*range-bearing* or *bearing-only* model of landmark observations (a heat source seen by
the thermal camera: the camera gives the bearing, range comes from the stereo pair or the
ultrasonic sensor when there is one). Particles are ``(P, 3)`` arrays of x [m], y [m],
theta [rad]; weights are kept as log weights ``(P,)``. Resampling is low-variance
(systematic) and happens when the effective sample size falls below a threshold.

These functions are shared with :mod:`firefleet.estimation.fastslam`.

References
----------
S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005: Table 4.4
(low-variance sampler), Table 8.2 (MCL), eq. 6.40 (range-bearing model).
R. Siegwart, I. Nourbakhsh, *Introduction to Autonomous Mobile Robots*, MIT Press 2004,
sec. 5.2.4 (odometry error propagated from the two wheels' travel).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray, IntArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.models.kinematics import RobotGeometry, wrap_angle

__all__ = [
    "MclParams",
    "MclResult",
    "OdometryNoise",
    "bearing_log_likelihood",
    "compose",
    "effective_sample_size",
    "gaussian_particles",
    "low_variance_resample",
    "normalise_log_weights",
    "odometry_covariance",
    "predict_range_bearing",
    "range_bearing_jacobians",
    "range_bearing_log_likelihood",
    "relative_pose",
    "run_mcl",
    "sample_odometry",
    "uniform_particles",
    "weighted_pose_mean",
]

ProgressCallback = Callable[[int, int], None]

_LOG = logging.getLogger(__name__)
_LOG_2PI = float(np.log(2.0 * np.pi))


# ----------------------------------------------------------------------------- motion


def compose(poses: ArrayLike, delta: ArrayLike) -> FloatArray:
    """Pose composition ``pose (+) delta``: move by ``delta`` given in the pose's frame.

    Parameters
    ----------
    poses : array_like, shape (..., 3)
        x [m], y [m], theta [rad].
    delta : array_like, broadcastable to (..., 3)
        Relative motion dx [m], dy [m] (in the frame of ``poses``), dtheta [rad].

    Returns
    -------
    ndarray, shape (..., 3)
        ``(x + cos(theta) dx - sin(theta) dy, y + sin(theta) dx + cos(theta) dy,
        wrap(theta + dtheta))``.
    """
    p = np.asarray(poses, dtype=np.float64)
    d = np.asarray(delta, dtype=np.float64)
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    out = np.empty(np.broadcast_shapes(p.shape, d.shape))
    out[..., 0] = p[..., 0] + c * d[..., 0] - s * d[..., 1]
    out[..., 1] = p[..., 1] + s * d[..., 0] + c * d[..., 1]
    out[..., 2] = wrap_angle(p[..., 2] + d[..., 2])
    return out


def relative_pose(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """The motion ``delta`` with ``compose(a, delta) == b`` (the inverse of :func:`compose`).

    Parameters
    ----------
    a, b : array_like, shape (..., 3)
        Poses x [m], y [m], theta [rad].

    Returns
    -------
    ndarray, shape (..., 3)
        dx, dy [m] in the frame of ``a``, dtheta [rad] wrapped to [-pi, pi).
    """
    pa = np.asarray(a, dtype=np.float64)
    pb = np.asarray(b, dtype=np.float64)
    c, s = np.cos(pa[..., 2]), np.sin(pa[..., 2])
    gx, gy = pb[..., 0] - pa[..., 0], pb[..., 1] - pa[..., 1]
    out = np.empty(np.broadcast_shapes(pa.shape, pb.shape))
    out[..., 0] = c * gx + s * gy
    out[..., 1] = -s * gx + c * gy
    out[..., 2] = wrap_angle(pb[..., 2] - pa[..., 2])
    return out


@dataclass(frozen=True)
class OdometryNoise:
    """Error model of wheel odometry (Siegwart and Nourbakhsh 2004, sec. 5.2.4).

    Each wheel's travel ``s`` [m] over a step has variance ``wheel_variance_m * |s|``
    (errors of successive centimetres are independent, so variance grows with distance,
    whatever the step length); it is propagated to ``(dx, dy, dtheta)``. A floor is added
    so that the covariance stays invertible (a robot standing still still slips).

    Attributes
    ----------
    wheel_variance_m : float
        k^2: variance of a wheel's travel per metre travelled [m^2/m = m].
    floor_sigma_xy_m : float
        Standard deviation added to dx and dy each step [m].
    floor_sigma_theta_rad : float
        Standard deviation added to dtheta each step [rad].
    """

    wheel_variance_m: float = 1e-4
    floor_sigma_xy_m: float = 1e-3
    floor_sigma_theta_rad: float = 1e-3

    def __post_init__(self) -> None:
        check_fields(
            self,
            "odometry_noise",
            non_negative=("wheel_variance_m", "floor_sigma_xy_m", "floor_sigma_theta_rad"),
        )


def odometry_covariance(
    delta: ArrayLike, geometry: RobotGeometry, noise: OdometryNoise
) -> FloatArray:
    """Covariance of odometry increments from the wheels' travel errors.

    Parameters
    ----------
    delta : array_like, shape (K, 3)
        Relative motions dx, dy [m], dtheta [rad], each an arc (constant wheel speeds).
    geometry : RobotGeometry
        Axle length L (the wheel radius does not enter: travel is in metres).
    noise : OdometryNoise

    Returns
    -------
    ndarray, shape (K, 3, 3)
        ``J diag(k^2 |s_R|, k^2 |s_L|) J^T + diag(floor^2)`` with the Jacobian J of
        ``dx = ds cos(dtheta/2)``, ``dy = ds sin(dtheta/2)``, ``dtheta = (s_R - s_L)/L``,
        ``ds = (s_R + s_L)/2`` with respect to the wheel travels (s_R, s_L)
        (Siegwart and Nourbakhsh 2004, eq. 5.9 and 5.10).
    """
    d = as_float_array(delta, "delta", (None, 3))
    L = geometry.axle_length_m
    dth = d[:, 2]
    half = 0.5 * dth
    chord = np.hypot(d[:, 0], d[:, 1])
    small = np.abs(half) < 1e-6
    sinc = np.where(small, 1.0, np.sin(np.where(small, 1.0, half)) / np.where(small, 1.0, half))
    ds = np.copysign(chord, d[:, 0]) / sinc
    s_r, s_l = ds + 0.5 * L * dth, ds - 0.5 * L * dth
    c, s = np.cos(half), np.sin(half)
    jac = np.empty((d.shape[0], 3, 2))
    jac[:, 0, 0] = 0.5 * c - ds * s / (2.0 * L)
    jac[:, 0, 1] = 0.5 * c + ds * s / (2.0 * L)
    jac[:, 1, 0] = 0.5 * s + ds * c / (2.0 * L)
    jac[:, 1, 1] = 0.5 * s - ds * c / (2.0 * L)
    jac[:, 2, 0] = 1.0 / L
    jac[:, 2, 1] = -1.0 / L
    k2 = noise.wheel_variance_m
    wheel_var = np.stack([k2 * np.abs(s_r), k2 * np.abs(s_l)], axis=-1)
    cov = np.einsum("kij,kj,klj->kil", jac, wheel_var, jac)
    floor = np.array(
        [noise.floor_sigma_xy_m**2, noise.floor_sigma_xy_m**2, noise.floor_sigma_theta_rad**2]
    )
    cov = 0.5 * (cov + np.swapaxes(cov, -1, -2)) + np.diag(floor)  # exactly symmetric
    return np.asarray(cov, dtype=np.float64)


def _sqrt_psd(cov: FloatArray) -> FloatArray:
    """A matrix square root ``S`` with ``S S^T = cov`` for a symmetric PSD ``cov`` (3, 3)."""
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    return np.asarray(vecs * np.sqrt(np.clip(vals, 0.0, None)), dtype=np.float64)


def sample_odometry(
    poses: FloatArray, delta: FloatArray, cov: FloatArray, rng: np.random.Generator
) -> FloatArray:
    """Sample the odometry motion model for every particle.

    Parameters
    ----------
    poses : ndarray, shape (P, 3)
        Particles x [m], y [m], theta [rad].
    delta : ndarray, shape (3,)
        Measured relative motion dx, dy [m], dtheta [rad] in the frame of the old pose.
    cov : ndarray, shape (3, 3)
        Covariance of the measured motion's error (symmetric positive semi-definite).
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (P, 3)
        ``compose(poses, delta + e)``, ``e ~ N(0, cov)`` drawn per particle.
    """
    noise = rng.standard_normal(poses.shape) @ _sqrt_psd(cov).T
    return compose(poses, delta + noise)


# ------------------------------------------------------------------------ measurement


def predict_range_bearing(poses: ArrayLike, landmarks: ArrayLike) -> FloatArray:
    """Range and bearing of landmarks seen from poses (Thrun et al. 2005, eq. 6.40).

    Parameters
    ----------
    poses : array_like, shape (..., 3)
        x [m], y [m], theta [rad].
    landmarks : array_like, broadcastable to (..., 2)
        Landmark x, y [m].

    Returns
    -------
    ndarray, shape (..., 2)
        Range [m] and bearing [rad] (relative to the heading, wrapped to [-pi, pi)).
    """
    p = np.asarray(poses, dtype=np.float64)
    m = np.asarray(landmarks, dtype=np.float64)
    dx, dy = m[..., 0] - p[..., 0], m[..., 1] - p[..., 1]
    return np.stack([np.hypot(dx, dy), wrap_angle(np.arctan2(dy, dx) - p[..., 2])], axis=-1)


def range_bearing_jacobians(
    poses: ArrayLike, landmarks: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Jacobians of :func:`predict_range_bearing` with respect to the pose and the landmark.

    Parameters
    ----------
    poses : array_like, shape (..., 3)
    landmarks : array_like, broadcastable to (..., 2)

    Returns
    -------
    h_pose : ndarray, shape (..., 2, 3)
        ``d(range, bearing) / d(x, y, theta)``.
    h_landmark : ndarray, shape (..., 2, 2)
        ``d(range, bearing) / d(m_x, m_y)`` (equal to minus the pose's first two columns).
    """
    p = np.asarray(poses, dtype=np.float64)
    m = np.asarray(landmarks, dtype=np.float64)
    dx, dy = m[..., 0] - p[..., 0], m[..., 1] - p[..., 1]
    q = dx * dx + dy * dy
    r = np.sqrt(q)
    h_lm = np.empty((*dx.shape, 2, 2))
    h_lm[..., 0, 0] = dx / r
    h_lm[..., 0, 1] = dy / r
    h_lm[..., 1, 0] = -dy / q
    h_lm[..., 1, 1] = dx / q
    h_pose = np.zeros((*dx.shape, 2, 3))
    h_pose[..., :, :2] = -h_lm
    h_pose[..., 1, 2] = -1.0
    return h_pose, h_lm


def range_bearing_log_likelihood(z: ArrayLike, z_pred: ArrayLike, cov: ArrayLike) -> FloatArray:
    """Gaussian log likelihood of range-bearing observations, bearing error wrapped.

    Parameters
    ----------
    z : array_like, shape (..., 2)
        Observed range [m], bearing [rad].
    z_pred : array_like, shape (..., 2)
        Predicted range and bearing.
    cov : array_like, broadcastable to (..., 2, 2)
        Innovation covariance (positive definite).

    Returns
    -------
    ndarray, shape (...)
        ``log N(z - z_pred; 0, cov)``.
    """
    nu = innovation(np.asarray(z, dtype=np.float64), np.asarray(z_pred, dtype=np.float64))
    c = np.asarray(cov, dtype=np.float64)
    inv, det = inv2(c)
    d2 = mahalanobis2(nu, inv)
    return np.asarray(-0.5 * d2 - 0.5 * np.log(det) - _LOG_2PI, dtype=np.float64)


def bearing_log_likelihood(
    bearing: ArrayLike, bearing_pred: ArrayLike, sigma_rad: ArrayLike
) -> FloatArray:
    """Gaussian log likelihood of bearing-only observations (a detection without range).

    Parameters
    ----------
    bearing, bearing_pred : array_like, shape (...)
        Observed and predicted bearing [rad].
    sigma_rad : array_like, broadcastable
        Bearing standard deviation [rad].

    Returns
    -------
    ndarray, shape (...)
        ``log N(wrap(bearing - bearing_pred); 0, sigma^2)``.
    """
    e = wrap_angle(np.asarray(bearing, dtype=np.float64) - np.asarray(bearing_pred))
    s = np.asarray(sigma_rad, dtype=np.float64)
    return np.asarray(-0.5 * (e / s) ** 2 - np.log(s) - 0.5 * _LOG_2PI, dtype=np.float64)


def innovation(z: FloatArray, z_pred: FloatArray) -> FloatArray:
    """``z - z_pred`` for (range, bearing) pairs with the bearing difference wrapped."""
    nu = z - z_pred
    nu[..., 1] = wrap_angle(nu[..., 1])
    return nu


def inv2(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Inverse and determinant of stacked 2 x 2 matrices ``(..., 2, 2)`` (closed form)."""
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    inv = np.empty_like(a)
    inv[..., 0, 0] = a[..., 1, 1] / det
    inv[..., 1, 1] = a[..., 0, 0] / det
    inv[..., 0, 1] = -a[..., 0, 1] / det
    inv[..., 1, 0] = -a[..., 1, 0] / det
    return inv, det


def mahalanobis2(nu: FloatArray, inv: FloatArray) -> FloatArray:
    """``nu^T inv nu`` for stacked 2-vectors ``(..., 2)`` and 2 x 2 matrices."""
    return np.asarray(
        inv[..., 0, 0] * nu[..., 0] ** 2
        + (inv[..., 0, 1] + inv[..., 1, 0]) * nu[..., 0] * nu[..., 1]
        + inv[..., 1, 1] * nu[..., 1] ** 2,
        dtype=np.float64,
    )


# --------------------------------------------------------------------------- weights


def normalise_log_weights(log_w: FloatArray) -> FloatArray:
    """Normalised weights ``(P,)`` from log weights (shifted by the maximum first)."""
    w = np.exp(log_w - np.max(log_w))
    return np.asarray(w / w.sum(), dtype=np.float64)


def effective_sample_size(weights: FloatArray) -> float:
    """Effective sample size ``1 / sum(w_i^2)`` of normalised weights ``(P,)``."""
    return float(1.0 / np.sum(weights * weights))


def low_variance_resample(weights: FloatArray, rng: np.random.Generator) -> IntArray:
    """Low-variance (systematic) resampling (Thrun et al. 2005, Table 4.4).

    One uniform draw ``r`` in ``[0, 1/P)``, then the particles whose cumulative weight
    intervals contain ``r + k/P``, ``k = 0..P-1``. Particle ``i`` is copied
    ``floor(P w_i)`` or ``ceil(P w_i)`` times.

    Parameters
    ----------
    weights : ndarray, shape (P,)
        Normalised weights.
    rng : numpy.random.Generator

    Returns
    -------
    ndarray of int64, shape (P,)
        Indices of the particles to keep, ascending.
    """
    n = weights.shape[0]
    cdf = np.cumsum(weights)
    cdf[-1] = 1.0  # guard against rounding: every pointer falls inside the last interval
    pointers = (rng.random() + np.arange(n)) / n
    idx = np.minimum(np.searchsorted(cdf, pointers, side="right"), n - 1)
    return np.asarray(idx, dtype=np.int64)


def weighted_pose_mean(poses: FloatArray, weights: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Weighted mean and covariance of particles, the heading averaged on the circle.

    Parameters
    ----------
    poses : ndarray, shape (P, 3)
    weights : ndarray, shape (P,)
        Normalised weights.

    Returns
    -------
    mean : ndarray, shape (3,)
        x, y [m] weighted means; theta = atan2 of the weighted mean of sin and cos.
    cov : ndarray, shape (3, 3)
        Weighted covariance, heading deviations wrapped about the mean.
    """
    mean = np.empty(3)
    mean[:2] = weights @ poses[:, :2]
    mean[2] = np.arctan2(weights @ np.sin(poses[:, 2]), weights @ np.cos(poses[:, 2]))
    dev = poses - mean
    dev[:, 2] = wrap_angle(dev[:, 2])
    cov = (dev * weights[:, None]).T @ dev
    return mean, np.asarray(cov, dtype=np.float64)


# ---------------------------------------------------------------------- initialisation


def gaussian_particles(
    pose: ArrayLike, cov: ArrayLike, n_particles: int, rng: np.random.Generator
) -> FloatArray:
    """``n_particles`` poses drawn from ``N(pose, cov)`` (a known start), shape (P, 3)."""
    mu = as_float_array(pose, "pose", (3,))
    c = as_float_array(cov, "cov", (3, 3))
    if n_particles < 1:
        raise InputError(f"n_particles must be >= 1, got {n_particles}")
    out = mu + rng.standard_normal((n_particles, 3)) @ _sqrt_psd(c).T
    out[:, 2] = wrap_angle(out[:, 2])
    return out


def uniform_particles(bounds: ArrayLike, n_particles: int, rng: np.random.Generator) -> FloatArray:
    """Particles spread uniformly over a rectangle and every heading (global localisation).

    Parameters
    ----------
    bounds : array_like, shape (4,)
        x_min, x_max, y_min, y_max [m].
    n_particles : int
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, shape (P, 3)
    """
    b = as_float_array(bounds, "bounds", (4,))
    if not (b[0] < b[1] and b[2] < b[3]):
        raise InputError(f"bounds must be x_min < x_max, y_min < y_max, got {b.tolist()}")
    if n_particles < 1:
        raise InputError(f"n_particles must be >= 1, got {n_particles}")
    u = rng.random((n_particles, 3))
    return np.stack(
        [
            b[0] + (b[1] - b[0]) * u[:, 0],
            b[2] + (b[3] - b[2]) * u[:, 1],
            -np.pi + 2.0 * np.pi * u[:, 2],
        ],
        axis=-1,
    )


# ------------------------------------------------------------------------------- MCL


@dataclass(frozen=True)
class MclParams:
    """Tuning of Monte Carlo localisation.

    Attributes
    ----------
    resample_threshold : float
        Resample when the effective sample size falls below this fraction of P, in (0, 1].
    bearing_only : bool
        Use only the bearing of each observation (a thermal detection without range).
    random_fraction : float
        Share of particles replaced by uniform ones over ``bounds`` at each resampling,
        in [0, 1): recovery from a wrong convergence (Thrun et al. 2005, sec. 8.3.5).
        Needs ``bounds``.
    bounds : tuple of float or None
        x_min, x_max, y_min, y_max [m] of the map, for ``random_fraction``.

    Examples
    --------
    >>> from firefleet.estimation import MclParams
    >>> MclParams(random_fraction=0.05, bounds=(0.0, 10.0, 0.0, 5.0)).resample_threshold
    0.5
    """

    resample_threshold: float = 0.5
    bearing_only: bool = False
    random_fraction: float = 0.0
    bounds: tuple[float, float, float, float] | None = None

    def __post_init__(self) -> None:
        if not 0.0 < self.resample_threshold <= 1.0:
            raise InputError(
                f"mcl.resample_threshold must be in (0, 1], got {self.resample_threshold}"
            )
        if not 0.0 <= self.random_fraction < 1.0:
            raise InputError(f"mcl.random_fraction must be in [0, 1), got {self.random_fraction}")
        if self.random_fraction > 0.0 and self.bounds is None:
            raise InputError("mcl.random_fraction > 0 needs mcl.bounds")


@dataclass(frozen=True)
class MclResult:
    """Estimates of :func:`run_mcl`, one per pose of the log.

    Attributes
    ----------
    mean : ndarray, shape (T, 3)
        Weighted mean pose after each update.
    cov : ndarray, shape (T, 3, 3)
        Weighted covariance of the particles.
    ess : ndarray, shape (T,)
        Effective sample size before resampling.
    resampled : ndarray of bool, shape (T,)
    particles : ndarray, shape (P, 3)
        The final particles.
    """

    mean: FloatArray
    cov: FloatArray
    ess: FloatArray
    resampled: NDArray[np.bool_]
    particles: FloatArray


def run_mcl(
    odometry: ArrayLike,
    odometry_cov: ArrayLike,
    obs_step: ArrayLike,
    obs_landmark: ArrayLike,
    obs_z: ArrayLike,
    obs_cov: ArrayLike,
    landmark_map: dict[int, tuple[float, float]],
    particles: ArrayLike,
    rng: np.random.Generator,
    *,
    params: MclParams | None = None,
    progress: ProgressCallback | None = None,
) -> MclResult:
    """Monte Carlo localisation over a log (Thrun et al. 2005, Table 8.2).

    At pose 0 the particles are weighted by the observations made there; then for each
    later pose: odometry prediction, weighting by that pose's observations, and
    low-variance resampling when the effective sample size is below the threshold.

    Parameters
    ----------
    odometry : array_like, shape (T - 1, 3)
        Relative motion from pose k to pose k + 1 (dx, dy [m] in pose k's frame, dtheta).
    odometry_cov : array_like, shape (T - 1, 3, 3)
        Its covariance.
    obs_step : array_like of int, shape (M,)
        Pose index (0..T-1) of each observation, non-decreasing.
    obs_landmark : array_like of int, shape (M,)
        Landmark id of each observation (keys of ``landmark_map``; other ids, such as
        -1 for an unassociated detection, are skipped).
    obs_z : array_like, shape (M, 2)
        Range [m], bearing [rad].
    obs_cov : array_like, shape (M, 2, 2)
        Observation covariance (range, bearing).
    landmark_map : dict of int to (x, y)
        The known map [m].
    particles : array_like, shape (P, 3)
        Initial particles (:func:`gaussian_particles` or :func:`uniform_particles`).
    rng : numpy.random.Generator
    params : MclParams, optional
    progress : callable(done, total), optional

    Returns
    -------
    MclResult

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import run_mcl
    >>> obs = dict(obs_step=[1], obs_landmark=[0], obs_z=[[1.0, 0.0]], obs_cov=[np.eye(2) * 0.01])
    >>> rng, odo_cov, p = np.random.default_rng(0), np.eye(3)[None] * 1e-4, np.zeros((200, 3))
    >>> r = run_mcl([[1.0, 0, 0]], odo_cov, **obs, landmark_map={0: (2, 0)}, particles=p, rng=rng)
    >>> (np.round(r.mean[-1], 1) + 0.0).tolist()  # 1 m driven, the landmark 1 m ahead at (2, 0)
    [1.0, 0.0, 0.0]
    """
    prm = params or MclParams()
    odo = as_float_array(odometry, "odometry", (None, 3))
    n_steps = odo.shape[0] + 1
    odo_cov = as_float_array(odometry_cov, "odometry_cov", (n_steps - 1, 3, 3))
    step = np.asarray(obs_step, dtype=np.int64)
    lm_id = np.asarray(obs_landmark, dtype=np.int64)
    m = step.shape[0]
    z = as_float_array(obs_z, "obs_z", (m, 2))
    zc = as_float_array(obs_cov, "obs_cov", (m, 2, 2))
    if lm_id.shape != (m,) or step.ndim != 1:
        raise InputError(f"obs_step and obs_landmark must have shape ({m},)")
    if m and (np.any(np.diff(step) < 0) or step[0] < 0 or step[-1] >= n_steps):
        raise InputError(f"obs_step must be non-decreasing pose indices in [0, {n_steps})")
    x = as_float_array(particles, "particles", (None, 3)).copy()
    n = x.shape[0]
    ids = np.array(sorted(landmark_map), dtype=np.int64)
    xy = np.array([landmark_map[int(i)] for i in ids], dtype=np.float64).reshape(-1, 2)
    starts = np.searchsorted(step, np.arange(n_steps + 1))

    log_w = np.zeros(n)
    mean = np.empty((n_steps, 3))
    cov = np.empty((n_steps, 3, 3))
    ess = np.empty(n_steps)
    resampled = np.zeros(n_steps, dtype=bool)
    for k in range(n_steps):
        if k > 0:
            x = sample_odometry(x, odo[k - 1], odo_cov[k - 1], rng)
        for j in range(starts[k], starts[k + 1]):
            slot = np.searchsorted(ids, lm_id[j])
            if slot >= ids.size or ids[slot] != lm_id[j]:
                continue
            z_pred = predict_range_bearing(x, xy[slot])
            if prm.bearing_only:
                log_w += bearing_log_likelihood(z[j, 1], z_pred[:, 1], np.sqrt(zc[j, 1, 1]))
            else:
                log_w += range_bearing_log_likelihood(z[j], z_pred, zc[j])
        w = normalise_log_weights(log_w)
        mean[k], cov[k] = weighted_pose_mean(x, w)
        ess[k] = effective_sample_size(w)
        if ess[k] < prm.resample_threshold * n:
            x = x[low_variance_resample(w, rng)]
            if prm.random_fraction > 0.0 and prm.bounds is not None:
                n_rand = round(prm.random_fraction * n)
                pick = rng.choice(n, size=n_rand, replace=False)
                x[pick] = uniform_particles(prm.bounds, n_rand, rng)
            log_w = np.zeros(n)
            resampled[k] = True
        if progress is not None:
            progress(k + 1, n_steps)
    _LOG.debug("MCL: %d steps, %d resamplings", n_steps, int(resampled.sum()))
    return MclResult(mean=mean, cov=cov, ess=ess, resampled=resampled, particles=x)
