"""The exploration's blocked nodes (``_explore._blocked_nodes``) decided by ``any_within``
equal the loop of ``np.hypot`` over the teammates it replaced, node for node."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._explore import _blocked_nodes
from firefleet.control.navigation import build_costmap
from firefleet.world import load_map


def _before(cm: CoarseMap, xy_m: np.ndarray, radius_m: float) -> np.ndarray:
    """_blocked_nodes as it was (the reference)."""
    if len(xy_m) == 0:
        return np.zeros(0, dtype=np.int64)
    k = math.ceil(radius_m / cm.cell_m) + 1
    dr, dc = np.mgrid[-k : k + 1, -k : k + 1]
    rc = cm.cell_of(xy_m)[:, None, :] + np.stack([dr.ravel(), dc.ravel()], axis=-1)[None]
    rc = rc.reshape(-1, 2)
    hc, wc = cm.shape
    rc = rc[(rc[:, 0] >= 0) & (rc[:, 0] < hc) & (rc[:, 1] >= 0) & (rc[:, 1] < wc)]
    centre = cm.centre_xy(rc)
    near = np.zeros(len(rc), dtype=bool)
    for p in xy_m:
        near |= np.hypot(centre[:, 0] - p[0], centre[:, 1] - p[1]) <= radius_m
    out: np.ndarray = np.unique(rc[near, 0] * wc + rc[near, 1])
    return out


def test_blocked_nodes_equal_the_loop_of_distances() -> None:
    """Teammates anywhere on the office (and off it), some a radius from a cell's centre
    to the last bit along an axis, some on a centre; 0-49 at a time."""
    grid = load_map("office")
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    rng = np.random.default_rng(4)
    x0, x1, y0, y1 = grid.extent_m
    edges = 0
    for _ in range(60):
        m = int(rng.integers(0, 50))
        xy = np.c_[rng.uniform(x0 - 0.5, x1 + 0.5, m), rng.uniform(y0 - 0.5, y1 + 0.5, m)]
        radius = float(rng.choice([0.35, 0.5, 0.6]))
        pick = rng.random(m) < 0.3
        centres = cm.centre_xy(cm.cell_of(xy[pick]))
        xy[pick] = centres + np.array([radius, 0.0])
        on = rng.random(m) < 0.1
        xy[on] = cm.centre_xy(cm.cell_of(xy[on]))
        got = _blocked_nodes(cm, xy, radius)
        want = _before(cm, xy, radius)
        assert got.dtype == want.dtype
        assert got.tobytes() == want.tobytes()
        edges += int(pick.sum())
    assert edges > 200


def test_blocked_nodes_edges_are_their_runs_in_the_graph() -> None:
    """The edges _travel closes (every edge leaving a blocked node) are the
    concatenation of the nodes' runs ``indptr[b]:indptr[b + 1]`` it was written as."""
    grid = load_map("office")
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    ptr = cm.graph.indptr
    rng = np.random.default_rng(8)
    for _ in range(20):
        blocked = np.unique(rng.integers(0, len(ptr) - 1, int(rng.integers(1, 200))))
        want = np.concatenate([np.arange(ptr[b], ptr[b + 1]) for b in blocked])
        first, many = ptr[blocked], ptr[blocked + 1] - ptr[blocked]
        got = np.repeat(first - (np.cumsum(many) - many), many) + np.arange(many.sum())
        assert got.tolist() == want.tolist()
