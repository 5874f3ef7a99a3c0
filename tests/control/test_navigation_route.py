"""Routes that keep a costmap's price through re-plans, and robots that make way."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from firefleet.control.navigation import (
    Costmap,
    NavigationParams,
    build_costmap,
    navigation_init,
)
from firefleet.control.navigation._team import _with_teammates
from firefleet.world import OccupancyGrid


def _walled(h: int, w: int) -> np.ndarray:
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return occ


def test_teammates_discs_keep_the_price_of_a_priced_costmap() -> None:
    # brute force: build_costmap of the map with the discs' cells occupied, plus the
    # static costmap's price (a fire's, on the mission) wherever the result is open
    occ = _walled(60, 80)
    occ[20:40, 40] = True
    grid = OccupancyGrid(occ, ~occ, 0.05)
    params = NavigationParams()
    static = build_costmap(
        grid, params.inflation_m, wall_weight=params.wall_weight, wall_decay_m=params.wall_decay_m
    )
    price = np.zeros(grid.shape)
    price[10:50, 30:60] = 20.0
    price[25:35, 45:55] += 200.0
    cost = np.where(static.blocked, np.inf, static.cost + price)
    priced = Costmap(grid, static.clearance_m, static.blocked, cost, static.inflation_m)
    state = navigation_init(grid, [[0.5, 0.5, 0.0]], [[1.0, 0.5]], params)
    state = replace(state, costmap=priced)
    discs = np.array([[2.2, 1.5], [3.4, 2.4], [0.6, 2.0]])
    got = _with_teammates(state, params, discs)
    centres = grid.center_of(np.argwhere(np.ones(grid.shape, dtype=bool))).reshape(*grid.shape, 2)
    on = np.zeros(grid.shape, dtype=bool)
    for xy in discs:
        on |= np.hypot(centres[..., 0] - xy[0], centres[..., 1] - xy[1]) <= params.robot_radius_m
    ref = build_costmap(
        OccupancyGrid(occ | on, ~(occ | on), 0.05),
        params.inflation_m,
        wall_weight=params.wall_weight,
        wall_decay_m=params.wall_decay_m,
    )
    want = np.where(ref.blocked, np.inf, ref.cost + price)
    assert np.array_equal(got.blocked, ref.blocked)
    open_ = ~ref.blocked
    assert np.allclose(got.cost[open_], want[open_], rtol=0.0, atol=1e-9)
    assert np.isinf(got.cost[~open_]).all()
