"""8-connected A* on a costmap, compiled (numba) with a binary heap.

Moving from cell ``a`` to a neighbour ``b`` costs ``step * (cost[a] + cost[b]) / 2``
with ``step`` the resolution (4 sides) or ``sqrt(2)`` times it (4 diagonals); a diagonal
move needs both cells it passes between to be open too, so no path cuts a corner or
slips through a diagonal gap in a wall. The heuristic is the octile distance times the
smallest cost per metre (1), admissible and consistent, so the path is optimal. The
heap holds stale entries (lazy deletion) instead of a decrease-key; the grid is copied
once into a flat array with a blocked border, so the inner loop checks no bounds.

References
----------
Hart, Nilsson, Raphael, "A formal basis for the heuristic determination of minimum cost
paths", IEEE Trans. SSC 4(2), 1968.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray, IntArray
from firefleet.control.navigation._costmap import Costmap
from firefleet.errors import InputError

__all__ = ["AStarResult", "astar", "astar_cells"]

_MEMO_SIZE = 64
"""Most plans :func:`astar` keeps per costmap (``Costmap._astar_memo``; the oldest goes)."""


@numba.njit(cache=True)
def _heap_push(
    keys: FloatArray, items: NDArray[np.int32], size: int, key: float, item: int
) -> int:  # pragma: no cover - compiled
    """Insert into the binary min-heap ``keys[:size]`` (a hole sifted up); new size."""
    i = size
    while i > 0:
        p = (i - 1) >> 1
        if keys[p] <= key:
            break
        keys[i] = keys[p]
        items[i] = items[p]
        i = p
    keys[i] = key
    items[i] = item
    return size + 1


@numba.njit(cache=True)
def _heap_pop(keys: FloatArray, items: NDArray[np.int32], size: int) -> int:  # pragma: no cover
    """Remove the root (the last entry sifted down from the top); new size."""
    size -= 1
    key = keys[size]
    item = items[size]
    i = 0
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and keys[c + 1] < keys[c]:
            c += 1
        if key <= keys[c]:
            break
        keys[i] = keys[c]
        items[i] = items[c]
        i = c
    keys[i] = key
    items[i] = item
    return size


@numba.njit(cache=True)
def _search(
    cost: FloatArray, sr: int, sc: int, gr: int, gc: int, res: float, cap: int
) -> tuple[IntArray, float, int, bool]:  # pragma: no cover - compiled
    """:func:`_astar_kernel` with a heap of ``cap`` entries; the last value is False
    (and the rest no answer) when an expansion might overflow it.

    The heap is never grown in place: an array variable assigned again inside the loop
    costs the loop ~15 % (reference counts), and the search with a larger heap makes
    the same heap operations in the same order, so it is searched again instead."""
    h, w = cost.shape
    # a padded flat copy: one border of blocked cells spares the bounds checks
    wp = w + 2
    n = (h + 2) * wp
    cf = np.full(n, np.inf)
    for r in range(h):
        for c in range(w):
            cf[(r + 1) * wp + c + 1] = cost[r, c]
    g = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int32)
    closed = np.zeros(n, dtype=np.bool_)
    keys = np.empty(cap)
    items = np.empty(cap, dtype=np.int32)
    sq2 = math.sqrt(2.0)
    hd = res * (sq2 - 1.0)
    start = (sr + 1) * wp + sc + 1
    goal = (gr + 1) * wp + gc + 1
    g[start] = 0.0
    size = _heap_push(keys, items, 0, 0.0, start)
    expanded = 0
    while size > 0:
        cur = items[0]
        size = _heap_pop(keys, items, size)
        if closed[cur]:
            continue  # a stale entry (lazy deletion)
        closed[cur] = True
        expanded += 1
        if cur == goal:
            break
        if size + 8 > cap:  # eight pushes might not fit
            return np.empty((0, 2), dtype=np.int64), np.inf, expanded, False
        gcur = g[cur]
        ccur = cf[cur]
        for k in range(8):
            # neighbours: 0 1 2 / 3 . 4 / 5 6 7
            if k == 0:
                o = -wp - 1
            elif k == 1:
                o = -wp
            elif k == 2:
                o = -wp + 1
            elif k == 3:
                o = -1
            elif k == 4:
                o = 1
            elif k == 5:
                o = wp - 1
            elif k == 6:
                o = wp
            else:
                o = wp + 1
            nxt = cur + o
            cn = cf[nxt]
            if cn == np.inf or closed[nxt]:
                continue
            step = res
            if k == 0 or k == 2 or k == 5 or k == 7:
                # no corner cutting: both cells the diagonal passes between must be open
                dcol = 1 if (k == 2 or k == 7) else -1
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
                hn = res * max(ddx, ddy) + hd * min(ddx, ddy)
                size = _heap_push(keys, items, size, gn + hn, nxt)
    if not closed[goal]:
        return np.empty((0, 2), dtype=np.int64), np.inf, expanded, True
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
    return out, g[goal], expanded, True


@numba.njit(cache=True)
def _astar_kernel(
    cost: FloatArray, sr: int, sc: int, gr: int, gc: int, res: float, heap: int = 1 << 16
) -> tuple[IntArray, float, int]:  # pragma: no cover - compiled
    """Cells (K, 2) of the cheapest path, its cost [m], cells expanded; K = 0 if none.

    ``heap`` is the first heap's size (entries); a search that might outgrow it is made
    again with four times as many (:func:`_search`)."""
    cap = max(heap, 16)
    while True:
        out, total, expanded, done = _search(cost, sr, sc, gr, gc, res, cap)
        if done:
            return out, total, expanded
        cap *= 4


def _check_size(shape: tuple[int, ...]) -> None:
    if (shape[0] + 2) * (shape[1] + 2) >= 2**31:
        raise InputError(f"a {shape[0]} x {shape[1]} grid is too large to plan on (< 2^31 cells)")


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
    _check_size(c.shape)
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


def _frozen(a: NDArray[Any]) -> bool:
    """Whether an array's values cannot change: it and every array it views are
    read-only, down to one that owns its data."""
    base: object = a
    while isinstance(base, np.ndarray):
        if base.flags.writeable:
            return False
        base = base.base
    return base is None


def _astar_memoised(costmap: Costmap, sr: int, sc: int, gr: int, gc: int) -> tuple[IntArray, float]:
    """:func:`_astar_kernel`'s cells (a new array) and total on ``costmap``, kept in
    the costmap when its cost cannot change (:class:`Costmap`'s notes): the kernel is a
    function of the cost grid, the two cells and the resolution alone."""
    memo = costmap._astar_memo
    frozen = _frozen(costmap.cost)
    key = (sr, sc, gr, gc)
    if frozen and key in memo:
        cells, total = memo[key]
        return np.array(cells), total
    cost = np.ascontiguousarray(costmap.cost)
    _check_size(cost.shape)
    cells, total, _ = _astar_kernel(cost, sr, sc, gr, gc, costmap.grid.resolution_m)
    total = float(total)
    if frozen:
        if len(memo) >= _MEMO_SIZE:
            del memo[next(iter(memo))]
        memo[key] = (cells.copy(), total)
    return cells, total


def adopt_plans(costmap: Costmap, other: Costmap) -> None:
    """Give ``costmap`` the plans kept in ``other`` (``Costmap._astar_memo``) when it
    has none of its own and the two plan alike: both cost grids frozen and equal
    element for element, at the same resolution (the kernel reads nothing else)."""
    if costmap._astar_memo or not other._astar_memo:
        return
    if costmap.grid.resolution_m != other.grid.resolution_m:
        return
    if not (_frozen(costmap.cost) and _frozen(other.cost)):
        return
    if costmap.cost is other.cost or np.array_equal(costmap.cost, other.cost):
        costmap._astar_memo.update(other._astar_memo)


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
    cells, total = _astar_memoised(
        costmap, int(rc[0, 0]), int(rc[0, 1]), int(rc[1, 0]), int(rc[1, 1])
    )
    if cells.shape[0] == 0:
        return AStarResult("unreachable", None, None, math.inf)
    xy = grid.center_of(cells)
    xy[0] = ends[0]
    xy[-1] = ends[1]
    return AStarResult("ok", cells, xy, float(total))
