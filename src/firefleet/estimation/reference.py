"""A reference for SLAM results on real data: GTSAM's batch optimum of a log.

Real logs (Victoria Park) have no ground truth; the usual reference a filter's
trajectory is compared with is the maximum a posteriori estimate of all the log's
factors. GTSAM computes it here: iSAM2 over the poses in order (a good initial
estimate: plain Levenberg-Marquardt from dead reckoning stalls on Victoria Park), then
Levenberg-Marquardt over all factors. GTSAM is an optional dependency (the tests and
the report install it); without it :func:`gtsam_optimum` raises ``InputError``.

References
----------
F. Dellaert and M. Kaess, "Factor graphs for robot perception", Foundations and Trends
in Robotics 6(1-2), 2017. M. Kaess et al., "iSAM2: incremental smoothing and mapping
using the Bayes tree", IJRR 31(2), 2012.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.estimation.logs import SlamLog

__all__ = ["gtsam_optimum"]


def gtsam_optimum(log: SlamLog, path: str | Path) -> tuple[NDArray[np.float64], float]:
    """GTSAM's batch optimum of a log in GTSAM's text format.

    Parameters
    ----------
    log : SlamLog
        The log as firefleet read it (pose order, first sightings of landmarks).
    path : str or Path
        The same log's file, which ``gtsam.load2D`` reads for the factors.

    Returns
    -------
    positions : ndarray, shape (T, 2)
        The optimum's pose positions [m], in the log's pose order.
    error : float
        The factor graph's final error (half the sum of squared whitened residuals).

    Raises
    ------
    InputError
        If GTSAM is not installed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from firefleet.estimation.logs import gtsam_text, parse_log
    >>> from firefleet.estimation.reference import gtsam_optimum
    >>> odometry = "ODOMETRY {} {} 1 0 0 1e-4 0 0 1e-4 0 1e-6"
    >>> log = parse_log([odometry.format(0, 1), odometry.format(1, 2)])
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "chain.txt"
    >>> _ = path.write_text(gtsam_text(log))
    >>> positions, error = gtsam_optimum(log, path)  # odometry only: the chain itself
    >>> (positions.round(6) + 0.0).tolist(), round(error, 6)
    ([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], 0.0)
    >>> folder.cleanup()
    """
    try:
        import gtsam
    except ImportError as exc:
        raise InputError("the GTSAM reference needs the gtsam package (pip install gtsam)") from exc
    graph, _ = gtsam.load2D(str(path))
    order = {int(p): k for k, p in enumerate(log.pose_ids)}
    buckets: list[list[Any]] = [[] for _ in range(log.n_poses)]
    for i in range(graph.size()):
        f = graph.at(i)
        keys = [k for k in f.keys() if k in order]  # noqa: SIM118 (a gtsam KeyVector)
        buckets[max(order[k] for k in keys)].append(f)
    prior = gtsam.PriorFactorPose2(
        int(log.pose_ids[0]), gtsam.Pose2(), gtsam.noiseModel.Diagonal.Sigmas([1e-3, 1e-3, 1e-4])
    )
    isam = gtsam.ISAM2(gtsam.ISAM2Params())
    est = gtsam.Values()
    seen: set[int] = set()
    for k, pid in enumerate(log.pose_ids):
        fg = gtsam.NonlinearFactorGraph()
        vals = gtsam.Values()
        if k == 0:
            fg.add(prior)
            pose = gtsam.Pose2()
        else:
            pose = est.atPose2(int(log.pose_ids[k - 1])).compose(gtsam.Pose2(*log.odometry[k - 1]))
        vals.insert(int(pid), pose)
        for f in buckets[k]:
            fg.add(f)
            for key in f.keys():  # noqa: SIM118 (a gtsam KeyVector, not a dict)
                if key in order or key in seen:
                    continue
                seen.add(key)
                lid = gtsam.Symbol(key).index()
                n = np.flatnonzero((log.obs_step == k) & (log.obs_landmark == lid))[0]
                r, b = log.obs_z[n]
                vals.insert(key, pose.transformFrom(np.array([r * math.cos(b), r * math.sin(b)])))
        isam.update(fg, vals)
        est = isam.calculateEstimate()
    graph.add(prior)
    best = gtsam.LevenbergMarquardtOptimizer(
        graph, est, gtsam.LevenbergMarquardtParams()
    ).optimize()
    ref = np.array([[best.atPose2(int(i)).x(), best.atPose2(int(i)).y()] for i in log.pose_ids])
    return ref, float(graph.error(best))
