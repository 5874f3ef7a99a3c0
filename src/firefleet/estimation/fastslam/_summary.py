"""What a FastSLAM run measured: sizes, time, errors against the truth, claims; CSV text."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet.estimation.fastslam._run import FastSlamResult
from firefleet.estimation.logs import SlamLog

__all__ = [
    "MATCH_RADIUS_M",
    "dead_reckoning_landmarks",
    "landmarks_csv",
    "slam_summary",
    "trajectory_csv",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


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
