"""The formation kind's metrics (deliverable section 2.3), and those of its link."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.scenarios.schema import Formation
from firefleet.sim.result import SimResult

__all__ = ["RADIUS_BAND", "formation_metrics", "link_metrics", "spacing_error_deg"]

RADIUS_BAND = 0.05
"""Band of ``radius_settling_time_s``: within 5 % of alpha (the issue's bound)."""


def _command(result: SimResult) -> Formation:
    cmd = result.scenario.command
    if not isinstance(cmd, Formation):
        raise InputError(f"not a formation scenario: command kind {cmd.kind!r}")
    return cmd


def spacing_error_deg(points: FloatArray, leader_xy: FloatArray) -> FloatArray:
    """Largest deviation of the angular gaps between neighbours from 360 / N [deg].

    Parameters
    ----------
    points : ndarray, shape (T, N, 2)
        Formation points [m].
    leader_xy : ndarray, shape (T, 2)
        Leader [m].

    Returns
    -------
    ndarray, shape (T,)
        ``max_k |gap_k - 360 / N|`` where the gaps are the differences of the sorted
        angles of the robots about the leader (wrapping around); 0 for one robot.
    """
    d = points - leader_xy[:, None, :]
    ang = np.sort(np.degrees(np.arctan2(d[..., 1], d[..., 0])), axis=1)
    n = ang.shape[1]
    if n < 2:
        return np.zeros(ang.shape[0])
    gaps = np.diff(np.concatenate([ang, ang[:, :1] + 360.0], axis=1), axis=1)
    return np.asarray(np.abs(gaps - 360.0 / n).max(axis=1), dtype=np.float64)


def _min_clearance(result: SimResult, cmd: Formation) -> float:
    """Smallest gap between two robot bodies or a body and an obstacle over the run [m]."""
    centres = result.pose[:, :, :2]
    n = centres.shape[1]
    best = math.inf
    radius = cmd.robot_radius_m
    if n >= 2:
        for xy in centres:
            dist, _ = cKDTree(xy).query(xy, k=2)
            best = min(best, float(dist[:, 1].min()) - 2.0 * radius)
    for o in cmd.obstacles:
        d = np.sqrt(((centres - np.array([o.x_m, o.y_m])) ** 2).sum(axis=2))
        best = min(best, float(d.min()) - radius - o.radius_m)
    return best


def formation_metrics(result: SimResult) -> dict[str, float | list[float]]:
    """The metrics of a formation run.

    Shape metrics use the formation points of the robots in the team (a failed robot
    drops out from its failure on) at the samples from ``formed_by_s`` on:

    - ``radius_error_max_m``: largest ``| |p_k - c| - alpha |``;
    - ``spacing_error_max_deg``: largest deviation from 360 / N of the angle between
      neighbours about the leader (N the robots in the team at that sample);
    - ``radius_settling_time_s``: time from the start until every robot in the team is
      within 5 % of alpha of the circle for good (``inf`` if not by the end);
    - ``final_radius_m``: each robot's distance from the leader at the end (a list,
      robot 1 first);
    - ``min_clearance_m``: over the whole run and every robot (failed ones too), the
      smallest gap between two bodies (``|p_k - p_i| - 2 R``) or between a body and an
      obstacle (``|p_k - o| - R - R_o``), from the robots' centres; > 0 means no
      contact.
    """
    cmd = _command(result)
    t = result.t
    points = np.asarray(result.extra["formation_xy_m"])
    leader = np.asarray(result.extra["leader_xy_m"])
    active = np.asarray(result.extra["robot_active"]) > 0.5
    r = np.sqrt(((points - leader[:, None, :]) ** 2).sum(axis=2))
    err = np.where(active, np.abs(r - cmd.alpha_m), 0.0)
    window = t >= cmd.formed_by_s - 1e-9
    spacing = np.zeros(t.size)
    for pattern in np.unique(active, axis=0):
        rows = (active == pattern).all(axis=1)
        spacing[rows] = spacing_error_deg(points[rows][:, pattern], leader[rows])
    worst = err.max(axis=1)
    outside = np.nonzero(worst > RADIUS_BAND * cmd.alpha_m)[0]
    if outside.size == 0:
        settle = 0.0
    elif outside[-1] == t.size - 1:
        settle = math.inf
    else:
        settle = float(t[outside[-1] + 1])
    return {
        "radius_error_max_m": float(worst[window].max()),
        "spacing_error_max_deg": float(spacing[window].max()),
        "min_clearance_m": _min_clearance(result, cmd),
        "radius_settling_time_s": settle,
        "final_radius_m": [float(v) for v in r[-1]],
        **link_metrics(result),
    }


def link_metrics(result: SimResult) -> dict[str, float]:
    """``messages_sent`` and ``messages_lost`` (per directed pair, the link's counters)
    and ``message_age_max_s`` (the oldest neighbour's value a robot's law used; NaN if it
    used none) of a formation run over an impaired link; over the ideal link every robot
    reads every other's point as it is, at every tick (``n (n - 1) n_steps`` messages,
    none lost, age 0).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.result import SimResult
    >>> scn = load_scenario("formation-3")
    >>> z = np.zeros((2, 3, 0))
    >>> res = SimResult(scn, np.zeros(2), np.zeros((2, 3, 3)), z, z, z, z, z, z, extra={})
    >>> link_metrics(res)["messages_sent"] == 3 * 2 * scn.n_steps
    True
    """
    extra = result.extra
    if "messages_sent" not in extra:
        n = result.pose.shape[1]
        return {
            "messages_sent": float(n * (n - 1) * result.scenario.n_steps),
            "messages_lost": 0.0,
            "message_age_max_s": 0.0,
        }
    age = np.asarray(extra["message_age_max_s"])
    return {
        "messages_sent": float(extra["messages_sent"][-1]),
        "messages_lost": float(extra["messages_lost"][-1]),
        "message_age_max_s": float(np.nanmax(age)) if np.isfinite(age).any() else math.nan,
    }
