"""Refillers wait clear of a hot refill spot (``control.mission._refill``): which spots
are hot (the boundary by hand), where a hot spot's refiller waits (clear of every hot
place, nearest by travel: a Dijkstra of its own over the plan's cells) and that one
with no clear place in reach stays where it is."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._refill import refill_goals
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid
from tests._dijkstra import grid_dijkstra

CELL_M = 0.25


def _floor(h: int = 12, w: int = 24) -> tuple[np.ndarray, CoarseMap]:
    """An open floor of h x w cells of 0.25 m, with a wall across it at columns 11-12
    (a door at rows 4-7 only, counted from the top)."""
    occ = np.zeros((h, w), dtype=bool)
    occ[:, 11:13] = True
    occ[4:8, 11:13] = False
    grid = OccupancyGrid(occ, ~occ, resolution_m=CELL_M)
    return occ, coarse_map(build_costmap(grid, 0.1), CELL_M)


def _centre(r: int, c: int, h: int) -> tuple[float, float]:
    return ((c + 0.5) * CELL_M, (h - r - 0.5) * CELL_M)


def _travel(occ: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """8-connected Dijkstra over free cells, diagonals sqrt(2) cells, no corner cut."""
    return grid_dijkstra(~occ, start, CELL_M)


def test_a_spot_clear_by_clear_m_is_kept_and_a_nearer_one_moves() -> None:
    """Hot place at (1.0, 1.5); clear_m 1.25 m: a spot 1.25 m away (exact in binary) is
    clear and kept as it is; one 1.0 m away is hot and moves at least 1.25 m from it."""
    _, cm = _floor()
    away = np.array([[1.0, 1.5]])
    spots = np.array([[2.25, 1.5], [2.0, 1.5]])
    goals = refill_goals(cm, spots, away, 1.25, spots)
    assert goals[0].tolist() == [2.25, 1.5]
    assert not np.allclose(goals[1], spots[1])
    assert math.hypot(goals[1, 0] - 1.0, goals[1, 1] - 1.5) >= 1.25
    # nothing to avoid: every refiller goes to its spot
    assert refill_goals(cm, spots, np.zeros((0, 2)), 1.25, spots).tolist() == spots.tolist()


def test_a_hot_spots_refiller_waits_at_the_nearest_clear_place_by_travel() -> None:
    """A spot just west of the wall with the west room hot near the wall: the nearest
    clear cell (by its own Dijkstra, every free cell tried) is where the refiller
    waits; the place found is a cell centre as far by travel as that one."""
    occ, cm = _floor()
    h = occ.shape[0]
    away = np.array([[2.0, 1.0], [2.0, 2.0]])
    spot_rc = (10, 10)  # near the bottom, west of the wall
    spot = np.array([_centre(*spot_rc, h)])
    goal = refill_goals(cm, spot, away, 1.0, spot)[0]
    dist = _travel(occ, spot_rc)
    free = np.argwhere(~occ)
    xy = np.array([_centre(int(r), int(c), h) for r, c in free])
    clear = (
        np.hypot(xy[:, None, 0] - away[None, :, 0], xy[:, None, 1] - away[None, :, 1]).min(axis=1)
        >= 1.0
    )
    best = dist[free[clear, 0], free[clear, 1]].min()
    r = h - 1 - int(goal[1] / CELL_M)
    c = int(goal[0] / CELL_M)
    assert np.allclose(goal, _centre(r, c, h))
    assert dist[r, c] == best
    assert np.hypot(*(away - goal).T).min() >= 1.0


def test_with_no_clear_place_in_reach_the_refiller_stays_where_it_is() -> None:
    """Hot places every 0.5 m over the whole floor, clear_m 1 m: no clear cell; the
    refiller's goal is where it stands, not a point in the heat."""
    _, cm = _floor()
    away = np.array([[x, y] for x in np.arange(0.0, 6.01, 0.5) for y in np.arange(0.0, 3.01, 0.5)])
    spots = np.array([[1.125, 1.125]])
    here = np.array([[1.6, 0.9]])
    assert refill_goals(cm, spots, away, 1.0, here).tolist() == here.tolist()


