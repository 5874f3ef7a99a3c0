"""Routes that keep a costmap's price through re-plans, and robots that make way."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from firefleet.control.navigation import (
    Costmap,
    NavigationInputs,
    NavigationParams,
    astar_cells,
    build_costmap,
    navigation_init,
    navigation_step,
)
from firefleet.control.navigation._makeway import cuts_path
from firefleet.control.navigation._team import _with_teammates
from firefleet.models import unicycle_step
from firefleet.world import OccupancyGrid

from ._nav_loop import lidar


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


def _passage(width_m: float = 1.0, res: float = 0.05) -> OccupancyGrid:
    """8 m x 3 m, walled, with one straight passage ``width_m`` wide along y = 1.5 m."""
    h, w = round(3.0 / res), round(8.0 / res)
    occ = _walled(h, w)
    half, mid = round(width_m / 2 / res), h // 2
    occ[1 : mid - half] = True
    occ[mid + half : -1] = True
    return OccupancyGrid(occ, ~occ, res)


def _drive(
    grid: OccupancyGrid, pose: np.ndarray, goals: np.ndarray, movable: np.ndarray, steps: int
) -> tuple[np.ndarray, float, list[tuple[str, ...]]]:
    params = NavigationParams()
    state = navigation_init(grid, pose, goals, params)
    least = np.inf
    seen = []
    for k in range(steps):
        ranges, bearings = lidar(grid, pose, params.robot_radius_m)
        inputs = NavigationInputs(
            pose.copy(), {"lidar": (ranges, bearings)}, pose[:, :2].copy(), k * 0.1, movable
        )
        state, v, w = navigation_step(state, inputs, params, 0.1)
        pose = unicycle_step(pose, v, w, 0.1)
        least = min(least, float(np.hypot(*(pose[0, :2] - pose[1, :2]))))
        seen.append(state.status)
        if state.status == ("arrived", "arrived") and not state.parked.any():  # type: ignore[union-attr]
            break
    return pose, least, seen


def test_a_robot_standing_in_a_1_m_passage_makes_way_and_goes_back() -> None:
    # robot 0 stands in the middle of the passage; robot 1 must pass it. With two radii
    # and the margins there is no room beside it: it moves to the passage's wall, the
    # other passes, and it goes back to its goal
    grid = _passage(1.0)
    pose = np.array([[4.0, 1.5, 0.0], [0.8, 1.5, 0.0]])
    goals = np.array([[4.0, 1.5], [7.2, 1.5]])
    params = NavigationParams()
    end, least, seen = _drive(grid, pose, goals, np.array([True, True]), 400)
    assert seen[-1] == ("arrived", "arrived")
    assert np.hypot(*(end[1, :2] - goals[1])) <= params.goal_tolerance_m
    assert np.hypot(*(end[0, :2] - goals[0])) <= params.goal_tolerance_m
    assert any(s[0] == "moving" for s in seen)  # it did move
    assert least > 2.0 * params.robot_radius_m  # no contact
    # a robot not marked movable stands for good: the other never gets past
    end, _, seen = _drive(grid, pose, goals, np.array([False, True]), 300)
    assert seen[-1][1] != "arrived"
    assert end[1, 0] < 4.0
    assert np.allclose(end[0, :2], pose[0, :2])


def test_cuts_path_agrees_with_a_plan_round_the_disc() -> None:
    # brute force: the way past a standing disc exists iff A* finds a path on the
    # costmap with the disc's cells occupied (the window holds the whole passage here)
    grid = _passage(1.0, res=0.05)
    params = NavigationParams()
    cm = build_costmap(grid, params.inflation_m)
    path = np.stack([np.linspace(3.0, 5.0, 41), np.full(41, 1.5)], axis=1)
    block = params.robot_radius_m + params.inflation_m
    for y in np.arange(1.2, 1.81, 0.05):
        xy = np.array([4.0, y])
        centres = grid.center_of(np.argwhere(np.ones(grid.shape, dtype=bool))).reshape(
            *grid.shape, 2
        )
        disc = np.hypot(centres[..., 0] - xy[0], centres[..., 1] - xy[1]) <= block
        cost = np.where(cm.blocked | disc, np.inf, 1.0)
        start, goal = tuple(grid.cell_of(path[0])), tuple(grid.cell_of(path[-1]))
        cells, _ = astar_cells(cost, start, goal, grid.resolution_m)
        assert cuts_path(cm, xy, block, path) == (cells is None), y


def test_the_maps_outside_is_a_wall_to_the_dynamic_window() -> None:
    # brute force: every cell of the map grown by one cell round it that is not free
    # (the outside never is) and has a free 4-neighbour, at its centre
    from firefleet.control.navigation._team import _wall_points

    occ = _walled(12, 16)
    occ[0, 5:9] = False  # a door in the map's top edge
    occ[4:8, 15] = False  # and one in its right edge
    grid = OccupancyGrid(occ, ~occ, 0.1, origin_m=(1.0, -2.0))
    h, w = occ.shape
    want = set()
    for r in range(-1, h + 1):
        for c in range(-1, w + 1):
            inside = 0 <= r < h and 0 <= c < w
            if inside and not occ[r, c]:
                continue
            for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                rr, cc = r + dr, c + dc
                if 0 <= rr < h and 0 <= cc < w and not occ[rr, cc]:
                    x = 1.0 + (c + 0.5) * 0.1
                    y = -2.0 + (h - r - 0.5) * 0.1
                    want.add((round(x, 9), round(y, 9)))
                    break
    got = {(round(x, 9), round(y, 9)) for x, y in _wall_points(grid)}
    assert got == want
    assert (round(1.0 + 6.5 * 0.1, 9), round(-2.0 + 12.5 * 0.1, 9)) in got  # past the door
