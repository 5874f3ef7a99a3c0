"""The team's coarse view of the building: coverage, line of sight, travel distances.

The map's cells (0.05 m) are too many for what the team decides a few times a second,
so the team works on a coarse grid of ``plan_cell_m`` (default 0.25 m; a whole number
``f`` of map cells per side). A coarse cell is

- *opaque* when any of its map cells is occupied (or it lies off the map): line of
  sight (the camera's coverage, the nozzle's reach) stops there;
- *floor* when any of its map cells is free: the building to explore;
- *standable* when any of its map cells is open in the navigation costmap (free and
  farther than robot radius + margin from a wall); its *goal cell* is that open map
  cell nearest to its centre, where the team sends a robot.

Coverage: a robot's thermal camera covers the cells of its cone (``hfov_rad`` wide,
``sensing_range_m`` long) up to and including the first opaque cell along each ray
(rays every half cell of arc at full range, samples every half cell), plus the cell it
stands on. Travel distances: Dijkstra on the standable cells' 8-connected graph
(:func:`firefleet.planning.geodesic.grid_graph`, built once), optionally cut off at a
distance limit (``scipy.sparse.csgraph.dijkstra``'s ``limit``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.ndimage as ndi
import scipy.sparse
from scipy.sparse.csgraph import dijkstra

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.navigation import Costmap
from firefleet.planning.geodesic import grid_graph
from firefleet.world import OccupancyGrid

__all__ = ["CoarseMap", "coarse_map", "cone_coverage", "line_of_sight"]


@dataclass(frozen=True, eq=False)
class CoarseMap:
    """The coarse grid the team decides on (module notes).

    Attributes
    ----------
    grid : OccupancyGrid
        The map (the cell <-> metre conversion of the fine cells).
    factor : int
        Map cells per coarse cell side.
    cell_m : float
        Coarse cell side [m].
    opaque, floor, standable : ndarray of bool, shape (Hc, Wc)
        The coarse cells' kinds.
    goal_cell : ndarray of int, shape (Hc, Wc, 2)
        Each standable coarse cell's open map cell (row, col) nearest its centre
        (-1 elsewhere).
    nearest_standable : ndarray of int, shape (Hc, Wc, 2)
        The standable coarse cell nearest to each coarse cell.
    free_count : ndarray of int, shape (Hc, Wc)
        Free map cells in each coarse cell (the explored fraction without the map grid).
    graph : scipy.sparse.csr_matrix, shape (Hc Wc, Hc Wc)
        Travel graph of the standable cells [m].
    """

    grid: OccupancyGrid
    factor: int
    cell_m: float
    opaque: BoolArray
    floor: BoolArray
    standable: BoolArray
    goal_cell: IntArray
    nearest_standable: IntArray
    graph: scipy.sparse.csr_matrix
    free_count: IntArray

    @property
    def shape(self) -> tuple[int, int]:
        """``(Hc, Wc)``."""
        h, w = self.opaque.shape
        return int(h), int(w)

    def cell_of(self, xy_m: FloatArray) -> IntArray:
        """Coarse (row, col) of points (..., 2), clipped onto the grid."""
        rc = self.grid.cell_of(xy_m) // self.factor
        hc, wc = self.shape
        return np.stack([np.clip(rc[..., 0], 0, hc - 1), np.clip(rc[..., 1], 0, wc - 1)], -1)

    def goal_xy(self, cells: IntArray) -> FloatArray:
        """The goal point [m] (..., 2) of coarse cells (..., 2) (their centre when not
        standable)."""
        g = self.goal_cell[cells[..., 0], cells[..., 1]]
        f = self.factor
        centre = (cells.astype(float) + 0.5) * f - 0.5
        out: FloatArray = self.grid.center_of(np.where(g[..., :1] >= 0, g, centre))
        return out

    def node_of(self, xy_m: FloatArray) -> IntArray:
        """Graph node (M,) of the standable cell nearest each point (M, 2)."""
        rc = self.cell_of(xy_m)
        near = self.nearest_standable[rc[..., 0], rc[..., 1]]
        out: IntArray = near[..., 0] * self.shape[1] + near[..., 1]
        return out

    def distances(self, nodes: IntArray, limit_m: float = math.inf) -> FloatArray:
        """Travel distance [m] from each node to every cell, (K, Hc Wc) (``inf``: not
        reached within ``limit_m``)."""
        if len(nodes) == 0:
            return np.zeros((0, self.shape[0] * self.shape[1]))
        out: FloatArray = np.asarray(
            dijkstra(self.graph, directed=False, indices=nodes, limit=limit_m), dtype=float
        ).reshape(len(nodes), -1)
        return out


def _blocks(a: BoolArray, f: int, fill: bool) -> BoolArray:
    """``a`` (H, W) padded with ``fill`` to multiples of ``f``, as (Hc, Wc, f * f)."""
    h, w = a.shape
    hc, wc = -(-h // f), -(-w // f)
    p = np.full((hc * f, wc * f), fill, dtype=bool)
    p[:h, :w] = a
    return p.reshape(hc, f, wc, f).transpose(0, 2, 1, 3).reshape(hc, wc, f * f)


def coarse_map(costmap: Costmap, cell_m: float) -> CoarseMap:
    """The coarse grid of a navigation costmap (module notes).

    Parameters
    ----------
    costmap : Costmap
        The map inflated for navigation.
    cell_m : float
        Wanted coarse cell side [m] (rounded to a whole number of map cells, >= 1).

    Returns
    -------
    CoarseMap

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> occ = np.zeros((20, 40), bool); occ[:, 19:21] = True   # a wall down the middle
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> cm.shape, cm.factor, int(cm.opaque.sum()), bool(cm.standable[2, 1])
    ((4, 8), 5, 8, True)
    """
    grid = costmap.grid
    f = max(1, round(cell_m / grid.resolution_m))
    opaque: BoolArray = np.any(_blocks(np.asarray(grid.occupied), f, True), axis=-1)
    free_blocks = _blocks(np.asarray(grid.free), f, False)
    floor: BoolArray = np.any(free_blocks, axis=-1)
    open_ = _blocks(~np.asarray(costmap.blocked), f, False)
    standable: BoolArray = np.any(open_, axis=-1)
    hc, wc = opaque.shape
    # the open map cell nearest each coarse cell's centre
    rr, cc = np.divmod(np.arange(f * f), f)
    d2 = (rr - (f - 1) / 2) ** 2 + (cc - (f - 1) / 2) ** 2
    pick = np.argmin(np.where(open_, d2[None, None, :], np.inf), axis=-1)
    base_r, base_c = np.mgrid[:hc, :wc]
    goal = np.stack([base_r * f + rr[pick], base_c * f + cc[pick]], axis=-1)
    goal[~standable] = -1
    if standable.any():
        _, idx = ndi.distance_transform_edt(~standable, return_indices=True)
        nearest = np.stack([idx[0], idx[1]], axis=-1)
    else:
        nearest = np.stack([base_r, base_c], axis=-1)
    return CoarseMap(
        grid=grid,
        factor=f,
        cell_m=f * grid.resolution_m,
        opaque=opaque,
        floor=floor,
        standable=standable,
        goal_cell=goal.astype(np.int64),
        nearest_standable=nearest.astype(np.int64),
        graph=grid_graph(standable, f * grid.resolution_m),
        free_count=free_blocks.sum(axis=-1).astype(np.int64),
    )


def cone_coverage(
    cm: CoarseMap, pose: FloatArray, range_m: float, hfov_rad: float
) -> tuple[IntArray, IntArray]:
    """The coarse cells the robots' cameras cover (module notes).

    Parameters
    ----------
    cm : CoarseMap
    pose : ndarray, shape (N, 3)
        Poses x [m], y [m], heading [rad].
    range_m, hfov_rad : float
        The cone's length [m] and opening [rad].

    Returns
    -------
    rows, cols : ndarray of int, shape (M,)
        Covered cells (with repeats).
    """
    step = 0.5 * cm.cell_m
    n_rays = max(2, math.ceil(hfov_rad * range_m / step) + 1)
    ang = pose[:, 2:3] + np.linspace(-0.5 * hfov_rad, 0.5 * hfov_rad, n_rays)[None]  # (N, R)
    dist = np.arange(1, math.floor(range_m / step) + 1) * step  # (S,)
    x = pose[:, 0, None, None] + dist * np.cos(ang)[..., None]  # (N, R, S)
    y = pose[:, 1, None, None] + dist * np.sin(ang)[..., None]
    xy = np.stack([x, y], axis=-1)
    on = cm.grid.contains(xy)
    rc = cm.cell_of(xy)
    blocked = ~on | cm.opaque[rc[..., 0], rc[..., 1]]
    blocked[..., dist < cm.cell_m] = False  # a robot beside a wall still looks out
    # visible: no opaque sample before this one (the first opaque one is seen)
    before = np.zeros_like(blocked)
    before[..., 1:] = np.logical_or.accumulate(blocked, axis=-1)[..., :-1]
    seen = on & ~before
    own = cm.cell_of(pose[:, :2])
    rows = np.concatenate([rc[..., 0][seen], own[:, 0]])
    cols = np.concatenate([rc[..., 1][seen], own[:, 1]])
    return rows, cols


def line_of_sight(cm: CoarseMap, a_m: FloatArray, b_m: FloatArray) -> BoolArray:
    """Whether nothing opaque lies between points ``a`` and ``b`` (M, 2) [m].

    The coarse cells within one cell of either end are not checked (a robot beside a
    wall, a fire in a cell touching one).
    """
    a = np.asarray(a_m, dtype=float).reshape(-1, 2)
    b = np.asarray(b_m, dtype=float).reshape(-1, 2)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    seg = np.hypot(*(b - a).T)
    n = max(2, math.ceil(float(seg.max()) / (0.5 * cm.cell_m)) + 1)
    s = np.linspace(0.0, 1.0, n)
    pts = a[:, None] + s[None, :, None] * (b - a)[:, None]
    rc = cm.cell_of(pts)
    blocked = cm.opaque[rc[..., 0], rc[..., 1]]
    along = s[None] * seg[:, None]
    ends = (along < cm.cell_m) | (along > seg[:, None] - cm.cell_m)
    out: BoolArray = ~np.any(blocked & ~ends, axis=1)
    return out
