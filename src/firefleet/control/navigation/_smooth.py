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


def _segment_samples(a: FloatArray, b: FloatArray, step: float) -> FloatArray:
    n = max(int(np.ceil(np.hypot(*(b - a)) / step)), 1)
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    return np.asarray(a + t * (b - a))


def shortcut(costmap: Costmap, xy_m: ArrayLike) -> FloatArray:
    """Line-of-sight shortcutting of a path's vertices (K, 2) [m] -> (J, 2), J <= K."""
    xy = np.asarray(xy_m, dtype=float)
    if len(xy) <= 2:
        return xy.copy()
    step = costmap.grid.resolution_m / 4.0
    own = clearance_along(costmap, xy)
    floor = costmap.inflation_m
    kept = [0]
    i = 0
    while i < len(xy) - 1:
        j = i + 1
        lowest = min(own[i], own[j])
        while j + 1 < len(xy):
            lowest_next = min(lowest, own[j + 1])
            need = max(lowest_next, floor)
            samples = _segment_samples(xy[i], xy[j + 1], step)
            clear = clearance_along(costmap, samples)
            # the exact ends may sit off their cells' centres: judge the inside only
            if np.all(clear[1:-1] >= need - 1e-9) and np.all(clear > floor):
                j += 1
                lowest = lowest_next
            else:
                break
        kept.append(j)
        i = j
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
