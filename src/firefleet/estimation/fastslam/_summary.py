"""What a FastSLAM run measured: sizes, time, errors against the truth, claims; CSV text."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from firefleet._typing import FloatArray, IntArray
from firefleet.estimation.fastslam._run import FastSlamResult
from firefleet.estimation.logs import SlamLog

if TYPE_CHECKING:
    from firefleet.scenarios.schema import Claim

__all__ = [
    "BOUND_M",
    "MATCH_RADIUS_M",
    "dead_reckoning_landmarks",
    "landmarks_csv",
    "slam_claims",
    "slam_summary",
    "trajectory_csv",
]


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


def slam_summary(log: SlamLog, result: FastSlamResult) -> dict[str, float]:
    """The numbers of a run: sizes, time, and errors against the truth when known.

    With ground truth (a simulated log), the errors are in the log's frame (the start is
    known exactly, no alignment): ``position_rms_m`` of the trajectory,
    ``landmark_rms_m`` of the map (each estimate against the true landmark of its id with
    given association, against the nearest one otherwise), the same two for odometry
    alone, and the duplicates and spurious landmarks left. :func:`slam_claims` states
    the bounds they are held to.

    Parameters
    ----------
    log : SlamLog
    result : FastSlamResult
        The run of :func:`run_fastslam` on ``log``.

    Returns
    -------
    dict of str to float
        Named numbers (units in the names; counts as whole numbers): ``version``,
        ``particles``, ``poses``, ``observations``, ``landmarks``, ``resamplings``,
        ``run_time_s``; with odometry calibration ``heading_drift_rad_per_m`` and
        ``turn_scale_error`` (the best particle's); with ground truth the errors above,
        ``true_landmarks_seen``, ``duplicate_landmarks`` and ``spurious_landmarks``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import FastSlamParams, run_fastslam, slam_summary
    >>> from firefleet.estimation.logs import parse_log
    >>> log = parse_log(["ODOMETRY 0 1 1 0 0 1e-4 0 0 1e-4 0 1e-6", "LANDMARK 1 7 3 1 0.01 0 0.01"])
    >>> result = run_fastslam(log, np.random.default_rng(0), params=FastSlamParams(n_particles=10))
    >>> summary = slam_summary(log, result)
    >>> summary["poses"], summary["observations"], summary["landmarks"], summary["particles"]
    (2, 1, 1, 10)
    """
    p = result.params
    doc: dict[str, float] = {
        "version": p.version,
        "particles": p.n_particles,
        "poses": log.n_poses,
        "observations": log.n_observations,
        "landmarks": int(result.landmarks.shape[0]),
        "resamplings": result.n_resamples,
        "run_time_s": result.run_time_s,
    }
    if result.calibration is not None:
        doc["heading_drift_rad_per_m"] = float(result.calibration[0])
        doc["turn_scale_error"] = float(result.calibration[1])
    if log.truth_pose is None or log.truth_landmarks is None or log.truth_landmark_ids is None:
        return doc
    truth = log.truth_pose
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
    doc.update(
        {
            "position_rms_m": _rms(np.linalg.norm(result.trajectory[:, :2] - truth[:, :2], axis=1)),
            "filtered_position_rms_m": _rms(
                np.linalg.norm(result.filtered[:, :2] - truth[:, :2], axis=1)
            ),
            "odometry_position_rms_m": _rms(
                np.linalg.norm(result.dead_reckoning[:, :2] - truth[:, :2], axis=1)
            ),
            "landmark_rms_m": _rms(err),
            "odometry_landmark_rms_m": _rms(np.linalg.norm(dr_xy - true_xy[dr_slot], axis=1)),
            "true_landmarks_seen": int(dr_ids.size),
            "duplicate_landmarks": int(np.sum(np.maximum(counts - 1, 0))),
            "spurious_landmarks": int(np.sum(~close)),
        }
    )
    return doc


BOUND_M = 0.5
"""Our bound on the position and landmark RMS errors of FastSLAM on the simulated 100 m
loop: 0.5 m, half a robot length over a loop whose odometry drifts 3-5 m."""


def slam_claims(summary: Mapping[str, float], *, association: str) -> tuple[Claim, ...]:
    """The bounds a run with ground truth is held to, as scenario claims.

    Each error (``position_rms_m``, ``landmark_rms_m``) at most :data:`BOUND_M` and at
    most half of odometry alone's; with unknown association, no duplicate landmark. A
    log without ground truth (Victoria Park) has no claims here: its reference is GTSAM's
    optimum, measured by ``bench/slam.py``.

    Parameters
    ----------
    summary : mapping
        :func:`slam_summary` of the run.
    association : {"known", "unknown"}
        The run's data association (``FastSlamParams.association``).

    Returns
    -------
    tuple of firefleet.scenarios.schema.Claim
        Checked against ``summary`` like every scenario's claims (``Claim.holds``).

    Examples
    --------
    >>> from firefleet.estimation import slam_claims
    >>> summary = {"position_rms_m": 0.2, "landmark_rms_m": 0.3,
    ...            "odometry_position_rms_m": 1.0, "odometry_landmark_rms_m": 1.0}
    >>> claims = slam_claims(summary, association="known")
    >>> [claim.metric for claim in claims]
    ['position_rms_m', 'landmark_rms_m']
    >>> [claim.value for claim in claims], [claim.holds(summary[claim.metric]) for claim in claims]
    ([0.5, 0.5], [True, True])
    >>> slam_claims({"poses": 3}, association="known")  # no ground truth, no claims
    ()
    """
    from firefleet.scenarios.schema import Claim

    if "position_rms_m" not in summary:
        return ()
    claims = []
    for metric, odometry in (
        ("position_rms_m", "odometry_position_rms_m"),
        ("landmark_rms_m", "odometry_landmark_rms_m"),
    ):
        half = float(summary[odometry]) / 2.0
        claims.append(
            Claim(
                metric=metric,
                op="<=",
                value=min(BOUND_M, half),
                source=f"our bound: {BOUND_M} m and half of odometry alone ({half:.3g} m)",
            )
        )
    if association == "unknown":
        claims.append(
            Claim(
                metric="duplicate_landmarks",
                op="<=",
                value=0.0,
                source="our bound: every landmark mapped once",
            )
        )
    return tuple(claims)


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
