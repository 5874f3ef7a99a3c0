"""A robot standing in a teammate's way makes way, and comes back once it has passed.

A robot that has arrived (a fighter at its slot, a refiller, one that waits) stands
still; a teammate whose path leads through where it stands cannot pass it where the way
is narrow (the maze's 1 m passages: with two radii and the margins, a robot standing in
the middle leaves no room beside it), and the team's priorities by index only order
robots that move. So, per control period, a moving robot's path ahead is checked
against every standing teammate the caller marks as able to move (``movable``):

- the standing robot is *in the way* when it lies within ``2 radius + margin`` of the
  mover's next ``yield_distance_m`` of path, the mover's target is not where it stands
  (farther than that gap + the goal tolerance + 0.1 m), and the way past it is cut:
  :func:`cuts_path`, in a window about it, the free cells left once its disc is on the
  map (grown by the planner's inflation) do not join where the mover's path enters the
  window to where it leaves it;
- it then makes way (:func:`make_way_spot`): to the nearest open spot within
  ``make_way_reach_m`` (unpriced where there are any: not into a fire's gas) that is
  either clear of the mover's whole remaining path by that gap + tolerance + 0.1 m, or
  does not cut the mover's path (in a passage: its side), and that it can reach round
  the mover; there it stands, and the mover re-plans round it;
- it goes back to its own goal once the mover's remaining path (and the mover) lies
  farther than that distance from the goal, or the mover stopped (:func:`passed`).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy import ndimage

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.navigation._costmap import Costmap
from firefleet.control.navigation._team import (
    NavigationParams,
    NavigationState,
    _plan,
    _wall_extra,
    _with_teammates,
)

__all__ = ["clear_of", "cuts_path", "make_way_spot", "open_cells_near", "passed", "price"]

_WINDOW_M = 1.5
"""Half the side of the window the way past a standing robot is judged in [m]."""


@numba.njit(cache=True)
def clear_of(
    xy: FloatArray, pts: FloatArray, limit: float
) -> np.ndarray:  # pragma: no cover - compiled
    """Whether each point of ``xy`` (C, 2) lies farther than ``limit`` from every point
    of ``pts`` (P, 2) (all True for no points)."""
    keep = np.ones(xy.shape[0], dtype=np.bool_)
    for c in range(xy.shape[0]):
        for j in range(pts.shape[0]):
            if not np.hypot(xy[c, 0] - pts[j, 0], xy[c, 1] - pts[j, 1]) > limit:
                keep[c] = False
                break
    return keep


def price(costmap: Costmap, params: NavigationParams, cells: IntArray) -> FloatArray:
    """The cost per metre of each open cell (K, 2) beyond its walls' (0: none)."""
    r, c = cells[:, 0], cells[:, 1]
    extra = costmap.cost[r, c] - 1.0 - _wall_extra(costmap.clearance_m[r, c], params)
    out: FloatArray = np.where(extra > 1e-9, extra, 0.0)
    return out


def cuts_path(costmap: Costmap, xy_m: FloatArray, block_m: float, path_xy_m: FloatArray) -> bool:
    """Whether a disc at ``xy_m`` (2,) [m] that blocks the cells within ``block_m`` of it
    cuts the path (K, 2) [m] in the window about it (module notes).

    The path's first and last points in the window are joined, or not, through the
    costmap's open cells (4-neighbours) the disc leaves in the window; an end inside
    the blocked disc is cut; a path that does not enter the window is not.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((40, 100), dtype=bool)
    >>> occ[:15] = occ[25:] = True  # a 1 m passage along y = 2 m (0.1 m cells)
    >>> cm = build_costmap(OccupancyGrid(occ, ~occ, 0.1), 0.2)
    >>> path = np.stack([np.linspace(1.0, 9.0, 81), np.full(81, 2.0)], axis=1)
    >>> cuts_path(cm, np.array([5.0, 2.0]), 0.35, path)  # standing in the middle
    True
    >>> cuts_path(cm, np.array([5.0, 1.75]), 0.35, path)  # by the wall: a way past
    False
    """
    grid = costmap.grid
    res = grid.resolution_m
    h, w = grid.shape
    r, c = (int(v) for v in grid.cell_of(np.asarray(xy_m, dtype=float)))
    k = math.ceil(_WINDOW_M / res)
    r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, h), max(c - k, 0), min(c + k + 1, w)
    if r0 >= r1 or c0 >= c1:
        return False
    pts = np.asarray(path_xy_m, dtype=float).reshape(-1, 2)
    rc = grid.cell_of(pts)
    inside = (rc[:, 0] >= r0) & (rc[:, 0] < r1) & (rc[:, 1] >= c0) & (rc[:, 1] < c1)
    if not inside.any():
        return False
    ends = rc[np.flatnonzero(inside)[[0, -1]]] - np.array([r0, c0])
    rr, cc = np.mgrid[r0:r1, c0:c1]
    centres = grid.center_of(np.stack([rr, cc], axis=-1))
    disc = np.hypot(centres[..., 0] - xy_m[0], centres[..., 1] - xy_m[1]) <= block_m
    free: BoolArray = ~np.asarray(costmap.blocked[r0:r1, c0:c1]) & ~disc
    if not (free[ends[0, 0], ends[0, 1]] and free[ends[1, 0], ends[1, 1]]):
        return True
    labels, _ = ndimage.label(free)
    return bool(labels[ends[0, 0], ends[0, 1]] != labels[ends[1, 0], ends[1, 1]])


