"""FastSLAM 1.0 and 2.0 with range-bearing landmarks, vectorised over particles.

The seed's particle-filter SLAM (section 2.7.3, ``p(x_t | o_t) ~ p(o_t | x_t)
p(x_t | x_{t-1})``) in its Rao-Blackwellised form: each particle is a robot path with its
own map of independent landmark Kalman filters (Montemerlo et al. 2002, 2003).

- FastSLAM 1.0 samples the pose from the odometry motion model and weights it by the
  observation likelihood ``N(z; h(x, m), H_m S H_m^T + R)``.
- FastSLAM 2.0 samples the pose from a proposal that also uses the current observations
  (an EKF step on the pose with each observed landmark), weighted by
  ``N(z; h(x_hat, m), H_x Sigma_x H_x^T + H_m S H_m^T + R)`` (Thrun et al. 2005,
  Table 13.3, observations fused one after another).
- Data association is given (the log's landmark ids) or unknown: per particle, the
  landmark of maximum likelihood among those whose Mahalanobis distance passes a chi-square
  gate, else a new landmark (weighted by the likelihood at the gate, ``p0``). A landmark
  that the sensor should have seen (inside its field of view and range, with a margin)
  and did not loses one point of evidence, one seen gains one; it is removed below zero
  (Montemerlo 2003, sec. 5.1.3, negative evidence): spurious detections leave no
  landmark behind.

- Odometry calibration (optional): each particle also carries the two systematic errors
  of differential-drive odometry (Borenstein and Feng 1996), a heading drift per metre
  and a turn scale error, drawn from a prior at the start and kept through resampling,
  so that the particles whose calibration explains the observations survive. White
  per-step noise cannot follow a bias that adds up over kilometres (Victoria Park's
  odometry under-reports its heading by about 0.0018 rad per metre).

State layout (the hot path loops over the observations of a step, never over
particles): poses ``(P, 3)``, log weights ``(P,)``, landmark means ``(P, C, 2)``,
covariances ``(P, C, 2, 2)``, ``active`` ``(P, C)`` and evidence ``(P, C)``, where C is
the number of landmark slots: the number of distinct ids with given association, the
largest map any particle holds (doubled when full) with unknown association. Memory is
O(P C), about 60 P C bytes.

References
----------
M. Montemerlo, S. Thrun, D. Koller, B. Wegbreit, "FastSLAM: A factored solution to the
simultaneous localization and mapping problem", AAAI 2002; "FastSLAM 2.0", IJCAI 2003.
M. Montemerlo, *FastSLAM*, PhD thesis, CMU-RI-TR-03-28, 2003.
S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005, ch. 13.
J. Borenstein, L. Feng, "Measurement and correction of systematic odometry errors in
mobile robots", IEEE Trans. Robotics and Automation 12(6), 1996.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.estimation.fastslam_kernel import update_known_v1, update_known_v2
from firefleet.estimation.logs import SlamLog
from firefleet.estimation.particle_filter import (
    ProgressCallback,
    compose,
    effective_sample_size,
    innovation,
    inv2,
    low_variance_resample,
    mahalanobis2,
    normalise_log_weights,
    predict_range_bearing,
    range_bearing_jacobians,
    sample_odometry,
    weighted_pose_mean,
)
from firefleet.models.kinematics import wrap_angle

__all__ = [
    "FastSlamParams",
    "FastSlamResult",
    "FastSlamState",
    "SensorView",
    "dead_reckoning_landmarks",
    "fastslam_init",
    "fastslam_step",
    "landmarks_csv",
    "run_fastslam",
    "slam_summary",
    "trajectory_csv",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

_LOG = logging.getLogger(__name__)
_LOG_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class FastSlamParams:
    """Tuning of FastSLAM.

    Attributes
    ----------
    n_particles : int
        Number of particles P (>= 1).
    version : {1, 2}
        FastSLAM 1.0 (motion-model proposal) or 2.0 (proposal with the observations).
    association : {"known", "unknown"}
        Use the log's landmark ids, or associate by maximum likelihood with a gate.
    resample_threshold : float
        Resample when the effective sample size falls below this fraction of P, (0, 1].
    gate_chi2 : float
        Squared Mahalanobis distance below which an observation may be associated with a
        landmark (unknown association). 13.8 is the chi-square 99.9 % point for 2 degrees
        of freedom.
    view_margin : float
        Share (0, 1] of the sensor's range and half field of view inside which a landmark
        not seen counts as a miss (negative evidence), away from the view's edges.
    odometry_noise_scale : float
        Factor on the log's odometry standard deviations (> 0). A log's per-step noise is
        white; real odometry errors are correlated over many steps (a wheel slipping in
        a turn), and a filter with few particles needs the wider spread to cover them.
        Victoria Park takes 2 with the calibration below (4 without it).
    heading_drift_sigma : float
        Prior standard deviation [rad/m] of a systematic heading drift per metre driven,
        estimated per particle (>= 0; 0 disables). Unequal wheel diameters turn a robot
        that odometry says drives straight (Borenstein and Feng 1996, "type B" error:
        ``dtheta_true = dtheta + k_d s``, s the signed distance of the step). Victoria
        Park: 0.003; its dead-reckoned heading drifts 412 degrees from GTSAM's over the
        4 km (0.0018 rad/m).
    turn_scale_sigma : float
        Prior standard deviation [-] of a systematic error on the scale of turns,
        estimated per particle (>= 0; 0 disables): a wrong axle length in the odometry
        (Borenstein and Feng 1996, wheelbase error: ``dtheta_true = dtheta (1 + k_b)``).
        Victoria Park: 0.05.
    new_landmark_chi2 : float
        Unknown association: an observation farther than this squared Mahalanobis
        distance from every landmark starts a new one; between ``gate_chi2`` and this it
        is ambiguous and skipped (two gates, as in Bailey's EKF-SLAM). 200 (about 14
        sigma): a landmark seen again after a loop is off by the drift gathered since it
        was last seen, which no particle's landmark covariance holds. On the simulated
        loop (4 drives x 3 seeds, 100 particles) 50 left duplicates at the loop's closure
        in 1 of 12 runs of FastSLAM 2.0 and 2 of 12 of 1.0; 200 leaves none. Two heat
        sources closer than this (about 1 m apart at 5 m with the simulated sensor) are
        mapped as one.
    confirm_evidence : int
        With unknown association, the final map keeps the landmarks whose evidence
        (times seen minus times missed in view) reached this count: a spurious detection
        at the edge of the view, never counted as missed, is seen once.
    """

    n_particles: int = 100
    version: Literal[1, 2] = 1
    association: Literal["known", "unknown"] = "known"
    resample_threshold: float = 0.5
    gate_chi2: float = 13.8
    view_margin: float = 0.9
    new_landmark_chi2: float = 200.0
    confirm_evidence: int = 3
    odometry_noise_scale: float = 1.0
    heading_drift_sigma: float = 0.0
    turn_scale_sigma: float = 0.0

    def __post_init__(self) -> None:
        if self.n_particles < 1:
            raise InputError(f"fastslam.n_particles must be >= 1, got {self.n_particles}")
        if self.version not in (1, 2):
            raise InputError(f"fastslam.version must be 1 or 2, got {self.version}")
        if self.association not in ("known", "unknown"):
            raise InputError(
                f"fastslam.association must be 'known' or 'unknown', got {self.association!r}"
            )
        check_fields(
            self,
            "fastslam",
            positive=("gate_chi2", "view_margin", "resample_threshold", "odometry_noise_scale"),
            non_negative=("heading_drift_sigma", "turn_scale_sigma"),
        )
        if self.resample_threshold > 1.0 or self.view_margin > 1.0:
            raise InputError("fastslam.resample_threshold and view_margin must be <= 1")


@dataclass(frozen=True)
class SensorView:
    """The sensor's field of view, for negative evidence (unknown association).

    Attributes
    ----------
    fov_rad : float
        Full horizontal field of view [rad], centred on the heading.
    max_range_m : float
        Detection range [m].
    """

    fov_rad: float
    max_range_m: float

    def __post_init__(self) -> None:
        check_fields(self, "sensor", positive=("fov_rad", "max_range_m"))


@dataclass
class FastSlamState:
    """The particles of FastSLAM (updated in place by :func:`fastslam_step`).

    Copying the map (``60 P C`` bytes) at every step would cost more than the update
    itself, so the step writes into these arrays; resampling replaces them.

    Attributes
    ----------
    poses : ndarray, shape (P, 3)
    log_w : ndarray, shape (P,)
        Unnormalised log weights.
    mu : ndarray, shape (P, C, 2)
        Landmark means x, y [m].
    sigma : ndarray, shape (P, C, 2, 2)
        Landmark covariances [m^2].
    active : ndarray of bool, shape (P, C)
        Whether a slot holds a landmark.
    evidence : ndarray of int64, shape (P, C)
        Seen minus missed-while-in-view count (unknown association).
    slot_ids : ndarray of int64, shape (C,)
        With given association, the landmark id of each slot (sorted); empty otherwise.
    calibration : ndarray, shape (P, 2), or None
        Each particle's odometry calibration: heading drift k_d [rad/m] and turn scale
        error k_b [-] (see :class:`FastSlamParams`); None when not estimated.
    """

    poses: FloatArray
    log_w: FloatArray
    mu: FloatArray
    sigma: FloatArray
    active: BoolArray
    evidence: IntArray
    slot_ids: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    calibration: FloatArray | None = None

    @property
    def n_particles(self) -> int:
        """P."""
        return int(self.poses.shape[0])

    @property
    def capacity(self) -> int:
        """C, the number of landmark slots."""
        return int(self.mu.shape[1])

    def weights(self) -> FloatArray:
        """Normalised weights ``(P,)``."""
        return normalise_log_weights(self.log_w)

    def best(self) -> int:
        """Index of the particle of largest weight."""
        return int(np.argmax(self.log_w))


def fastslam_init(
    n_particles: int,
    *,
    landmark_ids: IntArray | None = None,
    capacity: int = 16,
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    calibration: FloatArray | None = None,
) -> FastSlamState:
    """Particles at a known start pose with empty maps.

    Parameters
    ----------
    n_particles : int
    landmark_ids : ndarray of int, optional
        With given association, the landmark ids that may be observed (one slot each).
    capacity : int
        Initial number of slots with unknown association (grows as needed).
    pose : tuple of float
        The start pose x [m], y [m], theta [rad] (the log's frame: the origin).
    calibration : ndarray, shape (P, 2), optional
        Each particle's odometry calibration (heading drift [rad/m], turn scale error),
        e.g. drawn from the prior by :func:`run_fastslam`; None: not estimated.

    Returns
    -------
    FastSlamState
    """
    if n_particles < 1:
        raise InputError(f"n_particles must be >= 1, got {n_particles}")
    ids = np.zeros(0, dtype=np.int64) if landmark_ids is None else np.unique(landmark_ids)
    c = max(int(ids.size), 1) if landmark_ids is not None else max(capacity, 1)
    cal = None
    if calibration is not None:
        cal = as_float_array(calibration, "calibration", (n_particles, 2)).copy()
    return FastSlamState(
        poses=np.tile(np.asarray(pose, dtype=np.float64), (n_particles, 1)),
        log_w=np.zeros(n_particles),
        mu=np.zeros((n_particles, c, 2)),
        sigma=np.tile(np.eye(2), (n_particles, c, 1, 1)),
        active=np.zeros((n_particles, c), dtype=bool),
        evidence=np.zeros((n_particles, c), dtype=np.int64),
        slot_ids=ids.astype(np.int64),
        calibration=cal,
    )


def _grow(state: FastSlamState) -> None:
    """Double the number of slots (unknown association)."""
    p, c = state.n_particles, state.capacity
    state.mu = np.concatenate([state.mu, np.zeros((p, c, 2))], axis=1)
    state.sigma = np.concatenate([state.sigma, np.tile(np.eye(2), (p, c, 1, 1))], axis=1)
    state.active = np.concatenate([state.active, np.zeros((p, c), dtype=bool)], axis=1)
    state.evidence = np.concatenate([state.evidence, np.zeros((p, c), dtype=np.int64)], axis=1)


def _matmul(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(np.matmul(a, b), dtype=np.float64)


def _sandwich2(h: FloatArray, s: FloatArray) -> FloatArray:
    """``h s h^T`` for stacks of 2 x 2 matrices ``(..., 2, 2)``, element by element.

    ``np.matmul`` on a (P, C, 2, 2) stack costs ten times the arithmetic: it loops over
    the tiny matrices one by one.
    """
    h00, h01, h10, h11 = h[..., 0, 0], h[..., 0, 1], h[..., 1, 0], h[..., 1, 1]
    a00 = h00 * s[..., 0, 0] + h01 * s[..., 1, 0]
    a01 = h00 * s[..., 0, 1] + h01 * s[..., 1, 1]
    a10 = h10 * s[..., 0, 0] + h11 * s[..., 1, 0]
    a11 = h10 * s[..., 0, 1] + h11 * s[..., 1, 1]
    out = np.empty(np.broadcast_shapes(h.shape, s.shape))
    out[..., 0, 0] = a00 * h00 + a01 * h01
    out[..., 0, 1] = a00 * h10 + a01 * h11
    out[..., 1, 0] = a10 * h00 + a11 * h01
    out[..., 1, 1] = a10 * h10 + a11 * h11
    return out


def _init_landmarks(
    poses: FloatArray, z: FloatArray, r: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Mean ``(P, 2)`` and covariance ``(P, 2, 2)`` of landmarks first seen at ``z``."""
    ang = poses[:, 2] + z[1]
    m = np.stack([poses[:, 0] + z[0] * np.cos(ang), poses[:, 1] + z[0] * np.sin(ang)], axis=-1)
    _, h_m = range_bearing_jacobians(poses, m)
    h_inv, _ = inv2(h_m)
    s = _sandwich2(h_inv, r)
    return m, 0.5 * (s + np.swapaxes(s, -1, -2))


def _associate(
    state: FastSlamState,
    poses: FloatArray,
    z: FloatArray,
    r: FloatArray,
    used: BoolArray,
    fresh: BoolArray,
    gate: float,
    new_gate: float,
) -> tuple[IntArray, BoolArray, BoolArray]:
    """Maximum-likelihood association for each particle.

    Returns the landmark slot ``(P,)``, the mask of particles for which the observation
    is a new landmark and the mask of those for which it is ambiguous, skipped rather
    than risk a duplicate. An observation matches the most likely landmark within
    ``gate`` not yet matched in this frame (a landmark gives one detection per frame).
    It is new when no landmark at all, matched in this frame or not, lies within
    ``new_gate``: a second detection next to a landmark already matched is clutter or a
    double detection (a spurious heat blob beside a fire), not a landmark of its own.
    ``fresh`` marks the slots opened earlier in this frame, which hold no estimate yet.
    """
    active = state.active & ~fresh
    cand = active & ~used
    # empty slots hold a placeholder 1 m away, so that no distance is zero
    mu = np.where(active[..., None], state.mu, poses[:, None, :2] + 1.0)
    z_pred = predict_range_bearing(poses[:, None, :], mu)
    _, h_m = range_bearing_jacobians(poses[:, None, :], mu)
    q = _sandwich2(h_m, state.sigma) + r
    q_inv, det = inv2(q)
    m2 = mahalanobis2(innovation(z, z_pred), q_inv)
    d2 = np.where(cand, m2, np.inf)
    ok = d2 <= gate
    score = np.where(ok, -0.5 * d2 - 0.5 * np.log(np.where(ok, det, 1.0)), -np.inf)
    j = np.argmax(score, axis=1)
    matched = ok.any(axis=1)
    new = ~matched & (np.where(active, m2, np.inf).min(axis=1) > new_gate)
    return j.astype(np.int64), new, ~matched & ~new


def fastslam_step(
    state: FastSlamState,
    delta: FloatArray | None,
    delta_cov: FloatArray | None,
    z: FloatArray,
    z_cov: FloatArray,
    z_landmark: IntArray,
    rng: np.random.Generator,
    *,
    params: FastSlamParams,
    sensor: SensorView | None = None,
) -> tuple[float, IntArray | None]:
    """One FastSLAM step: motion, observations, negative evidence, resampling.

    Parameters
    ----------
    state : FastSlamState
        Updated in place.
    delta, delta_cov : ndarray, shapes (3,) and (3, 3), or None
        Odometry since the previous step (dx, dy [m] in its frame, dtheta [rad]) and its
        covariance; None at the first pose (no motion).
    z : ndarray, shape (K, 2)
        Observations at this pose: range [m], bearing [rad].
    z_cov : ndarray, shape (K, 2, 2)
        Their covariances.
    z_landmark : ndarray of int, shape (K,)
        Landmark ids (given association; -1 or an id without a slot is skipped).
    rng : numpy.random.Generator
    params : FastSlamParams
    sensor : SensorView, optional
        Enables negative evidence with unknown association.

    Returns
    -------
    ess : float
        Effective sample size before resampling.
    resampled : ndarray of int64, shape (P,), or None
        The resampling indices (the new particle i descends from old particle
        ``resampled[i]``), or None when the step did not resample.
    """
    p = state.n_particles
    ar = np.arange(p)
    known = params.association == "known"
    v2 = params.version == 2 and delta is not None
    if known:
        _step_known(state, delta, delta_cov, z, z_cov, z_landmark, rng, v2=v2)
        return _resample(state, params, rng)

    # motion: a sample (1.0) or the proposal's prior mean and covariance (2.0)
    prop_mean = state.poses
    prop_cov = np.zeros((p, 3, 3))
    if delta is not None and delta_cov is not None:
        deltas = _particle_deltas(state, delta)
        if v2:
            prop_mean = compose(state.poses, deltas)
            c, s = np.cos(state.poses[:, 2]), np.sin(state.poses[:, 2])
            jac = np.zeros((p, 3, 3))
            jac[:, 0, 0], jac[:, 0, 1], jac[:, 1, 0], jac[:, 1, 1] = c, -s, s, c
            jac[:, 2, 2] = 1.0
            prop_cov = _matmul(_matmul(jac, delta_cov), np.swapaxes(jac, -1, -2))
        else:
            state.poses = sample_odometry(state.poses, deltas, delta_cov, rng)
            prop_mean = state.poses

    # unknown association (NumPy over particles)
    # pass 1: association, weights, and (2.0) the proposal
    used = np.zeros(state.active.shape, dtype=bool)
    fresh = np.zeros(state.active.shape, dtype=bool)
    plan: list[tuple[int, IntArray, BoolArray]] = []
    log_p0 = 0.0
    for k in range(z.shape[0]):
        r = z_cov[k]
        j, new, skip = _associate(
            state, prop_mean, z[k], r, used, fresh, params.gate_chi2, params.new_landmark_chi2
        )
        if new.any():
            free = ~state.active
            if not free.any(axis=1).all():
                _grow(state)
                used = np.concatenate([used, np.zeros_like(used)], axis=1)
                fresh = np.concatenate([fresh, np.zeros_like(fresh)], axis=1)
                free = ~state.active
            j = np.where(new, np.argmax(free, axis=1), j)
            state.active[ar[new], j[new]] = True
            fresh[ar[new], j[new]] = True
            log_p0 = -0.5 * params.gate_chi2 - _LOG_2PI - 0.5 * float(np.log(np.linalg.det(r)))
            state.log_w[new] += log_p0
        used[ar[~skip], j[~skip]] = True
        plan.append((k, j, skip))
        old = ~new & ~skip
        if not old.any():
            continue
        idx = ar[old]
        m = state.mu[idx, j[old]]
        z_pred = predict_range_bearing(prop_mean[idx], m)
        h_x, h_m = range_bearing_jacobians(prop_mean[idx], m)
        q = _sandwich2(h_m, state.sigma[idx, j[old]]) + r
        nu = innovation(z[k], z_pred)
        if v2:
            cov_x = prop_cov[idx]
            lik_cov = _matmul(_matmul(h_x, cov_x), np.swapaxes(h_x, -1, -2)) + q
            lik_inv, lik_det = inv2(lik_cov)
            state.log_w[idx] += -0.5 * mahalanobis2(nu, lik_inv) - 0.5 * np.log(lik_det) - _LOG_2PI
            q_inv, _ = inv2(q)
            ht_qinv = _matmul(np.swapaxes(h_x, -1, -2), q_inv)
            info = _matmul(ht_qinv, h_x) + np.linalg.inv(cov_x)
            new_cov = np.linalg.inv(info)
            new_cov = 0.5 * (new_cov + np.swapaxes(new_cov, -1, -2))
            step = _matmul(new_cov, _matmul(ht_qinv, nu[..., None]))[..., 0]
            mean = prop_mean.copy()
            mean[idx] = prop_mean[idx] + step
            mean[idx, 2] = wrap_angle(mean[idx, 2])
            prop_mean = mean
            prop_cov[idx] = new_cov
        else:
            q_inv, det = inv2(q)
            state.log_w[idx] += -0.5 * mahalanobis2(nu, q_inv) - 0.5 * np.log(det) - _LOG_2PI

    if v2:  # sample the pose from the proposal
        chol = np.asarray(np.linalg.cholesky(prop_cov + 1e-12 * np.eye(3)), dtype=np.float64)
        eps = rng.standard_normal((p, 3, 1))
        poses: FloatArray = prop_mean + _matmul(chol, eps)[..., 0]
        poses[:, 2] = wrap_angle(poses[:, 2])
        state.poses = poses

    # pass 2: landmark Kalman updates (or initialisation) from the sampled pose
    seen = np.zeros(state.active.shape, dtype=bool)
    for k, j, skip in plan:
        r = z_cov[k]
        new = fresh[ar, j]
        # a new landmark's slot holds no estimate yet: a placeholder 1 m away stands in
        lm_mu = np.where(new[:, None], state.poses[:, :2] + 1.0, state.mu[ar, j])
        lm_sigma = state.sigma[ar, j]
        init_mu, init_sigma = _init_landmarks(state.poses, z[k], r)
        z_pred = predict_range_bearing(state.poses, lm_mu)
        _, h_m = range_bearing_jacobians(state.poses, lm_mu)
        q = _sandwich2(h_m, lm_sigma) + r
        q_inv, _ = inv2(q)
        gain = _matmul(_matmul(lm_sigma, np.swapaxes(h_m, -1, -2)), q_inv)
        upd_mu = lm_mu + _matmul(gain, innovation(z[k], z_pred)[..., None])[..., 0]
        upd_sigma = lm_sigma - _matmul(_matmul(gain, q), np.swapaxes(gain, -1, -2))
        upd_sigma = 0.5 * (upd_sigma + np.swapaxes(upd_sigma, -1, -2))
        keep = ar[~skip]
        js = j[~skip]
        state.mu[keep, js] = np.where(new[:, None], init_mu, upd_mu)[~skip]
        state.sigma[keep, js] = np.where(new[:, None, None], init_sigma, upd_sigma)[~skip]
        state.active[keep, js] = True
        fresh[keep, js] = False
        seen[keep, js] = True

    state.evidence += seen
    if sensor is not None:
        _negative_evidence(state, seen, sensor, params.view_margin)

    return _resample(state, params, rng)


def _particle_deltas(state: FastSlamState, delta: FloatArray) -> FloatArray:
    """The measured motion ``(3,)`` as each particle's calibration corrects it, ``(P, 3)``.

    ``dtheta_i = dtheta (1 + k_b,i) + k_d,i s`` with s the step's signed distance
    (negative when driving backwards, where the drift of unequal wheels reverses).
    """
    d = np.empty((state.n_particles, 3))
    d[:] = delta
    cal = state.calibration
    if cal is not None:
        s = math.copysign(math.hypot(delta[0], delta[1]), delta[0])
        d[:, 2] = delta[2] * (1.0 + cal[:, 1]) + cal[:, 0] * s
    return d


def _step_known(
    state: FastSlamState,
    delta: FloatArray | None,
    delta_cov: FloatArray | None,
    z: FloatArray,
    z_cov: FloatArray,
    z_landmark: IntArray,
    rng: np.random.Generator,
    *,
    v2: bool,
) -> None:
    """Motion and observations with given association, by the compiled kernels."""
    slots = np.searchsorted(state.slot_ids, z_landmark).astype(np.int64)
    deltas = None if delta is None else _particle_deltas(state, delta)
    ok = slots < state.slot_ids.size
    ok[ok] = state.slot_ids[slots[ok]] == z_landmark[ok]
    slots[~ok] = -1
    zz = np.ascontiguousarray(z, dtype=np.float64)
    zc = np.ascontiguousarray(z_cov, dtype=np.float64)
    if v2 and deltas is not None and delta_cov is not None:
        eps = rng.standard_normal((state.n_particles, 3))
        update_known_v2(
            state.poses, state.log_w, state.mu, state.sigma, state.active, state.evidence,
            slots, zz, zc, deltas,
            np.ascontiguousarray(delta_cov, dtype=np.float64), eps,
        )  # fmt: skip
        return
    if deltas is not None and delta_cov is not None:
        state.poses = sample_odometry(state.poses, deltas, delta_cov, rng)
    update_known_v1(
        state.poses, state.log_w, state.mu, state.sigma, state.active, state.evidence, slots,
        zz, zc,
    )  # fmt: skip


def _resample(
    state: FastSlamState, params: FastSlamParams, rng: np.random.Generator
) -> tuple[float, IntArray | None]:
    """Low-variance resampling when the effective sample size is below the threshold."""
    p = state.n_particles
    w = state.weights()
    ess = effective_sample_size(w)
    if ess >= params.resample_threshold * p:
        return ess, None
    idx = low_variance_resample(w, rng)
    state.poses = state.poses[idx]
    state.mu = state.mu[idx]
    state.sigma = state.sigma[idx]
    state.active = state.active[idx]
    state.evidence = state.evidence[idx]
    if state.calibration is not None:
        state.calibration = state.calibration[idx]
    state.log_w = np.zeros(p)
    return ess, idx


def _negative_evidence(
    state: FastSlamState, seen: BoolArray, sensor: SensorView, margin: float
) -> None:
    """Count seen / missed landmarks inside the view; remove those below zero evidence."""
    z_pred = predict_range_bearing(state.poses[:, None, :], state.mu)
    in_view = (
        state.active
        & (z_pred[..., 0] < margin * sensor.max_range_m)
        & (np.abs(z_pred[..., 1]) < margin * 0.5 * sensor.fov_rad)
    )
    state.evidence -= (in_view & ~seen).astype(np.int64)
    gone = state.active & (state.evidence < 0)
    if gone.any():
        state.active &= ~gone
        state.evidence[gone] = 0


@dataclass(frozen=True)
class FastSlamResult:
    """What :func:`run_fastslam` estimated from a log.

    Attributes
    ----------
    params : FastSlamParams
    trajectory : ndarray, shape (T, 3)
        The path of the final highest-weight particle (a sample of the path posterior,
        smoothed by resampling: the estimate FastSLAM makes of the whole path).
    filtered : ndarray, shape (T, 3)
        The weighted mean pose at each step (the online estimate).
    dead_reckoning : ndarray, shape (T, 3)
        The odometry alone, composed from the origin.
    landmark_ids : ndarray of int64, shape (K,)
        Ids of the final map's landmarks (the log's ids with given association, slot
        numbers otherwise).
    landmarks : ndarray, shape (K, 2)
        Their positions [m] in the best particle's map.
    landmark_cov : ndarray, shape (K, 2, 2)
    ess : ndarray, shape (T,)
        Effective sample size at each step (before resampling).
    n_resamples : int
    run_time_s : float
        Wall time of the filter loop.
    snapshot_steps : ndarray of int64, shape (S,)
        Steps at which the map was recorded (for the animation).
    snapshot_landmarks : tuple of ndarray, each (K_s, 2)
        The best particle's map at those steps.
    calibration : ndarray, shape (2,), or None
        The best particle's odometry calibration at the end: heading drift [rad/m] and
        turn scale error [-]; None when not estimated.
    """

    params: FastSlamParams
    trajectory: FloatArray
    filtered: FloatArray
    dead_reckoning: FloatArray
    landmark_ids: IntArray
    landmarks: FloatArray
    landmark_cov: FloatArray
    ess: FloatArray
    n_resamples: int
    run_time_s: float
    snapshot_steps: IntArray
    snapshot_landmarks: tuple[FloatArray, ...]
    calibration: FloatArray | None = None


def run_fastslam(
    log: SlamLog,
    rng: np.random.Generator,
    *,
    params: FastSlamParams | None = None,
    keep_path: bool = True,
    n_snapshots: int = 0,
    progress: ProgressCallback | None = None,
) -> FastSlamResult:
    """Run FastSLAM over a whole log, starting at the origin (the log's first pose).

    With ``heading_drift_sigma`` or ``turn_scale_sigma`` set, each particle's odometry
    calibration is first drawn from ``rng`` (the prior), then kept through resampling.

    Parameters
    ----------
    log : SlamLog
    rng : numpy.random.Generator
    params : FastSlamParams, optional
    keep_path : bool
        Keep every particle's pose at every step (``24 T P`` bytes) to return the best
        particle's path; when False ``trajectory`` is the filtered estimate.
    n_snapshots : int
        Number of evenly spaced steps at which to record the best particle's map.
    progress : callable(done, total), optional

    Returns
    -------
    FastSlamResult
    """
    prm = params or FastSlamParams()
    known = prm.association == "known"
    sigma_cal = np.array([prm.heading_drift_sigma, prm.turn_scale_sigma])
    calibration = rng.standard_normal((prm.n_particles, 2)) * sigma_cal if sigma_cal.any() else None
    state = fastslam_init(
        prm.n_particles,
        landmark_ids=log.landmark_ids if known else None,
        calibration=calibration,
    )
    sensor = None
    if log.sensor_fov_rad is not None and log.sensor_max_range_m is not None:
        sensor = SensorView(log.sensor_fov_rad, log.sensor_max_range_m)
    n = log.n_poses
    odo_cov = log.odometry_cov * prm.odometry_noise_scale**2
    starts = np.searchsorted(log.obs_step, np.arange(n + 1))
    snap_at = (
        np.unique(np.linspace(0, n - 1, n_snapshots).round().astype(np.int64))
        if n_snapshots > 0
        else np.zeros(0, dtype=np.int64)
    )
    snaps: list[FloatArray] = []
    history = np.empty((n, prm.n_particles, 3)) if keep_path else None
    parents = np.empty((n, prm.n_particles), dtype=np.int64) if keep_path else None
    filtered = np.empty((n, 3))
    ess = np.empty(n)
    n_resamples = 0
    t0 = time.perf_counter()
    for k in range(n):
        a, b = starts[k], starts[k + 1]
        ess[k], idx = fastslam_step(
            state,
            log.odometry[k - 1] if k > 0 else None,
            odo_cov[k - 1] if k > 0 else None,
            log.obs_z[a:b],
            log.obs_cov[a:b],
            log.obs_landmark[a:b],
            rng,
            params=prm,
            sensor=sensor,
        )
        n_resamples += idx is not None
        if history is not None and parents is not None:
            # particle i after this step descends from particle parents[k, i] of step k - 1
            history[k] = state.poses
            parents[k] = np.arange(prm.n_particles) if idx is None else idx
        filtered[k] = weighted_pose_mean(state.poses, state.weights())[0]
        if snap_at.size and k in snap_at:
            best = state.best()
            keep = state.active[best]
            if not known:
                keep = keep & (state.evidence[best] >= prm.confirm_evidence)
            snaps.append(state.mu[best, keep].copy())
        if progress is not None:
            progress(k + 1, n)
    run_time = time.perf_counter() - t0
    best = state.best()
    if history is not None and parents is not None:
        path = np.empty((n, 3))
        i = best
        for k in range(n - 1, -1, -1):
            path[k] = history[k, i]
            i = int(parents[k, i])
    else:
        path = filtered.copy()
    act = state.active[best]
    if not known:
        act = act & (state.evidence[best] >= prm.confirm_evidence)
    ids = state.slot_ids[act] if known else np.flatnonzero(act).astype(np.int64)
    _LOG.info("FastSLAM %d: %d steps in %.2f s", prm.version, n, run_time)
    return FastSlamResult(
        params=prm,
        trajectory=path,
        filtered=filtered,
        dead_reckoning=log.dead_reckoning(),
        landmark_ids=np.asarray(ids, dtype=np.int64),
        landmarks=state.mu[best, act].copy(),
        landmark_cov=state.sigma[best, act].copy(),
        ess=ess,
        n_resamples=n_resamples,
        run_time_s=run_time,
        snapshot_steps=snap_at,
        snapshot_landmarks=tuple(snaps),
        calibration=None if state.calibration is None else state.calibration[best].copy(),
    )


MATCH_RADIUS_M = 1.0
"""An estimated landmark farther than this from every true one is spurious; two within
it of the same true landmark are duplicates (half the simulated world's 2 m spacing)."""


def _rms(d: FloatArray) -> float:
    return float(np.sqrt(np.mean(d * d))) if d.size else float("nan")


def dead_reckoning_landmarks(log: SlamLog) -> tuple[IntArray, FloatArray]:
    """Landmarks mapped from odometry alone: each one's observations, averaged.

    Returns
    -------
    ids : ndarray of int64, shape (L,)
    xy : ndarray, shape (L, 2)
        Mean position of the landmark's observations projected from the dead-reckoned
        poses [m].
    """
    dr = log.dead_reckoning()
    ok = log.obs_landmark >= 0
    poses = dr[log.obs_step[ok]]
    z = log.obs_z[ok]
    ang = poses[:, 2] + z[:, 1]
    pts = poses[:, :2] + z[:, :1] * np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    ids, inv = np.unique(log.obs_landmark[ok], return_inverse=True)
    xy = np.zeros((ids.size, 2))
    np.add.at(xy, inv, pts)
    xy /= np.bincount(inv, minlength=ids.size)[:, None]
    return ids.astype(np.int64), xy


def slam_summary(log: SlamLog, result: FastSlamResult) -> dict[str, Any]:
    """The JSON summary of a run: sizes, time, and errors against the truth when known.

    With ground truth (a simulated log), the errors are in the log's frame (the start is
    known exactly, no alignment): ``position_rms_m`` of the trajectory,
    ``landmark_rms_m`` of the map (each estimate against the true landmark of its id with
    given association, against the nearest one otherwise), the same two for odometry
    alone, the duplicates and spurious landmarks left, and the issue's claims: each error
    at most 0.5 m and at most half of odometry's, no duplicate landmark.
    """
    p = result.params
    doc: dict[str, Any] = {
        "log": log.name,
        "version": p.version,
        "association": p.association,
        "particles": p.n_particles,
        "poses": log.n_poses,
        "observations": log.n_observations,
        "landmarks": int(result.landmarks.shape[0]),
        "resamplings": result.n_resamples,
        "run_time_s": result.run_time_s,
        "claims": [],
    }
    if result.calibration is not None:
        doc["odometry_calibration"] = {
            "heading_drift_rad_per_m": float(result.calibration[0]),
            "turn_scale_error": float(result.calibration[1]),
        }
    if log.truth_pose is None or log.truth_landmarks is None or log.truth_landmark_ids is None:
        return doc
    truth = log.truth_pose
    pos = _rms(np.linalg.norm(result.trajectory[:, :2] - truth[:, :2], axis=1))
    filt = _rms(np.linalg.norm(result.filtered[:, :2] - truth[:, :2], axis=1))
    odo = _rms(np.linalg.norm(result.dead_reckoning[:, :2] - truth[:, :2], axis=1))
    true_xy = log.truth_landmarks
    dists = np.linalg.norm(result.landmarks[:, None, :] - true_xy[None], axis=2)
    if p.association == "known":
        slot = np.searchsorted(log.truth_landmark_ids, result.landmark_ids)
        nearest = np.clip(slot, 0, true_xy.shape[0] - 1)
    else:
        nearest = np.argmin(dists, axis=1) if dists.size else np.zeros(0, dtype=np.int64)
    err = dists[np.arange(nearest.size), nearest] if dists.size else np.zeros(0)
    close = err <= MATCH_RADIUS_M
    counts = np.bincount(nearest[close], minlength=true_xy.shape[0])
    dr_ids, dr_xy = dead_reckoning_landmarks(log)
    dr_slot = np.searchsorted(log.truth_landmark_ids, dr_ids)
    odo_lm = _rms(np.linalg.norm(dr_xy - true_xy[dr_slot], axis=1))
    doc.update(
        {
            "position_rms_m": pos,
            "filtered_position_rms_m": filt,
            "odometry_position_rms_m": odo,
            "landmark_rms_m": _rms(err),
            "odometry_landmark_rms_m": odo_lm,
            "true_landmarks_seen": int(dr_ids.size),
            "duplicate_landmarks": int(np.sum(np.maximum(counts - 1, 0))),
            "spurious_landmarks": int(np.sum(~close)),
        }
    )
    claims = [
        ("position_rms_m", f"<= min(0.5, odometry/2 = {odo / 2:.3g})", pos, min(0.5, odo / 2)),
        (
            "landmark_rms_m",
            f"<= min(0.5, odometry/2 = {odo_lm / 2:.3g})",
            doc["landmark_rms_m"],
            min(0.5, odo_lm / 2),
        ),
    ]
    for name, expected, measured, bound in claims:
        doc["claims"].append(
            {"name": name, "expected": expected, "measured": measured, "passed": measured <= bound}
        )
    if p.association == "unknown":
        dup = doc["duplicate_landmarks"]
        doc["claims"].append(
            {"name": "duplicate_landmarks", "expected": "== 0", "measured": dup, "passed": dup == 0}
        )
    return doc


def trajectory_csv(log: SlamLog, result: FastSlamResult) -> str:
    """``pose_id,x,y,theta`` for every pose of the log (the log's frame, start at 0)."""
    lines = ["pose_id,x,y,theta"]
    for pid, (x, y, th) in zip(log.pose_ids, result.trajectory, strict=True):
        lines.append(f"{pid},{x:.6f},{y:.6f},{th:.6f}")
    return "\n".join(lines) + "\n"


def landmarks_csv(result: FastSlamResult) -> str:
    """``id,x,y`` for every landmark of the final map."""
    lines = ["id,x,y"]
    for lid, (x, y) in zip(result.landmark_ids, result.landmarks, strict=True):
        lines.append(f"{lid},{x:.6f},{y:.6f}")
    return "\n".join(lines) + "\n"
