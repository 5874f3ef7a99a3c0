"""Metrics of a navigate run, on the true poses against the map (per robot: a list)."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from firefleet._typing import FloatArray
from firefleet.sim.registry import Metrics
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid

__all__ = ["METRIC_NAMES", "clearance_m", "navigate_metrics"]

METRIC_NAMES = (
    "goal_reached",
    "time_to_goal_s",
    "path_length_m",
    "collisions",
    "min_clearance_m",
    "position_rms_m",
    "localisation_time_s",
    "map_agreement_pct",
)

LOCALISED_M = 0.3
"""``localisation_time_s`` counts from when the estimate's error stays below this [m]."""


def _obstacle_cells(grid: OccupancyGrid) -> tuple[FloatArray, float]:
    """Centres (M, 2) [m] of the occupied cells and of a ring of cells just off the map
    (the world ends at its edge), and the cell side."""
    h, w = grid.shape
    rows, cols = np.nonzero(grid.occupied)
    ring_r = np.r_[np.full(w + 2, -1), np.full(w + 2, h), np.arange(h), np.arange(h)]
    ring_c = np.r_[np.arange(-1, w + 1), np.arange(-1, w + 1), np.full(h, -1), np.full(h, w)]
    cells = np.stack([np.r_[rows, ring_r], np.r_[cols, ring_c]], axis=-1)
    return grid.center_of(cells), grid.resolution_m


def clearance_m(grid: OccupancyGrid, xy_m: FloatArray) -> FloatArray:
    """Distance [m] from each point (..., 2) to the nearest occupied cell (the square,
    not its centre; 0 inside one); off the map counts as occupied.

    Exact: the nearest square lies among the cells whose centre is within half a
    diagonal of the nearest centre's distance.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.sim.kinds._navigate_metrics import clearance_m
    >>> occ = np.zeros((10, 10), dtype=bool); occ[:, 0] = True  # a wall x in [0, 1)
    >>> grid = OccupancyGrid(occ, ~occ, resolution_m=1.0)
    >>> clearance_m(grid, np.array([[3.5, 5.0], [0.5, 5.0]])).round(6).tolist()
    [2.5, 0.0]
    """
    centres, res = _obstacle_cells(grid)
    tree = cKDTree(centres)
    pts = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    d0, _ = tree.query(pts)
    half = res / 2.0
    out = np.empty(pts.shape[0])
    reach = d0 + half * math.sqrt(2.0) + 1e-9
    for i, (p, r) in enumerate(zip(pts, reach, strict=True)):
        near = centres[tree.query_ball_point(p, r)]
        dx = np.maximum(np.abs(near[:, 0] - p[0]) - half, 0.0)
        dy = np.maximum(np.abs(near[:, 1] - p[1]) - half, 0.0)
        out[i] = float(np.min(np.hypot(dx, dy)))
    result: FloatArray = out.reshape(np.shape(xy_m)[:-1])
    return result


def navigate_metrics(result: SimResult) -> Metrics:
    """Metrics of a navigate run (per robot where it makes sense, robot 1 first).

    ``goal_reached`` (1 if the robot's true position came within ``goal_tolerance_m``
    of its goal, else 0); ``time_to_goal_s`` (the first such time, NaN if never);
    ``path_length_m`` (distance driven, true poses); ``collisions`` (recorded steps in
    which the robot's disc overlaps an occupied cell, the map's outside, or another
    robot's disc); ``min_clearance_m`` (smallest distance from the disc to a wall or
    another robot's disc, negative in contact); ``position_rms_m`` (RMS distance
    between the pose estimate and the truth); ``map_agreement_pct`` (SLAM: the final
    map's cells classified as the ground truth, over the cells observed; NaN without a
    map).
    """
    from firefleet.sim.kinds.navigate import _command, _grid

    scenario = result.scenario
    cmd = _command(scenario)
    grid = _grid(scenario)
    r = cmd.robot_radius_m
    xy = result.pose[:, :, :2]
    t_steps, n = xy.shape[:2]
    goals = np.asarray(cmd.goals_m, dtype=float)
    dist = np.hypot(*(xy - goals[None]).transpose(2, 0, 1))
    reached, time_to = [], []
    for i in range(n):
        hit = np.nonzero(dist[:, i] <= cmd.goal_tolerance_m)[0]
        reached.append(1.0 if hit.size else 0.0)
        time_to.append(float(result.t[hit[0]]) if hit.size else math.nan)
    length = np.sum(np.hypot(*np.diff(xy, axis=0).transpose(2, 0, 1)), axis=0)
    wall = clearance_m(grid, xy) - r  # (T, N)
    clear = wall.copy()
    if n > 1:
        gap = np.hypot(*(xy[:, :, None] - xy[:, None]).transpose(3, 0, 1, 2)) - 2.0 * r
        gap[:, np.arange(n), np.arange(n)] = np.inf
        clear = np.minimum(clear, gap.min(axis=2))
    collisions = np.sum(clear < 0.0, axis=0)
    out: Metrics = {
        "goal_reached": reached,
        "time_to_goal_s": time_to,
        "path_length_m": [float(v) for v in length],
        "collisions": [float(v) for v in collisions],
        "min_clearance_m": [float(v) for v in clear.min(axis=0)],
    }
    est = result.extra.get("estimated_pose")
    if est is not None and t_steps:
        err = np.hypot(*(est[:, :, :2] - xy).transpose(2, 0, 1))
        out["position_rms_m"] = [float(v) for v in np.sqrt(np.mean(err**2, axis=0))]
        settle = []
        for i in range(n):
            off = np.nonzero(~(err[:, i] < LOCALISED_M))[0]
            k = 0 if off.size == 0 else int(off[-1]) + 1
            settle.append(float(result.t[k]) if k < t_steps else math.nan)
        out["localisation_time_s"] = settle
    else:
        out["position_rms_m"] = [math.nan] * n
        out["localisation_time_s"] = [math.nan] * n
    occupancy = result.extra.get("occupancy")
    out["map_agreement_pct"] = (
        _agreement(grid, np.asarray(occupancy)) if occupancy is not None else math.nan
    )
    return out


def _agreement(grid: OccupancyGrid, occupancy: FloatArray) -> float:
    """Percentage of the observed cells (probability away from 0.5) that the map
    classifies as the ground truth does (occupied above 0.5)."""
    observed = np.abs(occupancy - 0.5) > 0.1
    if not np.any(observed):
        return math.nan
    agree = (occupancy > 0.5) == grid.occupied
    return float(100.0 * np.mean(agree[observed]))