def passed(mover_rest_xy_m: FloatArray, home_xy_m: FloatArray, limit_m: float) -> bool:
    """Whether a mover whose position and remaining path are ``mover_rest_xy_m`` (K, 2)
    [m] keeps farther than ``limit_m`` from ``home_xy_m`` (2,) [m]: a robot that made way
    may go back there.

    Examples
    --------
    >>> import numpy as np
    >>> rest = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    >>> passed(rest, np.array([1.0, 0.5]), 0.65), passed(rest, np.array([1.0, 0.7]), 0.65)
    (False, True)
    """
    pts = np.asarray(mover_rest_xy_m, dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        return True
    d = np.hypot(pts[:, 0] - home_xy_m[0], pts[:, 1] - home_xy_m[1])
    return bool(d.min() > limit_m)


def open_cells_near(
    costmap: Costmap, params: NavigationParams, xy_m: FloatArray, reach_m: float
) -> FloatArray:
    """Centres (K, 2) [m] of the open cells in the square of half-side ``reach_m`` [m]
    about ``xy_m`` (2,) [m], the unpriced ones only where there are any (the mission
    prices cells by fires and hot places: a spot out of a teammate's way must not lie in
    the fire's gas); (0, 2) when none is open."""
    grid = costmap.grid
    reach = round(reach_m / grid.resolution_m)
    rc = grid.cell_of(xy_m)
    h, w = grid.shape
    r0, r1 = max(rc[0] - reach, 0), min(rc[0] + reach + 1, h)
    c0, c1 = max(rc[1] - reach, 0), min(rc[1] + reach + 1, w)
    cells = np.argwhere(~costmap.blocked[r0:r1, c0:c1]) + np.array([r0, c0])
    if len(cells) == 0:
        return np.zeros((0, 2))
    cheap = price(costmap, params, cells)
    if (cheap <= 0.0).any():
        cells = cells[cheap <= 0.0]
    out: FloatArray = grid.center_of(cells)
    return out


def make_way_spot(
    state: NavigationState,
    params: NavigationParams,
    pose: FloatArray,
    mates: FloatArray,
    j: int,
    i: int,
    rest: FloatArray,
) -> FloatArray | None:
    """Where standing robot ``j`` makes way for mover ``i`` (module notes), whose
    position and remaining path are ``rest`` (K, 2) [m]; None if there is no spot.

    The candidates are the open cells within ``make_way_reach_m`` of ``j`` (unpriced
    where there are any), nearest first: the nearest that keeps the gap + the goal
    tolerance + 0.1 m from ``rest`` and from every other robot, and the nearest few
    (within 1 m) that leave ``i`` a way past (:func:`cuts_path`), kept gap + tolerance
    from every other robot; of these the nearer that ``j`` can reach round ``i``."""
    grid = state.costmap.grid
    gap = 2.0 * params.robot_radius_m + params.margin_m
    limit = gap + params.goal_tolerance_m + 0.1
    xy = open_cells_near(state.costmap, params, pose[j, :2], params.make_way_reach_m)
    if len(xy) == 0:
        return None
    dist = np.hypot(xy[:, 0] - pose[j, 0], xy[:, 1] - pose[j, 1])
    keep = dist <= params.make_way_reach_m
    xy, dist = xy[keep], dist[keep]
    others = np.ascontiguousarray(np.delete(mates, [i, j], axis=0), dtype=float)
    near_ok = clear_of(np.ascontiguousarray(xy), others, limit)
    xy, dist = xy[near_ok], dist[near_ok]
    if len(xy) == 0:
        return None
    order = np.argsort(dist)
    xy, dist = xy[order], dist[order]
    tries: list[FloatArray] = []
    clear = np.flatnonzero(clear_of(xy, np.ascontiguousarray(rest, dtype=float), limit))
    if len(clear):
        tries.append(xy[clear[0]])
    # by a wall (the planner's least clearance and two cells more), leaving the mover
    # a way past with a cell to spare
    res = grid.resolution_m
    block = params.robot_radius_m + params.inflation_m + res
    clear_m = state.costmap.clearance_m[tuple(grid.cell_of(xy).T)]
    side = 0
    for k in np.flatnonzero((dist <= 1.0) & (clear_m <= params.inflation_m + 2.0 * res)):
        if side >= 12:
            break
        if np.hypot(*(xy[k] - pose[i, :2])) <= limit:
            continue
        side += 1
        if not cuts_path(state.costmap, xy[k], block, rest):
            tries.insert(0, xy[k])
            break
    if not tries:
        return None
    costmap = _with_teammates(state, params, mates[i : i + 1])
    for spot in sorted(tries, key=lambda s: float(np.hypot(*(s - pose[j, :2])))):
        status, _ = _plan(costmap, pose[j, :2], spot, params)
        if status == "moving":
            return np.asarray(spot)
    return None
