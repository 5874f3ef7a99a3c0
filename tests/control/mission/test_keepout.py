"""The team's hot places on the navigation's costmap (``_keepout``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from firefleet.control.mission import TacticsParams, tactics_init
from firefleet.control.mission._keepout import heat_costmap
from firefleet.control.navigation import astar
from firefleet.world import OccupancyGrid


def _two_ways() -> OccupancyGrid:
    """10 m x 6 m, walled, a block in the middle: a way round it north and south."""
    res = 0.05
    occ = np.zeros((120, 200), dtype=bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[40:80, 60:140] = True  # y 2-4 m, x 3-7 m
    return OccupancyGrid(occ, ~occ, res)


def test_live_hot_places_are_priced_and_paths_go_round_them() -> None:
    grid = _two_ways()
    params = TacticsParams()
    pose = np.array([[1.0, 3.0, 0.0]])
    state = tactics_init(grid, pose, params)
    base = state.nav.costmap
    start, goal = np.array([1.0, 3.0]), np.array([9.0, 3.0])
    first = astar(base, start, goal)
    assert first.xy_m is not None
    south = bool(np.mean(first.xy_m[:, 1]) < 3.0)
    # a live hot place on the way A* took, a forgotten one on the other
    hot = np.array([[5.0, 1.0 if south else 5.0], [5.0, 5.0 if south else 1.0]])
    state = replace(state, hot_xy_m=hot, hot_s=np.array([100.0, 0.0]), t_s=110.0)
    priced = heat_costmap(state, params).nav.costmap
    # brute force: hot_cost more on the open cells within hot_keepout_m of the live one
    rr, cc = np.nonzero(np.ones(grid.shape, dtype=bool))
    centres = grid.center_of(np.stack([rr, cc], axis=1)).reshape(*grid.shape, 2)
    near = np.hypot(*(centres - hot[0]).transpose(2, 0, 1)) <= params.hot_keepout_m
    want = np.where(near & ~base.blocked, base.cost + params.hot_cost, base.cost)
    assert np.array_equal(priced.cost, want)
    second = astar(priced, start, goal)
    assert second.xy_m is not None
    assert bool(np.mean(second.xy_m[:, 1]) < 3.0) != south  # the other way round
    # the goal in the hot place itself is still reached, the price paid once
    into = astar(priced, start, hot[0])
    assert into.found
    # every place forgotten: the costmap as it was
    state = replace(state, t_s=200.0)
    assert heat_costmap(state, params).nav.costmap is base


def test_a_teammate_that_makes_way_does_not_block_the_explorers_travel() -> None:
    """A 0.5 m passage with a teammate in its middle: blocking, the candidates beyond it
    are out of reach; marked passable (it stands and makes way), the travel equals the
    travel with no teammate there at all."""
    from firefleet.control.mission._coverage import coarse_map
    from firefleet.control.mission._explore import _travel
    from firefleet.control.mission._views import view_table
    from firefleet.control.navigation import build_costmap

    occ = np.ones((40, 200), bool)
    occ[15:25, 2:198] = False
    cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    table = view_table(cm, 4.0, 2.0)
    start = np.array([[1.0, 1.0]])
    mates = np.array([[1.0, 1.0], [5.0, 1.0]])
    away = np.array([[1.0, 1.0], [105.0, 1.0]])
    who = np.array([0])
    alone = _travel(cm, table, start, away, who, 0.35, np.inf)
    blocked = _travel(cm, table, start, mates, who, 0.35, np.inf, np.array([True, True]))
    passing = _travel(cm, table, start, mates, who, 0.35, np.inf, np.array([True, False]))
    x = table.xy_m[:, 0]
    assert np.isinf(blocked[0, x > 5.5]).all()
    assert np.array_equal(passing, alone)
    assert np.isfinite(passing).all()
