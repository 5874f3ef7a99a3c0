"""A fighter held by the flame guard sprays its way on (``_fight.fight_through``),
against the cone's water by hand and the bearing by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._fight import fight_through, flame_guard
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._water import cone_cells
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid

P = TacticsParams()


def _open(h: int = 40, w: int = 40) -> CoarseMap:
    walls = np.zeros((h, w), dtype=bool)
    return coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)


def test_facing_the_flame_it_sprays_the_cone_with_one_period_of_flow() -> None:
    cm = _open()
    pose = np.array([4.0, 5.0, 0.0])
    flame = np.array([[4.6, 5.0]])  # 0.6 m dead ahead, inside the 0.8 m guard
    w, on, wet = fight_through(pose, flame, np.zeros((0, 0)), cm, P)
    assert on
    assert w == pytest.approx(0.0, abs=1e-12)
    rows, cols = cone_cells(cm, pose, P.spray_range_m, P.spray_half_angle_rad)
    litres = P.flow_l_s * P.nav_period_s
    # every cell of the cone got an equal share, nothing elsewhere
    assert wet[rows, cols] == pytest.approx(np.full(len(rows), litres / (len(rows) * 0.0625)))
    assert wet.sum() * 0.0625 == pytest.approx(litres)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_off_the_cone_it_turns_to_the_nearest_flame_and_holds_its_water(side: float) -> None:
    cm = _open()
    pose = np.array([4.0, 5.0, 0.0])
    near = np.array([4.0 + 0.5 * math.cos(0.8), 5.0 + side * 0.5 * math.sin(0.8)])
    far = np.array([4.0, 5.0 - side * 0.75])  # farther, on the other side
    w, on, wet = fight_through(pose, np.array([far, near]), np.zeros((0, 0)), cm, P)
    assert not on
    assert wet.shape == (0, 0)
    w_max = P.nav.dwa.omega_max_rad_s
    assert w == pytest.approx(side * min(P.face_gain * 0.8, w_max))


def test_no_flame_in_the_guard_or_every_cell_soaked_no_spray() -> None:
    cm = _open()
    pose = np.array([4.0, 5.0, 0.0])
    w, on, _ = fight_through(pose, np.array([[6.0, 5.0]]), np.zeros((0, 0)), cm, P)
    assert (w, on) == (0.0, False)
    soaked = np.full(cm.shape, P.soak_l_m2)
    w, on, wet = fight_through(pose, np.array([[4.6, 5.0]]), soaked, cm, P)
    assert not on
    assert wet is soaked


def _hallway() -> CoarseMap:
    """A 0.5 m wall at x = 2.0-2.5 m with a door at y = 4-5 m, on a 0.05 m map."""
    occ = np.zeros((120, 100), dtype=bool)  # 6 m x 5 m
    occ[:, 40:50] = True
    occ[20:40, 40:50] = False  # rows from the top: y = 4-5 m
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.05)
    return coarse_map(build_costmap(grid, 0.1), 0.25)


def test_a_flame_behind_a_wall_does_not_hold_a_robot_one_on_its_side_does() -> None:
    cm = _hallway()
    w_max = P.nav.dwa.omega_max_rad_s
    half = math.radians(60.0)
    pose = np.array([[1.75, 2.0, 0.0]])  # facing the wall (east), driving on
    inside = np.array([[2.45, 2.1]])  # 0.71 m, in the wall's far half (a deep detection)
    near = np.array([[2.1, 2.1]])  # 0.36 m, in the wall's near half: its face, this side
    for flames, held in ((inside, False), (near, True)):
        v, _ = flame_guard(np.array([0.3]), np.zeros(1), pose, flames, 0.8, half, w_max, cm)
        assert (v[0] == 0.0) == held
        v_all, _ = flame_guard(np.array([0.3]), np.zeros(1), pose, flames, 0.8, half, w_max)
        assert v_all[0] == 0.0  # without the map every flame holds (the rule before)
    # in the door (y = 4-5 m) a flame just past the wall's line holds: in sight
    at_door = np.array([[1.6, 4.5, 0.0]])
    door_flame = np.array([[2.3, 4.5]])
    v, _ = flame_guard(np.array([0.3]), np.zeros(1), at_door, door_flame, 0.8, half, w_max, cm)
    assert v.tolist() == [0.0]


def test_held_it_faces_the_flame_in_sight_not_a_nearer_one_behind_the_wall() -> None:
    cm = _hallway()
    pose = np.array([1.75, 4.1, 0.0])  # in the door's mouth, by its south jamb
    hidden = np.array([2.3, 3.6])  # 0.74 m, south-east, in the wall south of the door
    seen = np.array([1.9, 4.85])  # 0.76 m, north, in the open
    flames = np.array([hidden, seen])
    w, on, _ = fight_through(pose, flames, np.zeros((0, 0)), cm, P)
    assert not on
    bearing = math.atan2(seen[1] - pose[1], seen[0] - pose[0])  # 1.37 rad, left
    assert w == pytest.approx(min(P.face_gain * bearing, P.nav.dwa.omega_max_rad_s))
    # the hidden one alone holds nothing
    assert fight_through(pose, hidden[None], np.zeros((0, 0)), cm, P)[:2] == (0.0, False)


def test_a_fighter_without_a_valid_slot_goes_to_the_nearest_free_cell() -> None:
    from firefleet.control.mission._fight import _nearest_cell

    cm = _open()
    free = np.zeros(cm.shape, dtype=bool)
    free[10, 30] = free[30, 10] = True  # two free cells, by hand
    to = np.array([[7.0, 7.0], [2.0, 1.0], [np.nan, np.nan]])
    fallback = np.array([[0.0, 0.0], [0.0, 0.0], [7.6, 7.4]])
    got = _nearest_cell(cm, free, to, fallback)
    near_a = cm.goal_xy(np.array([[10, 30]]))[0]  # (7.625, 7.375)
    near_b = cm.goal_xy(np.array([[30, 10]]))[0]  # (2.625, 2.375)
    assert got[0] == pytest.approx(near_a)
    assert got[1] == pytest.approx(near_b)
    assert got[2] == pytest.approx(near_a)  # NaN: nearest its fallback
    none = _nearest_cell(cm, np.zeros(cm.shape, dtype=bool), to, fallback)
    assert none == pytest.approx(fallback)
