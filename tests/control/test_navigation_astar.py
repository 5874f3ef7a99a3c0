"""A* on the inflated costmap and the smoothing of its paths."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import scipy.sparse
from scipy.sparse.csgraph import dijkstra

from firefleet.control.navigation import (
    astar,
    astar_cells,
    build_costmap,
    clearance_along,
    smooth_path,
)
from firefleet.errors import InputError
from firefleet.planning import Trajectory
from firefleet.planning.planar import PlanarPath
from firefleet.world import OccupancyGrid


def _graph(cost: np.ndarray, res: float) -> scipy.sparse.csr_matrix:
    """The same graph as the kernel, written independently: every edge listed."""
    h, w = cost.shape
    rows, cols, vals = [], [], []
    for r in range(h):
        for c in range(w):
            if not np.isfinite(cost[r, c]):
                continue
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    nr, nc = r + dr, c + dc
                    if (dr, dc) == (0, 0) or not (0 <= nr < h and 0 <= nc < w):
                        continue
                    if not np.isfinite(cost[nr, nc]):
                        continue
                    if dr and dc and not (np.isfinite(cost[r, nc]) and np.isfinite(cost[nr, c])):
                        continue
                    step = res * (math.sqrt(2.0) if dr and dc else 1.0)
                    rows.append(r * w + c)
                    cols.append(nr * w + nc)
                    vals.append(step * 0.5 * (cost[r, c] + cost[nr, nc]))
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(h * w, h * w))


def _random_rooms(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    for _ in range(4):
        if rng.random() < 0.5:
            r = int(rng.integers(5, h - 5))
            occ[r, :] = True
            for door in rng.integers(2, w - 8, size=2):
                occ[r, door : door + 6] = False
        else:
            c = int(rng.integers(5, w - 5))
            occ[:, c] = True
            for door in rng.integers(2, h - 8, size=2):
                occ[door : door + 6, c] = False
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return occ


@pytest.mark.parametrize("seed", range(6))
def test_astar_cost_equals_dijkstra_on_random_grids(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = 18, 23
    cost = 1.0 + 3.0 * rng.random((h, w))
    cost[rng.random((h, w)) < 0.3] = np.inf
    free = np.argwhere(np.isfinite(cost))
    graph = _graph(cost, 0.1)
    for _ in range(5):
        s, g = free[rng.choice(len(free), 2, replace=False)]
        ref = dijkstra(graph, indices=s[0] * w + s[1])[g[0] * w + g[1]]
        cells, total = astar_cells(cost, tuple(s), tuple(g), 0.1)
        if not np.isfinite(ref):
            assert cells is None
            assert total == math.inf
            continue
        assert cells is not None
        assert total == pytest.approx(ref, rel=1e-12)
        # the cells form a legal walk whose cost is the total
        steps = np.diff(cells, axis=0)
        assert np.all(np.abs(steps).max(axis=1) == 1)
        walk = sum(graph[a[0] * w + a[1], b[0] * w + b[1]] for a, b in itertools.pairwise(cells))
        assert walk == pytest.approx(ref, rel=1e-12)


def test_octile_distance_on_an_empty_grid() -> None:
    cells, total = astar_cells(np.ones((50, 60)), (45, 3), (7, 50), 0.05)
    dx, dy = 47, 38
    assert total == pytest.approx(0.05 * (max(dx, dy) + (math.sqrt(2) - 1) * min(dx, dy)))
    assert cells is not None
    assert cells[0].tolist() == [45, 3]
    assert cells[-1].tolist() == [7, 50]


def test_no_corner_cutting_through_a_diagonal_gap() -> None:
    cost = np.ones((2, 2))
    cost[0, 0] = cost[1, 1] = np.inf  # the two open cells touch only at a corner
    assert astar_cells(cost, (0, 1), (1, 0)) == (None, math.inf)


def test_unreachable_and_blocked_ends_are_reported() -> None:
    occ = np.zeros((30, 30), dtype=bool)
    occ[:, 15] = True
    cm = build_costmap(OccupancyGrid(occ, ~occ, 0.1), inflation_m=0.2)
    assert astar(cm, [0.5, 1.5], [2.5, 1.5]).status == "unreachable"
    assert astar(cm, [1.5, 1.5], [2.5, 1.5]).status == "start_blocked"  # next to the wall
    assert astar(cm, [0.5, 1.5], [1.45, 1.5]).status == "goal_blocked"
    assert astar(cm, [0.5, 1.5], [9.0, 1.5]).status == "goal_blocked"  # off the map
    res = astar(cm, [0.5, 0.5], [0.5, 2.5])
    assert res.found
    assert res.cells is not None
    assert res.xy_m is not None
    assert res.xy_m[0].tolist() == [0.5, 0.5]
    assert res.xy_m[-1].tolist() == [0.5, 2.5]


def test_inflation_is_an_exact_disc_and_the_outside_a_wall() -> None:
    occ = np.zeros((61, 61), dtype=bool)
    occ[30, 30] = True
    cm = build_costmap(OccupancyGrid(occ, ~occ, 0.05), inflation_m=0.5)
    rr, cc = np.mgrid[:61, :61]
    centre_distance = 0.05 * np.hypot(rr - 30, cc - 30)
    # the map's outside is occupied too: one cell beyond each edge
    edge_distance = 0.05 * (np.minimum(np.minimum(rr, cc), np.minimum(60 - rr, 60 - cc)) + 1)
    assert np.array_equal(cm.blocked, (centre_distance <= 0.5) | (edge_distance <= 0.5))
    assert cm.blocked[30, 9]  # 10 cells from the outside
    assert not cm.blocked[30, 10]  # 11 cells
    # the wall cost falls off with the clearance and is 1 + weight at the edge
    assert np.all(np.isinf(cm.cost[cm.blocked]))
    assert cm.cost[30, 41] == pytest.approx(1.0 + 2.0 * math.exp(-(0.55 - 0.5) / 0.1))


@pytest.mark.parametrize("seed", range(4))
def test_paths_avoid_the_inflated_region_and_smoothing_keeps_clearance(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    occ = _random_rooms(rng, 80, 100)
    cm = build_costmap(OccupancyGrid(occ, ~occ, 0.05), inflation_m=0.12)
    free = np.argwhere(~cm.blocked)
    found = 0
    for _ in range(6):
        a, b = cm.grid.center_of(free[rng.choice(len(free), 2, replace=False)])
        res = astar(cm, a, b)
        if not res.found:
            continue
        found += 1
        assert res.cells is not None
        assert res.xy_m is not None
        assert not cm.blocked[res.cells[:, 0], res.cells[:, 1]].any()
        path = smooth_path(cm, res.xy_m)
        s = np.linspace(0.0, path.length_m, int(path.length_m / 0.005) + 2)
        pose = path.pose_at(s)
        assert clearance_along(cm, pose[:, :2]).min() > cm.inflation_m
        assert np.allclose(pose[0, :2], a)
        assert np.allclose(pose[-1, :2], b)
        # smoothing shortens the path and never lengthens it past A*'s
        astar_length = np.hypot(*np.diff(res.xy_m, axis=0).T).sum()
        assert path.length_m <= astar_length + 1e-9
        # continuous position (no jumps larger than the sample spacing)
        assert np.hypot(*np.diff(pose[:, :2], axis=0).T).max() <= s[1] - s[0] + 1e-9
    assert found >= 2


def test_smoothing_rounds_a_corner_and_falls_back_near_walls() -> None:
    # an L-shaped corridor 0.6 m wide: the corner cannot take a 0.5 m radius arc
    occ = np.ones((60, 60), dtype=bool)
    occ[5:55, 5:17] = False  # vertical leg
    occ[43:55, 5:55] = False  # horizontal leg at the bottom
    cm = build_costmap(OccupancyGrid(occ, ~occ, 0.05), inflation_m=0.2)
    res = astar(cm, [0.55, 2.4], [2.5, 0.55])
    assert res.found
    assert res.xy_m is not None
    path = smooth_path(cm, res.xy_m, radius_m=2.0)
    s = np.linspace(0.0, path.length_m, 4000)
    assert clearance_along(cm, path.pose_at(s)[:, :2]).min() > cm.inflation_m
    assert np.any(path.curvature_1_m != 0.0)  # a corner was rounded


def test_planar_path_analytic_shapes() -> None:
    # a full circle as four quarter arcs of a square with radius = half side
    r = 1.0
    path = PlanarPath.from_polyline([[0, 0], [2, 0], [2, 2]], radius_m=r)
    assert path.length_m == pytest.approx(1.0 + math.pi / 2 + 1.0)
    s = np.linspace(1.0, 1.0 + math.pi / 2, 7)
    pose = path.pose_at(s)
    # the arc's centre is (1, 1): every point at distance r, heading = the arc angle
    assert np.allclose(np.hypot(pose[:, 0] - 1.0, pose[:, 1] - 1.0), r)
    assert np.allclose(pose[:, 2], s - 1.0)
    assert np.allclose(path.curvature_at(s[1:-1]), 1.0 / r)
    # arc length: summed chords of a fine sampling
    fine = path.pose_at(np.linspace(0.0, path.length_m, 20001))
    assert np.hypot(*np.diff(fine[:, :2], axis=0).T).sum() == pytest.approx(path.length_m, rel=1e-8)
    # projection of the arc's centre region and of points beside the lines
    s_p, d_p = path.project([[1.0 + 0.5 * math.cos(-0.3), 1.0 + 0.5 * math.sin(-0.3)], [0.5, -0.2]])
    assert s_p[0] == pytest.approx(1.0 + math.pi / 2 - 0.3)
    assert d_p[0] == pytest.approx(0.5)
    assert d_p[1] == pytest.approx(0.2)
    assert s_p[1] == pytest.approx(0.5)


def test_planar_path_right_turn_and_trajectory() -> None:
    path = PlanarPath.from_polyline([[0, 0], [0, -3], [3, -3]], radius_m=0.5)
    # heading -pi/2 then 0: a left turn seen from above, curvature > 0
    assert path.curvature_1_m.tolist() == [0.0, 2.0, 0.0]
    right = PlanarPath.from_polyline([[0, 0], [3, 0], [3, -3]], radius_m=0.5)
    assert right.curvature_1_m.tolist() == [0.0, -2.0, 0.0]
    end = right.pose_at(right.length_m)
    assert np.allclose(end, [3.0, -3.0, -math.pi / 2])
    # Trajectory takes any path with sample() and length_m (annotated PolynomialPath)
    traj = Trajectory.from_paths([right], pieces=10, duration_s=10.0)  # type: ignore[list-item]
    assert traj.points.shape == (1, 11, 3)
    assert np.allclose(traj.points[0, -1], end)


def test_bad_inputs_raise() -> None:
    occ = np.zeros((5, 5), dtype=bool)
    grid = OccupancyGrid(occ, ~occ, 0.1)
    with pytest.raises(InputError, match="inflation_m"):
        build_costmap(grid, -0.1)
    with pytest.raises(InputError, match="start cell"):
        astar_cells(np.ones((3, 3)), (5, 0), (0, 0))
    with pytest.raises(InputError, match="two distinct points"):
        PlanarPath.from_polyline([[1.0, 1.0], [1.0, 1.0]])
