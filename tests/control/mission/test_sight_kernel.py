"""control/mission/_coverage.py's compiled line of sight equals its array form (the
samples, the cells, the ends excepted) on the office's coarse map."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import CoarseMap, coarse_map, line_of_sight
from firefleet.control.navigation import build_costmap
from firefleet.world import load_map


def _array_form(cm: CoarseMap, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The NumPy line of sight the kernel replaced (the reference)."""
    seg = np.hypot(*(b - a).T)
    n = max(2, math.ceil(float(seg.max()) / (0.5 * cm.cell_m)) + 1)
    s = np.linspace(0.0, 1.0, n)
    pts = a[:, None] + s[None, :, None] * (b - a)[:, None]
    rc = cm.cell_of(pts)
    blocked = cm.opaque[rc[..., 0], rc[..., 1]]
    along = s[None] * seg[:, None]
    ends = (along < cm.cell_m) | (along > seg[:, None] - cm.cell_m)
    out: np.ndarray = ~np.any(blocked & ~ends, axis=1)
    return out


def test_compiled_line_of_sight_equals_the_array_form() -> None:
    grid = load_map("office")
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    rng = np.random.default_rng(15)
    x0, x1, y0, y1 = grid.extent_m
    for m in (1, 7, 400):  # segments of every length, ends off the map too
        a = np.c_[rng.uniform(x0 - 0.5, x1 + 0.5, m), rng.uniform(y0 - 0.5, y1 + 0.5, m)]
        b = a + rng.normal(0.0, 3.0, (m, 2))
        got = line_of_sight(cm, a, b)
        want = _array_form(cm, a, b)
        np.testing.assert_array_equal(got, want)
    assert 0 < int(want.sum()) < len(want)  # both answers among them
    # a point to itself: nothing between
    assert line_of_sight(cm, a[:1], a[:1]).tolist() == [True]


def test_compiled_coarse_cells_equal_the_grids_cells() -> None:
    """CoarseMap.cell_of (compiled for finite points) is the grid's cell floored by the
    factor and clipped, on and off the map, on cell edges, in any batch shape."""
    grid = load_map("office")
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    rng = np.random.default_rng(3)
    x0, x1, y0, y1 = grid.extent_m
    pts = np.c_[rng.uniform(x0 - 2, x1 + 2, 3000), rng.uniform(y0 - 2, y1 + 2, 3000)]
    edges = grid.center_of(rng.integers(0, 40, (500, 2))) + 0.5 * grid.resolution_m
    pts = np.vstack([pts, edges, edges - 0.5 * grid.resolution_m]).reshape(2, -1, 5, 2)
    hc, wc = cm.shape
    rc = grid.cell_of(pts) // cm.factor
    want = np.stack([np.clip(rc[..., 0], 0, hc - 1), np.clip(rc[..., 1], 0, wc - 1)], -1)
    got = cm.cell_of(pts)
    assert got.dtype == want.dtype
    np.testing.assert_array_equal(got, want)
    assert cm.cell_of(pts[0, 0, 0]).tolist() == want[0, 0, 0].tolist()  # one point
    assert cm.cell_of(np.zeros((0, 2))).shape == (0, 2)
    nan = np.array([[np.nan, 1.0], [2.0, 3.0]])  # not finite: NumPy's path
    with np.errstate(invalid="ignore"):  # NumPy's cast of NaN warns
        assert cm.cell_of(nan)[1].tolist() == cm.cell_of(nan[1]).tolist()
