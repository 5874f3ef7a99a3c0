"""FastSLAM with unknown association: maximum likelihood with gates, NumPy over particles.

Per particle, an observation goes to the landmark of maximum likelihood among those
whose Mahalanobis distance passes ``gate_chi2``; it starts a new landmark when no
landmark lies within ``new_landmark_chi2`` (weighted by the likelihood at the gate,
``p0``), and is skipped in between. Negative evidence removes landmarks the sensor
should have seen and did not (Montemerlo 2003, sec. 5.1.3).
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.estimation.fastslam._kernel import update_landmarks
from firefleet.estimation.fastslam._params import FastSlamParams, SensorView
from firefleet.estimation.fastslam._state import FastSlamState, grow, particle_deltas
from firefleet.estimation.particle_filter import (
    compose,
    innovation,
    inv2,
    mahalanobis2,
    predict_range_bearing,
    range_bearing_jacobians,
    sample_odometry,
)
from firefleet.models.kinematics import wrap_angle

__all__ = ["step_unknown"]


_LOG_2PI = float(np.log(2.0 * np.pi))


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


def step_unknown(
    state: FastSlamState,
    delta: FloatArray | None,
    delta_cov: FloatArray | None,
    z: FloatArray,
    z_cov: FloatArray,
    rng: np.random.Generator,
    *,
    params: FastSlamParams,
    sensor: SensorView | None,
) -> None:
    """Motion, association, observations and negative evidence of one step, in place.

    The arguments are those of :func:`firefleet.estimation.fastslam.fastslam_step`
    (without the landmark ids); resampling is the caller's.
    """
    p = state.n_particles
    ar = np.arange(p)
    v2 = params.version == 2 and delta is not None
    # motion: a sample (1.0) or the proposal's prior mean and covariance (2.0)
    prop_mean = state.poses
    prop_cov = np.zeros((p, 3, 3))
    if delta is not None and delta_cov is not None:
        deltas = particle_deltas(state, delta)
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
                grow(state)
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

    # pass 2: landmark Kalman updates (or initialisation) from the sampled pose, compiled
    seen = np.zeros(state.active.shape, dtype=bool)
    for k, j, skip in plan:
        new = fresh[ar, j]
        update_landmarks(
            state.poses, state.mu, state.sigma, np.where(skip, -1, j), new, z[k], z_cov[k]
        )
        keep = ar[~skip]
        js = j[~skip]
        state.active[keep, js] = True
        fresh[keep, js] = False
        seen[keep, js] = True

    state.evidence += seen
    if sensor is not None:
        _negative_evidence(state, seen, sensor, params.view_margin)


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
