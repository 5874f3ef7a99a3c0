"""One FastSLAM step: motion, observations (given or unknown association), resampling."""

from __future__ import annotations

import numpy as np

from firefleet._typing import FloatArray, IntArray
from firefleet.estimation.fastslam._association import step_unknown
from firefleet.estimation.fastslam._kernel import update_known_v1, update_known_v2
from firefleet.estimation.fastslam._params import FastSlamParams, SensorView
from firefleet.estimation.fastslam._state import FastSlamState, particle_deltas
from firefleet.estimation.particle_filter import (
    effective_sample_size,
    low_variance_resample,
    sample_odometry,
)

__all__ = ["fastslam_step"]


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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import FastSlamParams, fastslam_init, fastslam_step
    >>> state = fastslam_init(20, landmark_ids=np.array([7]))
    >>> z, z_cov = np.array([[5.0, 0.0]]), np.eye(2)[None] * 0.01  # landmark 7, 5 m ahead
    >>> rng, params = np.random.default_rng(0), FastSlamParams(n_particles=20)
    >>> _ = fastslam_step(state, None, None, z, z_cov, np.array([7]), rng, params=params)
    >>> state.mu[:, 0].round(6).tolist()[0], bool(state.active[:, 0].all())
    ([5.0, 0.0], True)
    """
    known = params.association == "known"
    if known:
        _step_known(
            state,
            delta,
            delta_cov,
            z,
            z_cov,
            z_landmark,
            rng,
            v2=params.version == 2 and delta is not None,
        )
    else:
        step_unknown(state, delta, delta_cov, z, z_cov, rng, params=params, sensor=sensor)
    return _resample(state, params, rng)


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
    deltas = None if delta is None else particle_deltas(state, delta)
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
