"""8-connected A* on a costmap, compiled (numba) with a binary heap.

Moving from cell ``a`` to a neighbour ``b`` costs ``step * (cost[a] + cost[b]) / 2``
with ``step`` the resolution (4 sides) or ``sqrt(2)`` times it (4 diagonals); a diagonal
move needs both cells it passes between to be open too, so no path cuts a corner or
slips through a diagonal gap in a wall. The heuristic is the octile distance times the
smallest cost per metre (1), admissible and consistent, so the path is optimal. Ties
in ``f`` are broken towards the larger ``g`` (nearer the goal), which expands fewer
cells on open floors. The heap holds stale entries (lazy deletion) instead of a
decrease-key.

References
----------
Hart, Nilsson, Raphael, "A formal basis for the heuristic determination of minimum cost
paths", IEEE Trans. SSC 4(2), 1968.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray, IntArray
from firefleet.control.navigation._costmap import Costmap
from firefleet.errors import InputError

__all__ = ["AStarResult", "astar", "astar_cells"]

_SQRT2 = math.sqrt(2.0)


@numba.njit(cache=True)
def _heap_push(
    keys: FloatArray, ties: FloatArray, items: IntArray, size: int, k: float, t: float, item: int
) -> int:  # pragma: no cover - compiled
    i = size
    keys[i] = k
    ties[i] = t
    items[i] = item
    while i > 0:
        p = (i - 1) // 2
        if keys[p] < keys[i] or (keys[p] == keys[i] and ties[p] <= ties[i]):
            break
        keys[p], keys[i] = keys[i], keys[p]
        ties[p], ties[i] = ties[i], ties[p]
        items[p], items[i] = items[i], items[p]
        i = p
    return size + 1


@numba.njit(cache=True)
def _heap_pop(keys: FloatArray, ties: FloatArray, items: IntArray, size: int) -> int:
    # pragma: no cover - compiled; moves the last entry to the root and sifts it down
    size -= 1
    keys[0] = keys[size]
    ties[0] = ties[size]
    items[0] = items[size]
    i = 0
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        c = left
        right = left + 1
        if right < size and (
            keys[right] < keys[left] or (keys[right] == keys[left] and ties[right] < ties[left])
        ):
            c = right
        if keys[i] < keys[c] or (keys[i] == keys[c] and ties[i] <= ties[c]):
            break
        keys[c], keys[i] = keys[i], keys[c]
        ties[c], ties[i] = ties[i], ties[c]
        items[c], items[i] = items[i], items[c]
        i = c
    return size


@numba.njit(cache=True)
def _astar_kernel(
    cost: FloatArray, sr: int, sc: int, gr: int, gc: int, res: float
) -> tuple[IntArray, float, int]:  # pragma: no cover - compiled
    """Cells (K, 2) of the cheapest path, its cost [m], cells expanded; K = 0 if none."""
    h, w = cost.shape
    # a padded flat copy: one border of blocked cells spares the bounds checks
    wp = w + 2
    n = (h + 2) * wp
    cf = np.full(n, np.inf)
    for r in range(h):
        for c in range(w):
            cf[(r + 1) * wp + c + 1] = cost[r, c]
    g = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=np.bool_)
    cap = 4096
    keys = np.empty(cap)
    ties = np.empty(cap)
    items = np.empty(cap, dtype=np.int64)
    offs = np.array([-wp - 1, -wp, -wp + 1, -1, 1, wp - 1, wp, wp + 1])
    diag = (True, False, True, False, False, True, False, True)
    sq2 = math.sqrt(2.0)
    start = (sr + 1) * wp + sc + 1
    goal = (gr + 1) * wp + gc + 1
    g[start] = 0.0
    dy0 = abs(sr - gr)
    dx0 = abs(sc - gc)
    h0 = res * (max(dx0, dy0) + (sq2 - 1.0) * min(dx0, dy0))
    size = _heap_push(keys, ties, items, 0, h0, h0, start)
    expanded = 0
    while size > 0:
        cur = items[0]
        size = _heap_pop(keys, ties, items, size)
        if closed[cur]:
            continue
        closed[cur] = True
        expanded += 1
        if cur == goal:
            break
        gcur = g[cur]
        ccur = cf[cur]
        for k in range(8):
            nxt = cur + offs[k]
            cn = cf[nxt]
            if cn == np.inf or closed[nxt]:
                continue
            step = res
            if diag[k]:
                # no corner cutting: both cells the diagonal passes between must be open
                o = offs[k]
                dcol = 1 if (o == -wp + 1 or o == wp + 1) else -1
                if cf[cur + dcol] == np.inf or cf[nxt - dcol] == np.inf:
                    continue
                step = res * sq2
            gn = gcur + step * 0.5 * (ccur + cn)
            if gn < g[nxt]:
                g[nxt] = gn
                parent[nxt] = cur
                nr = nxt // wp
                ddy = abs(nr - 1 - gr)
                ddx = abs(nxt - nr * wp - 1 - gc)
                hn = res * (max(ddx, ddy) + (sq2 - 1.0) * min(ddx, ddy))
                if size == cap:
                    cap *= 2
                    keys2 = np.empty(cap)
                    ties2 = np.empty(cap)
                    items2 = np.empty(cap, dtype=np.int64)
                    keys2[:size] = keys[:size]
                    ties2[:size] = ties[:size]
                    items2[:size] = items[:size]
                    keys, ties, items = keys2, ties2, items2
                size = _heap_push(keys, ties, items, size, gn + hn, hn, nxt)
    if not closed[goal]:
        return np.empty((0, 2), dtype=np.int64), np.inf, expanded
    count = 1
    cur = goal
    while cur != start:
        cur = parent[cur]
        count += 1
    out = np.empty((count, 2), dtype=np.int64)
    cur = goal
    for i in range(count - 1, -1, -1):
        rr = cur // wp
        out[i, 0] = rr - 1
        out[i, 1] = cur - rr * wp - 1
        cur = parent[cur]
    return out, g[goal], expanded


def astar_cells(
    cost: ArrayLike, start: tuple[int, int], goal: tuple[int, int], resolution_m: float = 1.0
) -> tuple[IntArray | None, float]:
    """The cheapest 8-connected path between two cells of a cost grid.

    Parameters
    ----------
    cost : array_like, shape (H, W)
        Cost per metre of each cell (>= 1); ``inf`` (or NaN) where blocked.
    start, goal : tuple of int
        ``(row, col)`` cells.
    resolution_m : float
        Cell side [m].

    Returns
    -------
    cells : ndarray of int64, shape (K, 2), or None
        ``(row, col)`` from start to goal; None when the goal cannot be reached (or
        either end is blocked).
    total : float
        The path's cost (``inf`` when None) [m of cost].

    Examples
    --------
    >>> import numpy as np
    >>> cells, total = astar_cells(np.ones((3, 4)), (2, 0), (0, 3))
    >>> cells.tolist(), round(total, 6)  # 1 straight + 2 diagonals: 1 + 2 sqrt(2)
    ([[2, 0], [1, 1], [1, 2], [0, 3]], 3.828427)
    """
    c = np.ascontiguousarray(cost, dtype=np.float64)
    if c.ndim != 2:
        raise InputError(f"cost must be an (H, W) grid, got shape {c.shape}")
    c = np.where(np.isnan(c), np.inf, c)
    h, w = c.shape
    for name, (r, col) in (("start", start), ("goal", goal)):
        if not (0 <= r < h and 0 <= col < w):
            raise InputError(f"{name} cell {(r, col)} is off the {h} x {w} grid")
    if not (np.isfinite(c[start]) and np.isfinite(c[goal])):
        return None, math.inf
    cells, total, _ = _astar_kernel(c, start[0], start[1], goal[0], goal[1], float(resolution_m))
    if cells.shape[0] == 0:
        return None, math.inf
    return cells, float(total)


@dataclass(frozen=True, eq=False)
class AStarResult:
    """What the global planner found.

    Attributes
    ----------
    status : str
        ``"ok"``; ``"start_blocked"`` or ``"goal_blocked"`` (the point lies in the
        inflated region or off the map); ``"unreachable"`` (no path joins them).
    cells : ndarray of int64, shape (K, 2), or None
        ``(row, col)`` of the path, start to goal; None unless ``status == "ok"``.
    xy_m : ndarray, shape (K, 2), or None
        The cells' centres [m], with the exact start and goal points at the two ends.
    cost : float
        The path's cost (``inf`` unless ok).
    """

    status: str
    cells: IntArray | None
    xy_m: FloatArray | None
    cost: float

    @property
    def found(self) -> bool:
        """Whether a path was found."""
        return self.status == "ok"


def astar(costmap: Costmap, start_xy_m: ArrayLike, goal_xy_m: ArrayLike) -> AStarResult:
    """Plan from a point to a point [m] on a costmap.

    Parameters
    ----------
    costmap : Costmap
        The inflated map (:func:`build_costmap`).
    start_xy_m, goal_xy_m : array_like, shape (2,)
        World positions [m].

    Returns
    -------
    AStarResult
        Its ``status`` says which end is blocked, or that the goal is unreachable.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> occ = np.zeros((20, 20), dtype=bool)
    >>> occ[:, 10] = True  # a wall across the map: nothing joins the two halves
    >>> cm = build_costmap(OccupancyGrid(occ, ~occ, 0.1), inflation_m=0.15)
    >>> astar(cm, [0.3, 1.0], [1.7, 1.0]).status
    'unreachable'
    >>> astar(cm, [0.3, 1.0], [0.3, 1.8]).status, astar(cm, [1.0, 1.0], [0.3, 1.0]).status
    ('ok', 'start_blocked')
    """
    grid = costmap.grid
    ends = np.stack(
        [
            np.asarray(start_xy_m, dtype=float).reshape(2),
            np.asarray(goal_xy_m, dtype=float).reshape(2),
        ]
    )
    if not np.isfinite(ends).all():
        raise InputError(f"start and goal must be finite (x, y) [m], got {ends.tolist()}")
    rc = grid.cell_of(ends)
    inside = grid.contains(ends)
    h, w = grid.shape
    for k, name in enumerate(("start", "goal")):
        r, c = int(np.clip(rc[k, 0], 0, h - 1)), int(np.clip(rc[k, 1], 0, w - 1))
        if not inside[k] or costmap.blocked[r, c]:
            return AStarResult(f"{name}_blocked", None, None, math.inf)
    cost = np.ascontiguousarray(costmap.cost)
    cells, total, _ = _astar_kernel(
        cost, int(rc[0, 0]), int(rc[0, 1]), int(rc[1, 0]), int(rc[1, 1]), grid.resolution_m
    )
    if cells.shape[0] == 0:
        return AStarResult("unreachable", None, None, math.inf)
    xy = grid.center_of(cells)
    xy[0] = ends[0]
    xy[-1] = ends[1]
    return AStarResult("ok", cells, xy, float(total))
