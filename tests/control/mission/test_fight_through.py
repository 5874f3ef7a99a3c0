"""A fighter held by the flame guard sprays its way on (``_fight.fight_through``),
against the cone's water by hand and the bearing by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._fight import fight_through
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