def test_an_empty_tank_goes_to_the_refill_point_nearest_by_travel() -> None:
    """Two refill points on a 10 m x 3 m floor cut by a wall at x = 5 m with a door at
    its north end (y 2.4-3 m): point A at (1, 0.5), point B at (6.5, 0.5). A robot at
    (4.6, 0.5), west of the wall, is 1.9 m from B in a straight line and 3.6 m from A,
    but B is over 5 m away through the door: it goes to A. A robot at (5.4, 0.5), east
    of the wall, goes to B (the nearer both ways). Each goal is one of its point's
    spots (within ``refill_radius_m``)."""
    from firefleet.control.mission import TacticsParams, tactics_init
    from firefleet.control.mission._upkeep import tank_changes

    grid = _two_rooms()
    points = ((1.0, 0.5), (6.5, 0.5))
    params = TacticsParams(refill_xy_m=points)
    poses = np.array([[4.6, 0.5, 0.0], [5.4, 0.5, 0.0]])
    state = tactics_init(grid, poses, params)
    assert sorted(set(state.refill_group.tolist())) == [0, 1]
    state = tank_changes(state, poses, np.zeros(2), np.ones(2, dtype=bool), params)
    want = np.array(points)
    for i, k in enumerate((0, 1)):
        spot = int(state.refill_spot[i])
        assert state.refill_group[spot] == k
        goal = state.goal_xy_m[i]
        assert math.hypot(*(goal - want[k])) <= params.refill_radius_m


def test_an_empty_tank_passes_a_hot_refill_point_for_a_clear_one() -> None:
    """The two-room floor, the robot east of the wall at (5.4, 0.5): B at (6.5, 0.5) is
    nearer, but a hot place the team marked 1 m from B (live: marked now) makes B hot
    (within ``standoff_m``), so it goes to A through the door; the hot place forgotten
    (``hot_forget_s`` later), B again. With B the only point it reaches (the door shut),
    it goes to B hot or not (it waits there: ``refill_wait``)."""
    from dataclasses import replace

    from firefleet.control.mission import TacticsParams, tactics_init
    from firefleet.control.mission._upkeep import tank_changes

    points = ((1.0, 0.5), (6.5, 0.5))
    params = TacticsParams(refill_xy_m=points)
    pose = np.array([[5.4, 0.5, 0.0]])

    def group_of(grid: OccupancyGrid, t_s: float) -> int:
        state = tactics_init(grid, pose, params)
        state = replace(state, hot_xy_m=np.array([[6.5, 1.5]]), hot_s=np.array([10.0]), t_s=t_s)
        state = tank_changes(state, pose, np.zeros(1), np.ones(1, dtype=bool), params)
        return int(state.refill_group[state.refill_spot[0]])

    assert group_of(_two_rooms(), 10.0) == 0  # B hot: A
    assert group_of(_two_rooms(), 10.0 + params.hot_forget_s + 1.0) == 1  # forgotten: B
    shut = _two_rooms()
    occ = shut.occupied.copy()
    occ[:, 50] = True  # the wall from floor to ceiling: A unreachable
    assert group_of(OccupancyGrid(occ, ~occ, resolution_m=0.1), 10.0) == 1


def _two_rooms() -> OccupancyGrid:
    """10 m x 3 m at 0.1 m, outer walls, a wall at x = 5 m from y = 0 to y = 2.4 m."""
    occ = np.zeros((30, 100), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    occ[6:, 50] = True  # rows from the top: the wall from y = 0 to y = 2.4 m
    return OccupancyGrid(occ, ~occ, resolution_m=0.1)


def test_robots_fill_up_at_either_refill_point() -> None:
    """The two-room floor, robots with empty tanks on either side of the wall (the
    kinematic harness: tanks fill while the team says ``refilling``): within 60 s both
    tanks are 95 % full (the team calls a tank full a little short of it), each filled
    within ``refill_radius_m`` of its side's point (the second point's spots count as
    at a point, not only the first point's)"""
    from firefleet.control.mission import TacticsParams
    from tests.control.mission._harness import World

    points = np.array([[1.0, 0.5], [6.5, 0.5]])
    params = TacticsParams(refill_xy_m=((1.0, 0.5), (6.5, 0.5)))
    world = World(_two_rooms(), params, np.array([[3.0, 1.0, 0.0], [8.0, 1.0, np.pi]]))
    world.tank[:] = 0.0
    where: list[list[np.ndarray]] = [[], []]
    for _ in range(600):
        world.step()
        for j in map(int, np.flatnonzero(world.state.refilling)):
            where[j].append(world.pose[j, :2].copy())
        if (world.tank >= 0.95 * params.tank_l).all():
            break
    assert (world.tank >= 0.95 * params.tank_l).all()
    for i, k in enumerate((0, 1)):
        at = np.asarray(where[i])
        assert len(at) > 0
        assert np.hypot(*(at - points[k]).T).max() <= params.refill_radius_m + 0.05
