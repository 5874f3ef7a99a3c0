"""Explorers and the fires the team believes: no viewpoint behind a flame."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from firefleet.control.mission import MODES, TacticsParams, tactics_init
from firefleet.control.mission._step import _plan
from firefleet.world import OccupancyGrid
from tests.control.mission.test_team import FAST_NAV

EXPLORE, FIGHT = MODES.index("explore"), MODES.index("fight")


def two_rooms() -> OccupancyGrid:
    """12 m x 10 m, a wall at x = 6 m with a 1 m door at y = 4.5-5.5 m (5 cm cells)."""
    occ = np.zeros((200, 240), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:, 119:121] = True
    occ[90:110, 119:121] = False  # rows 90-110: y 4.5-5.5 m
    return OccupancyGrid(occ, ~occ, 0.05, name="two-rooms")


def test_no_explorer_is_sent_through_a_door_the_team_believes_burning() -> None:
    """West room searched, a flame believed in the door (soaked by the ledger): the
    explorer gets no viewpoint in the east room, whose only way in is the door (the
    house, seed 2: an explorer sent so was damaged in the burning door at 280 s). With
    no flame there, it is sent east."""
    p = TacticsParams(nav=FAST_NAV, fire_robots_min=1, fire_robots_max=1, explore_frac=0.0)
    pose = np.array([[2.0, 5.0, 0.0], [2.0, 3.0, 0.0]])
    state = replace(tactics_init(two_rooms(), pose, p), t_s=10.0)
    cm = state.coarse
    west = cm.centre_xy(np.argwhere(np.ones(cm.shape, bool)))[:, 0] < 6.0
    covered = west.reshape(cm.shape) & cm.floor
    door = np.array([[6.0, 5.0]])
    k = state.knowledge
    wet = np.zeros(cm.shape)
    r, c = cm.cell_of(door)[0]
    wet[r, c] = 2.0 * p.soak_l_m2  # the team soaked it
    k = replace(
        k,
        spot_xy_m=door,
        spot_fire=np.zeros(1, np.int64),
        spot_flame=np.ones(1, bool),
        spot_misses=np.zeros(1, np.int64),
        next_fire=1,
        wet_l_m2=wet,
    )
    tank = np.full(2, p.tank_l)
    working = np.ones(2, bool)
    burning = _plan(replace(state, knowledge=k, covered_coarse=covered), pose, tank, working, p)
    explorer = np.flatnonzero(burning.mode == EXPLORE)
    assert len(np.flatnonzero(burning.mode == FIGHT)) == 1
    goals = burning.goal_xy_m
    # nothing left to search on its side: idle, or a viewpoint in the west room
    assert not np.any(goals[explorer, 0] > 6.0)
    # the same with the door's spot gone out (no flame): the explorer goes east
    out = replace(k, spot_xy_m=np.zeros((0, 2)), spot_fire=np.zeros(0, np.int64),
                  spot_flame=np.zeros(0, bool), spot_misses=np.zeros(0, np.int64))  # fmt: skip
    clear = _plan(replace(state, knowledge=out, covered_coarse=covered), pose, tank, working, p)
    assert (clear.mode == EXPLORE).sum() == 2
    assert np.all(clear.goal_xy_m[:, 0] > 6.0)


def test_a_refiller_stops_short_of_a_burning_door_on_its_way() -> None:
    """A fighter empties its small tank on a fire in the only door between it and the
    refill point: as a refiller it is held by the flame guard short of the flames (it
    drove through them before: a school wing, seed 1, damaged at 423 s), and with its
    tank empty it does not spray its way on."""
    from tests.control.mission._harness import World

    p = TacticsParams(
        nav=FAST_NAV,
        soak_l_m2=1e9,
        fire_robots_min=1,
        fire_robots_max=1,
        explore_frac=0.0,
        sensing_range_m=6.0,
        tank_l=1.0,
        flow_l_s=0.5,
        refill_xy_m=(2.0, 5.0),
    )
    world = World(two_rooms(), p, np.array([[8.5, 5.0, np.pi]]), fire_xy=np.array([[6.0, 5.0]]),
                  water_l=1e9)  # fmt: skip
    world.run(60.0)
    mode = np.array([e["mode"][0] for e in world.log])
    pose = np.array([e["pose"][0] for e in world.log])
    refill = mode == MODES.index("refill")
    assert refill.any(), "it never went to refill"
    d = np.hypot(pose[refill, 0] - 6.0, pose[refill, 1] - 5.0)
    assert d.min() > 0.5 * p.flame_guard_m
    assert np.all(pose[:, 0] > 6.0)  # it never passed the door
