"""floor100 (mission-large's storey): size and resolution, every room reachable from the
entrance lobby by a robot of radius 0.15 m (flood fill on the planner's inflated map),
door widths measured on the shipped file, and A* across the floor."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from firefleet.control.navigation import NavigationParams, astar, build_costmap
from firefleet.world import load_map
from firefleet.world._floor100 import floor100_rooms

ROBOT_RADIUS_M = 0.15


def test_size_resolution_and_the_map_server_file() -> None:
    grid = load_map("floor100")
    assert grid.shape == (400, 400)
    assert grid.resolution_m == 0.25
    assert grid.origin_m == (0.0, 0.0)
    assert (grid.width_m, grid.height_m) == (100.0, 100.0)
    assert not (grid.occupied & grid.free).any()
    assert (grid.occupied | grid.free).all()
    # the outer wall is closed all round
    assert grid.occupied[[0, -1], :].all()
    assert grid.occupied[:, [0, -1]].all()
    # the 84 rooms, 4 halls (2 doors a side: 16 rows) and the lobby
    rooms = floor100_rooms()
    assert rooms.shape == (84 + 16 + 1, 6)


def test_every_room_is_reachable_from_the_entrance() -> None:
    """Flood fill (4-connected, so stricter than A*'s 8 neighbours) from the lobby's
    centre over the cells the planner lets a robot's centre enter: every room's whole
    standable floor belongs to it."""
    grid = load_map("floor100")
    inflation = NavigationParams(robot_radius_m=ROBOT_RADIUS_M).inflation_m
    costmap = build_costmap(grid, inflation_m=inflation)
    labels, _ = ndi.label(~costmap.blocked)
    rooms = floor100_rooms()
    lobby = grid.cell_of(rooms[-1, 4:6])
    reach = labels == labels[lobby[0], lobby[1]]
    assert labels[lobby[0], lobby[1]] > 0
    h = grid.shape[0]
    for x0, x1, y0, y1, _, _ in rooms:
        block = np.s_[h - round(y1 * 4) : h - round(y0 * 4), round(x0 * 4) : round(x1 * 4)]
        standable = ~costmap.blocked[block]
        assert standable.sum() > 0.4 * standable.size  # a room, not a sliver
        assert reach[block][standable].all(), (x0, x1, y0, y1)
    # and nothing standable lies outside the lobby's component
    assert np.array_equal(reach, ~costmap.blocked)


def test_doors_are_one_metre_and_halls_two() -> None:
    """Along each door's wall, inside its room's span, the one gap is the door."""
    grid = load_map("floor100")
    rooms = floor100_rooms()
    widths = []
    for x0, x1, _, _, door_x, door_y in rooms[:-1]:
        xs = np.arange(x0 + 0.125, x1, 0.25)
        wall = grid.occupied_at(np.stack([xs, np.full(xs.size, door_y)], axis=-1))
        gap = xs[~wall]
        assert gap.min() < door_x < gap.max()
        widths.append(gap.size * 0.25 if gap.size * 0.25 < 5.0 else np.nan)
    widths_arr = np.asarray(widths)
    # rooms: one 1 m door; hall walls: two 2 m doors each (4 m of gap on the wall)
    assert np.count_nonzero(widths_arr == 1.0) == 84
    assert np.count_nonzero(widths_arr == 4.0) == 16


@pytest.mark.parametrize("goal", [(88.5, 95.0), (11.5, 45.0), (3.0, 3.0)])
def test_astar_from_the_lobby_across_the_floor(goal: tuple[float, float]) -> None:
    grid = load_map("floor100")
    costmap = build_costmap(grid, inflation_m=ROBOT_RADIUS_M + 0.05)
    plan = astar(costmap, (50.0, 3.0), goal)
    assert plan.status == "ok"
    assert plan.xy_m is not None
    length = float(np.sum(np.hypot(*np.diff(plan.xy_m, axis=0).T)))
    # at least the Manhattan distance along the corridors' grid minus the diagonals
    # across rooms, at most 1.5 times it
    straight = float(np.hypot(goal[0] - 50.0, goal[1] - 3.0))
    assert straight <= length <= 1.5 * (abs(goal[0] - 50.0) + abs(goal[1] - 3.0))
