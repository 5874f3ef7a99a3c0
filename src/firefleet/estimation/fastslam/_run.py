"""FastSLAM over a whole log: the filter loop, the best particle's path and map."""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from firefleet._typing import FloatArray, IntArray
from firefleet.errors import InputError
from firefleet.estimation.fastslam._params import FastSlamParams, SensorView
from firefleet.estimation.fastslam._state import fastslam_init
from firefleet.estimation.fastslam._step import fastslam_step
from firefleet.estimation.logs import SlamLog
from firefleet.estimation.particle_filter import ProgressCallback, weighted_pose_mean

__all__ = ["FastSlamResult", "fastslam_memory_bytes", "run_fastslam"]


_LOG = logging.getLogger("firefleet.estimation.fastslam")


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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import FastSlamParams, run_fastslam
    >>> from firefleet.estimation.logs import parse_log
    >>> odometry = "ODOMETRY {} {} 1 0 0 1e-4 0 0 1e-4 0 1e-6"
    >>> lines = [odometry.format(0, 1), odometry.format(1, 2), "LANDMARK 1 7 3 1 0.01 0 0.01"]
    >>> log = parse_log(lines)
    >>> result = run_fastslam(log, np.random.default_rng(0), params=FastSlamParams(n_particles=20))
    >>> result.trajectory.shape, result.landmark_ids.tolist(), result.dead_reckoning[-1].tolist()
    ((3, 3), [7], [2.0, 0.0, 0.0])
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


def fastslam_memory_bytes(log: SlamLog, params: FastSlamParams, *, keep_path: bool = True) -> int:
    """Bytes :func:`run_fastslam` needs on ``log``, estimated before allocating any.

    The particles' maps (``57 P C`` bytes, C landmark slots: the log's landmark ids with
    given association, at least 16 with unknown), twice (resampling copies them), the
    per-observation (P, C, 2, 2) work arrays of unknown association (``320 P C``), and
    with ``keep_path`` every particle's pose and parent at every step (``32 T P``).

    Parameters
    ----------
    log : SlamLog
    params : FastSlamParams
    keep_path : bool
        As :func:`run_fastslam`'s.

    Returns
    -------
    int
        Bytes (a lower bound with unknown association, whose map may grow).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.logs import parse_log
    >>> log = parse_log(["ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6",
    ...                  "LANDMARK 1 7 3 1 0.01 0 0.01"])
    >>> fastslam_memory_bytes(log, FastSlamParams(n_particles=1000))
    378000
    """
    p = params.n_particles
    known = params.association == "known"
    c = max(int(log.landmark_ids.size), 1) if known else max(int(log.landmark_ids.size), 16)
    per_particle = c * (2 * 57 + (0 if known else 320)) + 200
    if keep_path:
        per_particle += 32 * log.n_poses
    return int(p * per_particle)


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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import FastSlamParams, run_fastslam
    >>> from firefleet.estimation.logs import parse_log
    >>> odometry = "ODOMETRY {} {} 1 0 0 1e-4 0 0 1e-4 0 1e-6"
    >>> lines = [odometry.format(0, 1), odometry.format(1, 2)]
    >>> lines += ["LANDMARK 1 7 3 1 0.01 0 0.01", "LANDMARK 2 7 2 1 0.01 0 0.01"]  # at (4, 1)
    >>> params = FastSlamParams(n_particles=20)
    >>> result = run_fastslam(parse_log(lines), np.random.default_rng(0), params=params)
    >>> result.landmarks.round(1).tolist()
    [[4.0, 1.0]]
    """
    prm = params or FastSlamParams()
    known = prm.association == "known"
    if log.n_observations == 0:
        raise InputError(
            f"{log.name}: no LANDMARK or BR lines: FastSLAM needs landmark observations"
        )
    if known and log.landmark_ids.size == 0:
        raise InputError(
            f"{log.name}: no observation names its landmark (every id is -1): "
            "given association needs landmark ids; use unknown association"
        )
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
