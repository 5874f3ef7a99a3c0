"""Map cells whose centres lie within a distance of any of a set of points, in one
compiled pass (the fires' costmap marks the discs round every burning spot at each
plan: ~1 ms a call as array windows per spot on the 0.05 m office).

The arithmetic is :meth:`OccupancyGrid.cell_of`'s for the points' cells,
:meth:`OccupancyGrid.center_of`'s for the cells' centres and ``np.hypot``'s for the
distance (the C library's ``hypot`` both ways), over the same window of
``ceil(r / resolution) + 1`` cells each side of a point's cell, so the cells are the
array form's (``tests/control/mission/test_discs.py``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.world import OccupancyGrid

__all__ = ["disc_cells"]


@numba.njit(cache=True)
def _discs(
    h: int, w: int, ox: float, oy: float, res: float, xy: FloatArray, radius: float, k: int
) -> BoolArray:  # pragma: no cover - compiled
    """The (H, W) mask of the cells within ``radius`` of a point of ``xy`` (M, 2),
    each point's window ``k`` cells about its cell."""
    out = np.zeros((h, w), dtype=np.bool_)
    for i in range(xy.shape[0]):
        px = xy[i, 0]
        py = xy[i, 1]
        c = int(np.floor((px - ox) / res))
        r = h - 1 - int(np.floor((py - oy) / res))
        r0, r1 = max(r - k, 0), min(r + k + 1, h)
        c0, c1 = max(c - k, 0), min(c + k + 1, w)
        for rr in range(r0, r1):
            cy = oy + (float(h - 1 - rr) + 0.5) * res
            for cc in range(c0, c1):
                if out[rr, cc]:
                    continue
                cx = ox + (float(cc) + 0.5) * res
                if np.hypot(cx - px, cy - py) <= radius:
                    out[rr, cc] = True
    return out


def disc_cells(grid: OccupancyGrid, xy_m: FloatArray, radius_m: float) -> BoolArray:
    """Map cells (H, W) whose centres lie within ``radius_m`` (``hypot <= r``) of any
    point of ``xy_m`` (M, 2) [m]; points that are not finite, or whose window misses
    the map, mark nothing.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> g = OccupancyGrid(np.zeros((10, 10), bool), np.ones((10, 10), bool), 0.1)
    >>> int(disc_cells(g, np.array([[0.55, 0.55]]), 0.2).sum())  # a centre, 4 + 4 + 4 more
    13
    """
    h, w = grid.shape
    res = float(grid.resolution_m)
    ox, oy = (float(v) for v in grid.origin_m)
    k = math.ceil(radius_m / res) + 1
    xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    # a window that cannot reach the map marks nothing either way; the rest have cells
    # of a few map sizes, which the compiled integer conversion takes exactly
    margin = (k + 2) * res
    near = (
        np.isfinite(xy).all(axis=1)
        & (xy[:, 0] >= ox - margin)
        & (xy[:, 0] <= ox + w * res + margin)
        & (xy[:, 1] >= oy - margin)
        & (xy[:, 1] <= oy + h * res + margin)
    )
    out: BoolArray = _discs(
        h, w, ox, oy, res, np.ascontiguousarray(xy[near]), float(radius_m), int(k)
    )
    return out
