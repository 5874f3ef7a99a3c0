"""navigation's teammates' costmap with the discs' windows compiled (``_disc_window``)
equals the form before it (``grid.cell_of``, ``np.mgrid``, ``grid.center_of`` and
``np.hypot`` per teammate) bit for bit."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy import ndimage

from firefleet.control.navigation import Costmap, NavigationParams, navigation_init
from firefleet.control.navigation._team import NavigationState, _wall_extra, _with_teammates
from firefleet.world import OccupancyGrid, load_map


def _before(state: NavigationState, params: NavigationParams, others_xy: np.ndarray) -> Costmap:
    """_with_teammates as it was (the reference)."""
    static = state.costmap
    grid = static.grid
    res = grid.resolution_m
    h, w = grid.shape
    occ = np.array(~grid.free)
    clearance = np.array(static.clearance_m)
    cost = np.array(static.cost)
    reach = params.robot_radius_m + params.inflation_m + 20.0 * params.wall_decay_m
    k = math.ceil(reach / res) + 1
    windows = []
    for xy in np.asarray(others_xy, dtype=float).reshape(-1, 2):
        r, c = (int(v) for v in grid.cell_of(xy))
        r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, h), max(c - k, 0), min(c + k + 1, w)
        if r0 >= r1 or c0 >= c1:
            continue
        rr, cc = np.mgrid[r0:r1, c0:c1]
        centres = grid.center_of(np.stack([rr, cc], axis=-1))
        disc = np.hypot(centres[..., 0] - xy[0], centres[..., 1] - xy[1]) <= params.robot_radius_m
        if not disc.any():
            continue
        occ[r0:r1, c0:c1] |= disc
        near = np.asarray(ndimage.distance_transform_edt(~disc)) * res
        np.minimum(clearance[r0:r1, c0:c1], near, out=clearance[r0:r1, c0:c1])
        windows.append((r0, r1, c0, c1))
    blocked = clearance <= params.inflation_m
    for r0, r1, c0, c1 in windows:
        cw = clearance[r0:r1, c0:c1]
        base = static.cost[r0:r1, c0:c1]
        add = base - 1.0 - _wall_extra(static.clearance_m[r0:r1, c0:c1], params)
        add = np.where(np.isfinite(base) & (add > 1e-9), add, 0.0)
        cost[r0:r1, c0:c1] = np.where(
            blocked[r0:r1, c0:c1] | ~np.isfinite(base),
            np.inf,
            1.0 + _wall_extra(cw, params) + add,
        )
    teamed = OccupancyGrid(occ, grid.free & ~occ, grid.resolution_m, grid.origin_m, grid.name)
    return Costmap(teamed, clearance, blocked, cost, float(params.inflation_m))


def test_teammates_costmap_equals_the_form_before() -> None:
    """The office and a small grid off the origin: teammates anywhere, by the map's
    edges and off it, on cell edges and corners (where a centre's distance is the
    radius to the last bit), in groups of 1-12."""
    rng = np.random.default_rng(5)
    params = NavigationParams()
    small = np.zeros((50, 70), dtype=bool)
    small[20:30, 30] = True
    grids = [load_map("office"), OccupancyGrid(small, ~small, 0.05, (-1.3, 0.7))]
    checked = 0
    for grid in grids:
        state = navigation_init(grid, [[1.0, 1.0, 0.0]], [[1.5, 1.0]], params)
        res = grid.resolution_m
        x0, x1, y0, y1 = grid.extent_m
        for _ in range(25):
            m = int(rng.integers(1, 13))
            xy = np.c_[rng.uniform(x0 - 0.5, x1 + 0.5, m), rng.uniform(y0 - 0.5, y1 + 0.5, m)]
            # some on a cell's corner or edge, some a radius off a centre along an axis
            snap = rng.random(m) < 0.4
            xy[snap] = np.round(xy[snap] / (0.5 * res)) * (0.5 * res)
            ax = rng.random(m) < 0.2
            centre = grid.center_of(grid.cell_of(xy[ax]))
            xy[ax] = centre + np.array([params.robot_radius_m, 0.0])
            got = _with_teammates(state, params, xy)
            want = _before(state, params, xy)
            assert got.grid.occupied.tobytes() == want.grid.occupied.tobytes()
            assert got.grid.free.tobytes() == want.grid.free.tobytes()
            for name in ("clearance_m", "blocked", "cost"):
                assert getattr(got, name).tobytes() == getattr(want, name).tobytes(), name
            assert got.inflation_m == want.inflation_m
            checked += 1
        # no teammate, and one off the map
        for xy in (np.zeros((0, 2)), np.array([[x1 + 50.0, y1 + 50.0]])):
            got = _with_teammates(state, params, xy)
            assert got.cost.tobytes() == _before(state, params, xy).cost.tobytes()
    assert checked == 50
    # a priced costmap (the fires' price) keeps its price the same way
    state = navigation_init(grids[0], [[1.0, 1.0, 0.0]], [[1.5, 1.0]], params)
    static = state.costmap
    price = np.zeros(static.cost.shape)
    price[40:120, 100:300] = 20.0
    priced = Costmap(static.grid, static.clearance_m, static.blocked, static.cost + price, 0.2)
    state = replace(state, costmap=priced)
    xy = np.array([[6.0, 3.0], [7.0, 3.5], [12.0, 6.0]])
    assert _with_teammates(state, params, xy).cost.tobytes() == (
        _before(state, params, xy).cost.tobytes()
    )
