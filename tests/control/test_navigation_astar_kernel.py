"""A*'s kernel (``_astar._astar_kernel``: a fixed heap per search, searched again with a
larger one when it might overflow) against the kernel it replaced, kept here verbatim
(a heap grown in place): the same cells, total and count of expanded cells, bit for
bit, on random and uniform grids (ties broken the same way), a map priced like a fire's,
a heap too small (searched again), and the edges."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from numpy.typing import NDArray

from firefleet._typing import FloatArray, IntArray
from firefleet.control.navigation._astar import _astar_kernel, _search

# ---------------------------------------------------------------- the reference (before)


@numba.njit(cache=True)
def _ref_heap_push(
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
def _ref_heap_pop(keys: FloatArray, items: NDArray[np.int32], size: int) -> int:  # pragma: no cover
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
def _reference_kernel(
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
    parent = np.full(n, -1, dtype=np.int32)
    closed = np.zeros(n, dtype=np.bool_)
    cap = 1 << 16
    keys = np.empty(cap)
    items = np.empty(cap, dtype=np.int32)
    sq2 = math.sqrt(2.0)
    hd = res * (sq2 - 1.0)
    start = (sr + 1) * wp + sc + 1
    goal = (gr + 1) * wp + gc + 1
    g[start] = 0.0
    size = _ref_heap_push(keys, items, 0, 0.0, start)
    expanded = 0
    while size > 0:
        cur = items[0]
        size = _ref_heap_pop(keys, items, size)
        if closed[cur]:
            continue  # a stale entry (lazy deletion)
        closed[cur] = True
        expanded += 1
        if cur == goal:
            break
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
                if size == cap:
                    cap *= 2
                    keys2 = np.empty(cap)
                    items2 = np.empty(cap, dtype=np.int32)
                    keys2[:size] = keys[:size]
                    items2[:size] = items[:size]
                    keys = keys2
                    items = items2
                size = _ref_heap_push(keys, items, size, gn + hn, nxt)
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


# ---------------------------------------------------------------- the comparisons


def _same(cost: FloatArray, sr: int, sc: int, gr: int, gc: int, res: float, heap: int) -> int:
    """Assert the two kernels agree bit for bit; the cells expanded."""
    ref_cells, ref_total, ref_expanded = _reference_kernel(cost, sr, sc, gr, gc, res)
    cells, total, expanded = _astar_kernel(cost, sr, sc, gr, gc, res, heap)
    assert cells.dtype == ref_cells.dtype
    assert cells.shape == ref_cells.shape
    assert np.array_equal(cells, ref_cells)
    assert np.float64(total).tobytes() == np.float64(ref_total).tobytes()
    assert expanded == ref_expanded
    return int(expanded)


def _pairs(rng: np.random.Generator, cost: FloatArray, k: int) -> list[tuple[int, int, int, int]]:
    free = np.argwhere(np.isfinite(cost))
    picks = free[rng.integers(len(free), size=(k, 2))]
    return [(int(a[0]), int(a[1]), int(b[0]), int(b[1])) for a, b in picks]


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("heap", [1 << 16, 16])
def test_random_grids(seed: int, heap: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = int(rng.integers(5, 60)), int(rng.integers(5, 60))
    cost = 1.0 + 3.0 * rng.random((h, w))
    cost[rng.random((h, w)) < 0.3] = np.inf
    for sr, sc, gr, gc in _pairs(rng, cost, 8):
        _same(cost, sr, sc, gr, gc, 0.05, heap)


@pytest.mark.parametrize("heap", [1 << 16, 9, 40])
def test_uniform_grids_break_ties_alike(heap: int) -> None:
    """A uniform cost: many paths of equal cost, chosen by the heap's order of equal
    keys; and a few values only (0.5 m steps of cost), equal keys everywhere."""
    rng = np.random.default_rng(11)
    uniform = np.ones((40, 70))
    steps = 1.0 + 0.5 * rng.integers(0, 3, (40, 70)).astype(float)
    steps[rng.random((40, 70)) < 0.15] = np.inf
    for cost in (uniform, steps):
        for sr, sc, gr, gc in _pairs(rng, cost, 10):
            _same(cost, sr, sc, gr, gc, 0.1, heap)


def test_a_map_priced_like_a_fire() -> None:
    """An office-sized grid (200 x 400 at 0.05 m) with walls and a room priced 30 and
    300 per metre round a goal inside it: the search visits nearly every open cell (as
    mission-office's fighters' plans do); with a small first heap it is made again."""
    rng = np.random.default_rng(5)
    cost = 1.0 + 2.0 * np.exp(-rng.random((200, 400)) * 5.0)
    cost[:, 200] = np.inf
    cost[90:110, 200] = 1.0  # a door
    cost[100, 20:180] = np.inf
    rr, cc = np.mgrid[:200, :400]
    fire = np.hypot(rr - 80, cc - 300)
    cost[fire < 30] += 30.0
    cost[fire < 10] += 300.0
    expanded = _same(cost, 150, 30, 82, 302, 0.05, 1 << 16)
    assert expanded > 0.8 * np.isfinite(cost).sum()
    assert not _search(cost, 150, 30, 82, 302, 0.05, 64)[3]  # 64 entries overflow
    assert _same(cost, 150, 30, 82, 302, 0.05, 64) == expanded


def test_edges() -> None:
    one = np.ones((1, 1))
    _same(one, 0, 0, 0, 0, 1.0, 1 << 16)  # a single cell: start is goal
    row = np.ones((1, 9))
    _same(row, 0, 0, 0, 8, 0.5, 16)  # a corridor one cell wide
    _same(row, 0, 8, 0, 0, 0.5, 0)  # any first heap size (at least 16 is used)
    wall = np.ones((7, 7))
    wall[:, 3] = np.inf
    cells, total, _ = _astar_kernel(wall, 3, 0, 3, 6, 1.0)
    assert cells.shape == (0, 2)
    assert total == math.inf
    _same(wall, 3, 0, 3, 6, 1.0, 16)  # unreachable: every reachable cell expanded
    gap = np.ones((2, 2))
    gap[0, 0] = gap[1, 1] = np.inf  # a diagonal gap is no way
    _same(gap, 0, 1, 1, 0, 1.0, 1 << 16)
    border = np.ones((30, 30))
    _same(border, 0, 0, 29, 29, 0.05, 16)  # corner to corner along the padding
    _same(border, 29, 0, 0, 29, 0.05, 1 << 16)


def test_results_are_the_reference_types() -> None:
    cells, total, expanded = _astar_kernel(np.ones((3, 4)), 2, 0, 0, 3, 1.0)
    ref_cells, ref_total, ref_expanded = _reference_kernel(np.ones((3, 4)), 2, 0, 0, 3, 1.0)
    assert cells.tolist() == ref_cells.tolist() == [[2, 0], [1, 1], [1, 2], [0, 3]]
    assert isinstance(expanded, int)
    assert total == ref_total
    assert expanded == ref_expanded
