"""From A*'s staircase of cells to a smooth path the fuzzy follower can drive.

1. Line-of-sight shortcutting: from each kept vertex, the path jumps to the farthest
   later cell that a straight segment reaches without coming nearer the walls than A*'s
   own cells did on that stretch (the clearance sampled every quarter cell). The path
   keeps A*'s distance from walls and loses its 45-degree zigzags.
2. Corner rounding: each remaining corner becomes a circular arc tangent to both
   segments (:meth:`firefleet.planning.PlanarPath.from_polyline`; C1, arc-length
   parametrised in closed form). Where an arc would enter the inflated region (it cuts
   inside the corner), its radius is halved until it does not, down to a sharp corner,
   which the shortcutting already checked.

The result's clearance is therefore > ``inflation_m`` at every sample (a test checks it).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.control.navigation._costmap import Costmap
from firefleet.planning.planar import PlanarPath

__all__ = ["clearance_along", "shortcut", "smooth_path"]


def clearance_along(costmap: Costmap, xy_m: ArrayLike) -> FloatArray:
    """Clearance [m] of the cell under each point (..., 2); 0 off the map."""
    xy = np.asarray(xy_m, dtype=float)
    grid = costmap.grid
    rc = grid.cell_of(xy)
    inside = grid.contains(xy)
    h, w = grid.shape
    r = np.clip(rc[..., 0], 0, h - 1)
    c = np.clip(rc[..., 1], 0, w - 1)
    return np.where(inside, costmap.clearance_m[r, c], 0.0)


@numba.njit(cache=True)
def _clearance_at(
    x: float, y: float, clearance: FloatArray, origin: FloatArray, res: float
) -> float:  # pragma: no cover - compiled
    """:func:`clearance_along` of one point (OccupancyGrid.cell_of's arithmetic)."""
    h, w = clearance.shape
    col = int(np.floor((x - origin[0]) / res))
    row = h - 1 - int(np.floor((y - origin[1]) / res))
    if row < 0 or row >= h or col < 0 or col >= w:
        return 0.0
    return float(clearance[row, col])


@numba.njit(cache=True)
def _shortcut_kept(
    xy: FloatArray, clearance: FloatArray, origin: FloatArray, res: float, floor: float
) -> np.ndarray:  # pragma: no cover - compiled
    """The indices of the vertices :func:`shortcut` keeps (module notes, step 1): from
    each kept vertex, the farthest later one whose straight segment, sampled every
    quarter cell (``np.linspace``'s points), keeps its inner samples at least as clear
    as the path's own vertices on that stretch (and above ``floor``) and every sample
    above ``floor``."""
    k = xy.shape[0]
    step = res / 4.0
    own = np.empty(k)
    for i in range(k):
        own[i] = _clearance_at(xy[i, 0], xy[i, 1], clearance, origin, res)
    kept = np.empty(k, dtype=np.int64)
    kept[0] = 0
    n_kept = 1
    i = 0
    while i < k - 1:
        j = i + 1
        lowest = min(own[i], own[j])
        while j + 1 < k:
            lowest_next = min(lowest, own[j + 1])
            need = max(lowest_next, floor)
            ax, ay = xy[i, 0], xy[i, 1]
            dx, dy = xy[j + 1, 0] - ax, xy[j + 1, 1] - ay
            n = max(int(np.ceil(np.hypot(dx, dy) / step)), 1)
            dt = 1.0 / n
            ok = True
            for m in range(n + 1):
                t = 1.0 if m == n else m * dt  # np.linspace(0, 1, n + 1)
                c = _clearance_at(ax + t * dx, ay + t * dy, clearance, origin, res)
                # the exact ends may sit off their cells' centres: judge the inside only
                if not c > floor or (0 < m < n and not c >= need - 1e-9):
                    ok = False
                    break
            if ok:
                j += 1
                lowest = lowest_next
            else:
                break
        kept[n_kept] = j
        n_kept += 1
        i = j
    return kept[:n_kept].copy()


def shortcut(costmap: Costmap, xy_m: ArrayLike) -> FloatArray:
    """Line-of-sight shortcutting of a path's vertices (K, 2) [m] -> (J, 2), J <= K."""
    xy = np.ascontiguousarray(xy_m, dtype=float)
    if len(xy) <= 2:
        return xy.copy()
    grid = costmap.grid
    kept = _shortcut_kept(
        xy,
        np.ascontiguousarray(costmap.clearance_m, dtype=float),
        np.asarray(grid.origin_m, dtype=float),
        float(grid.resolution_m),
        float(costmap.inflation_m),
    )
    return np.asarray(xy[kept])


def smooth_path(
    costmap: Costmap, xy_m: ArrayLike, *, radius_m: float = 0.5, max_halvings: int = 6
) -> PlanarPath:
    """Shortcut an A* path and round its corners, staying out of the inflated region.

    Parameters
    ----------
    costmap : Costmap
        The map the path was planned on.
    xy_m : array_like, shape (K, 2)
        The A* path's points [m] (:attr:`AStarResult.xy_m`), K >= 2 distinct ones.
    radius_m : float
        Largest corner radius [m].
    max_halvings : int
        How many times a corner's radius may be halved before the corner is left sharp.

    Returns
    -------
    PlanarPath
        Arc-length parametrised, heading continuous except at corners left sharp.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import astar, build_costmap
    >>> occ = np.zeros((40, 40), dtype=bool)  # 4 m x 4 m, empty
    >>> cm = build_costmap(OccupancyGrid(occ, ~occ, 0.1), inflation_m=0.2)
    >>> path = smooth_path(cm, astar(cm, [0.5, 0.5], [3.5, 3.5]).xy_m)
    >>> round(path.length_m, 6), len(path.length_m_pieces)  # one straight diagonal
    (4.242641, 1)
    """
    pts = shortcut(costmap, xy_m)
    radii = np.full(max(len(pts) - 2, 0), float(radius_m))
    step = costmap.grid.resolution_m / 4.0
    for attempt in range(max_halvings + 1):
        path = PlanarPath.from_polyline(pts, radii)
        n = max(int(np.ceil(path.length_m / step)), 1)
        s = np.linspace(0.0, path.length_m, n + 1)
        xy = path.pose_at(s)[:, :2]
        bad = clearance_along(costmap, xy) <= costmap.inflation_m
        bad[0] = bad[-1] = False
        if not bad.any() or len(radii) == 0:
            return path
        # which corners: the nearest vertex to each bad sample
        corners = pts[1:-1]
        d = np.hypot(
            xy[bad][:, None, 0] - corners[None, :, 0], xy[bad][:, None, 1] - corners[None, :, 1]
        )
        hit = np.unique(np.argmin(d, axis=1))
        radii[hit] = 0.0 if attempt == max_halvings - 1 else radii[hit] / 2.0
    return PlanarPath.from_polyline(pts, radii)
