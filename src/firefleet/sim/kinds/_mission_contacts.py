"""Contacts of the mission's robots at every tick, for the ``collisions`` metric.

The mission records its robots' poses at the tactics' rate (10 Hz, ``mission`` module
notes), not at every tick: a touch between two samples would be lost. So the world
notes at every tick, on the true poses, what the metric needs to give the answer it
gives on poses recorded at every tick (:func:`firefleet.sim.kinds._mission_metrics._touching`):

- two robots touch when their centres are closer than two radii: tested at once on
  the same numbers (``np.hypot`` of the same differences);
- a robot may touch a wall only where the lower bound of its clearance (the distance
  transform of the map's cells, less half a cell's diagonal) allows it: those points
  are kept (robot, x, y), and the metric computes their exact clearance
  (:func:`~firefleet.sim.kinds._navigate_metrics.clearance_m`) as it did on every
  recorded point. A point the bound rules out cannot touch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.world import OccupancyGrid

__all__ = ["ContactCheck", "near_wall_cells", "touched_walls"]


def near_wall_cells(grid: OccupancyGrid, radius_m: float) -> BoolArray:
    """Cells (H, W) where a disc of ``radius_m`` centred in them may touch an occupied
    cell: the clearance's lower bound ``(e - sqrt 2) * resolution`` (``e`` the distance
    in cells from the cell's centre to the nearest occupied centre, the map's edge
    counting as occupied) below the radius.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((5, 8), dtype=bool); occ[:, 0] = True
    >>> near_wall_cells(OccupancyGrid(occ, ~occ, 1.0), 0.5)[2].astype(int).tolist()
    [1, 1, 0, 0, 0, 0, 0, 1]

    The wall's column and the next, not the one after (2 cells from the wall's centres:
    a bound of 0.59 m), and the last column, by the map's edge.
    """
    import scipy.ndimage as ndi

    edt = ndi.distance_transform_edt(~np.pad(grid.occupied, 1, constant_values=True))[1:-1, 1:-1]
    bound = (edt - math.sqrt(2.0)) * grid.resolution_m
    near: BoolArray = bound < radius_m + 1e-9
    return near


@dataclass(frozen=True, eq=False)
class ContactCheck:
    """The per-tick contact test (module notes).

    Attributes
    ----------
    grid : OccupancyGrid
        The map the robots drive on.
    radius_m : float
        The robots' radius [m].
    near_wall : ndarray of bool, shape (H, W)
        :func:`near_wall_cells` of the two.
    """

    grid: OccupancyGrid
    radius_m: float
    near_wall: BoolArray

    @classmethod
    def of(cls, grid: OccupancyGrid, radius_m: float) -> ContactCheck:
        """The test for robots of ``radius_m`` on ``grid``."""
        return cls(grid, float(radius_m), near_wall_cells(grid, radius_m))

    def init(self, n_robots: int) -> dict[str, Any]:
        """The log entries: the points near walls, and who touched another robot."""
        return {"near_wall": [], "touched_robot": np.zeros(n_robots, dtype=bool)}

    def check(self, log: dict[str, Any], pose: FloatArray) -> None:
        """Note the contacts of the poses (N, 3) [m, m, rad] of a tick in ``log``.

        A compiled pass (:func:`_candidates`) finds the robots near a wall (the same
        cell arithmetic as :meth:`OccupancyGrid.cell_of`) and whether any two come within
        a hair over two radii; only then does the exact pair test run (``np.hypot``, as
        the metric's)."""
        xy = np.ascontiguousarray(pose[:, :2], dtype=np.float64)
        near = np.empty(xy.shape[0], dtype=np.bool_)
        ox, oy = self.grid.origin_m
        close = _candidates(
            xy, float(ox), float(oy), self.grid.resolution_m, self.near_wall, self.radius_m, near
        )
        if near.any():
            idx = np.flatnonzero(near)
            log["near_wall"].append(np.c_[idx.astype(float), xy[idx]])
        if close:
            d = np.hypot(xy[None, :, 0] - xy[:, None, 0], xy[None, :, 1] - xy[:, None, 1])
            np.fill_diagonal(d, np.inf)
            log["touched_robot"] |= (d < 2 * self.radius_m).any(axis=1)

    def check_ticks(self, log: dict[str, Any], poses: FloatArray) -> None:
        """:meth:`check` of each tick's poses (m, N, 3) in turn, the candidates of all
        of them found in one compiled pass (a quiet stretch's ticks)."""
        xy = np.ascontiguousarray(poses[:, :, :2], dtype=np.float64)
        m, n = xy.shape[0], xy.shape[1]
        near = np.empty((m, n), dtype=np.bool_)
        close = np.empty(m, dtype=np.bool_)
        ox, oy = self.grid.origin_m
        _candidates_ticks(
            xy, float(ox), float(oy), self.grid.resolution_m, self.near_wall, self.radius_m,
            near, close,
        )  # fmt: skip
        for j in np.flatnonzero(near.any(axis=1) | close):
            if near[j].any():
                idx = np.flatnonzero(near[j])
                log["near_wall"].append(np.c_[idx.astype(float), xy[j, idx]])
            if close[j]:
                p = xy[j]
                d = np.hypot(p[None, :, 0] - p[:, None, 0], p[None, :, 1] - p[:, None, 1])
                np.fill_diagonal(d, np.inf)
                log["touched_robot"] |= (d < 2 * self.radius_m).any(axis=1)

    def final(self, log: dict[str, Any]) -> dict[str, FloatArray]:
        """``near_wall_xy_m`` (M, 3: robot, x [m], y [m]) and ``touched_robot`` (N,)."""
        pts = np.concatenate(log["near_wall"]) if log["near_wall"] else np.zeros((0, 3))
        return {
            "near_wall_xy_m": pts,
            "touched_robot": log["touched_robot"].astype(float),
        }


@numba.njit(cache=True)
def _candidates(
    xy: FloatArray,
    ox: float,
    oy: float,
    res: float,
    near_wall: BoolArray,
    radius_m: float,
    near: BoolArray,
) -> bool:  # pragma: no cover - compiled
    """Fill ``near`` (N,): each point off the grid or in a ``near_wall`` cell (the cell
    as :meth:`OccupancyGrid.cell_of` finds it); return whether two points lie closer than
    two radii and a relative 1e-6 (their squared distance: a superset of the pairs the
    exact ``np.hypot`` test can find)."""
    h, w = near_wall.shape
    n = xy.shape[0]
    for i in range(n):
        col = np.int64(math.floor((xy[i, 0] - ox) / res))
        row = h - 1 - np.int64(math.floor((xy[i, 1] - oy) / res))
        if 0 <= row < h and 0 <= col < w:
            near[i] = near_wall[row, col]
        else:
            near[i] = True
    reach = (2.0 * radius_m * (1.0 + 1e-6)) ** 2
    for i in range(n):
        for j in range(i + 1, n):
            dx = xy[j, 0] - xy[i, 0]
            dy = xy[j, 1] - xy[i, 1]
            if dx * dx + dy * dy < reach:
                return True
    return False


@numba.njit(cache=True)
def _candidates_ticks(
    xy: FloatArray,
    ox: float,
    oy: float,
    res: float,
    near_wall: BoolArray,
    radius_m: float,
    near: BoolArray,
    close: BoolArray,
) -> None:  # pragma: no cover - compiled
    """:func:`_candidates` of each tick's points ``xy[j]`` (m, N, 2): ``near[j]`` (m, N)
    and ``close[j]`` (m,)."""
    for j in range(xy.shape[0]):
        close[j] = _candidates(xy[j], ox, oy, res, near_wall, radius_m, near[j])


def touched_walls(
    grid: OccupancyGrid, near_wall_xy_m: FloatArray, n_robots: int, radius_m: float
) -> BoolArray:
    """Whether each robot (N,) touched a wall at one of the points (M, 3: robot, x, y)
    :class:`ContactCheck` kept: their exact clearance below ``radius_m``."""
    from firefleet.sim.kinds._navigate_metrics import clearance_m

    touch = np.zeros(n_robots, dtype=bool)
    pts = np.asarray(near_wall_xy_m, dtype=float).reshape(-1, 3)
    if len(pts):
        clear = clearance_m(grid, pts[:, 1:])
        np.logical_or.at(touch, pts[:, 0].astype(np.int64), clear < radius_m)
    return touch
