"""Fighting a fire: the ring, refilling, a damaged robot replaced; finding victims."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from firefleet.control.mission import MODES, TacticsParams, tactics_init
from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._fight import dry_flames
from firefleet.control.mission._knowledge import (
    behind_water,
    empty_knowledge,
    update_knowledge,
)
from firefleet.control.mission._water import spray_ledger
from firefleet.control.navigation import build_costmap
from firefleet.world import FireParams, OccupancyGrid, SprayParams, fire_init, spray_step
from tests.control.mission._harness import World
from tests.control.mission.test_team import FAST_NAV, room

FIGHT, REFILL, DAMAGED, EXPLORE = (
    MODES.index(m) for m in ("fight", "refill", "damaged", "explore")
)
FIRE = np.array([[6.0, 5.0]])
NEVER = 1e9
"""Water per area [L/m^2] (``soak_l_m2``) and litres (``water_l``) a fire that never goes
out takes: the team never believes its cells soaked."""


def settled(world: World, team: np.ndarray) -> bool:
    """Every robot of ``team`` fights, stands still and sprays."""
    o = world.orders
    assert o is not None
    return bool(
        np.all(o.mode[team] == FIGHT) and np.all(o.spray[team]) and np.all(o.v_m_s[team] == 0)
    )


def test_four_robots_ring_a_fire_at_the_regular_spacing() -> None:
    """A fire needing 4 robots: they stand on the ring of radius standoff about it at
    90 deg +- 6 deg from each other (the regular law's polygon), distance +- 0.12 m,
    facing it and spraying."""
    p = TacticsParams(
        soak_l_m2=NEVER,
        nav=FAST_NAV,
        fire_robots_min=4,
        fire_robots_max=4,
        sensing_range_m=6.0,
        explore_frac=0.0,
    )
    start = np.array([[1.5, y, 0.0] for y in (3.5, 4.5, 5.5, 6.5)])
    world = World(room(), p, start, fire_xy=FIRE, water_l=NEVER)
    team = np.arange(4)
    world.run(90.0, until=lambda w: w.t_s > 5.0 and settled(w, team))
    assert settled(world, team), world.t_s
    rel = world.pose[:, :2] - FIRE[0]
    dist = np.hypot(*rel.T)
    assert np.all(np.abs(dist - p.standoff_m) <= 0.12), dist
    ang = np.sort(np.degrees(np.arctan2(rel[:, 1], rel[:, 0])) % 360.0)
    gaps = np.diff(np.append(ang, ang[0] + 360.0))
    assert np.all(np.abs(gaps - 90.0) <= 6.0), gaps
    # each faces the fire within the spray's half angle
    bearing = np.arctan2(-rel[:, 1], -rel[:, 0])
    off = np.abs((bearing - world.pose[:, 2] + np.pi) % (2 * np.pi) - np.pi)
    assert np.all(off <= p.spray_half_angle_rad)
    assert world.state.assignment.tolist() == [0, 0, 0, 0]


def test_an_empty_tank_goes_to_refill_and_comes_back() -> None:
    p = TacticsParams(
        soak_l_m2=NEVER,
        nav=FAST_NAV,
        fire_robots_min=1,
        fire_robots_max=1,
        sensing_range_m=6.0,
        tank_l=5.0,
        flow_l_s=0.5,
        refill_l_s=1.0,
        refill_xy_m=(1.5, 2.0),
    )
    world = World(room(), p, np.array([[1.5, 5.0, 0.0]]), fire_xy=FIRE, water_l=NEVER)
    world.run(120.0)
    mode = np.array([e["mode"][0] for e in world.log])
    tank = np.array([e["tank"][0] for e in world.log])
    spray = np.array([e["spray"][0] for e in world.log])
    pose = np.array([e["pose"][0] for e in world.log])
    first_refill = int(np.argmax(mode == REFILL))
    assert spray[:first_refill].any()
    assert first_refill > 0
    assert tank[first_refill] < 0.1 * p.tank_l  # it left because the tank ran dry
    # refilled at the refill point
    at_point = np.hypot(pose[:, 0] - 1.5, pose[:, 1] - 2.0) <= p.refill_radius_m
    full_again = first_refill + int(np.argmax(tank[first_refill:] >= 0.98 * p.tank_l))
    assert full_again > first_refill
    assert at_point[full_again]
    # and back on the ring, spraying again
    ring = np.abs(np.hypot(*(pose[:, :2] - FIRE[0]).T) - p.standoff_m) <= 0.12
    back = full_again + np.flatnonzero((spray & ring & (mode == FIGHT))[full_again:])
    assert len(back), "never back on the ring spraying"


def test_a_damaged_robots_task_is_reassigned() -> None:
    p = TacticsParams(
        soak_l_m2=NEVER,
        nav=FAST_NAV,
        fire_robots_min=2,
        fire_robots_max=2,
        sensing_range_m=6.0,
        explore_frac=0.0,
    )
    start = np.array([[1.5, 4.5, 0.0], [1.5, 5.5, 0.0], [1.5, 8.5, 0.0]])
    world = World(room(), p, start, fire_xy=FIRE, water_l=NEVER)
    world.run(
        60.0, until=lambda w: w.t_s > 5.0 and settled(w, np.flatnonzero(w.state.task_fire >= 0))
    )
    fighters = np.flatnonzero(world.state.task_fire >= 0)
    assert len(fighters) == 2
    spare = int(np.setdiff1d(np.arange(3), fighters)[0])
    hit = int(fighters[0])
    world.damaged[hit] = True
    world.run(2.0)
    s = world.state
    assert s.mode[hit] == DAMAGED
    assert s.task_fire[hit] == -1
    assert s.task_fire[spare] >= 0  # the spare robot took over
    assert world.orders is not None
    assert world.orders.v_m_s[hit] == 0.0
    team = np.flatnonzero(s.task_fire >= 0)
    world.run(60.0, until=lambda w: settled(w, team))
    assert settled(world, team)
    rel = world.pose[team, :2] - FIRE[0]
    assert np.all(np.abs(np.hypot(*rel.T) - p.standoff_m) <= 0.12)


def test_victims_are_confirmed_from_within_2_m_and_the_fire_goes_out() -> None:
    p = TacticsParams(nav=FAST_NAV, sensing_range_m=4.0)
    people = np.array([[10.0, 8.5], [2.0, 1.5]])
    fire = FIRE + np.array([[0.0, 0.0], [0.3, 0.0], [0.0, 0.3]])
    world = World(
        room(),
        p,
        np.array([[1.5, 5.0, 0.0], [1.5, 6.0, 0.0]]),
        fire_xy=fire,
        people_xy=people,
        water_l=2.0,
    )
    world.run(
        240.0,
        until=lambda w: (
            not w.burning.any()
            and len(w.state.victims_xy_m) == 2
            and w.state.victims_confirmed.all()
            and len(w.state.fires_xy_m) == 0
        ),
    )
    s = world.state
    assert not world.burning.any()
    assert len(s.fires_xy_m) == 0  # believed out too
    assert s.victims_confirmed.all()
    assert len(s.victims_xy_m) == 2
    times = np.array([e for e in s.victims_confirmed_s])
    for v, t in zip(s.victims_xy_m, times, strict=True):
        truth = people[np.argmin(np.hypot(*(people - v).T))]
        assert np.hypot(*(v - truth)) < 0.05  # detections are exact in the harness
        k = round(t / world.dt_s)
        poses = world.log[k]["pose"]
        assert np.hypot(*(poses[:, :2] - truth).T).min() <= p.confirm_radius_m


def test_a_third_of_the_team_keeps_exploring_while_floor_is_unsearched() -> None:
    """A fire asking for all 3 robots gets 2 while the room is not covered: ceil(0.3 x 3)
    = 1 explores; with explore_frac = 0 it gets all 3."""
    start = np.array([[1.5, 4.5, 0.0], [1.5, 5.5, 0.0], [1.5, 6.5, 0.0]])
    for frac, fighters in ((0.3, 2), (0.0, 3)):
        p = TacticsParams(
            soak_l_m2=NEVER,
            nav=FAST_NAV,
            fire_robots_min=3,
            fire_robots_max=3,
            sensing_range_m=6.0,
            explore_frac=frac,
        )
        world = World(room(), p, start, fire_xy=FIRE, water_l=NEVER)
        world.run(3.0)
        assert world.state.explored_frac < 0.9
        assert int((world.state.task_fire >= 0).sum()) == fighters
        assert int((world.state.mode == EXPLORE).sum()) == 3 - fighters


def test_tanks_fill_only_by_the_refill_point() -> None:
    """Two fighters on a fire of two spots, small tanks: each tank rises only while its
    robot stands within refill_radius_m of the refill point (checked on every logged
    tick), and both go and refill."""
    p = TacticsParams(
        soak_l_m2=NEVER,
        nav=FAST_NAV,
        fire_robots_min=2,
        fire_robots_max=2,
        sensing_range_m=6.0,
        explore_frac=0.0,
        tank_l=4.0,
        flow_l_s=0.5,
        refill_l_s=2.0,
        refill_xy_m=(1.5, 2.0),
    )
    fire = np.array([[7.0, 5.0], [7.5, 5.5]])
    start = np.array([[1.5, 4.5, 0.0], [1.5, 5.5, 0.0]])
    world = World(room(), p, start, fire_xy=fire, water_l=NEVER)
    world.run(90.0)
    tank = np.array([e["tank"] for e in world.log])
    pose = np.array([e["pose"] for e in world.log])
    rose = np.diff(tank, axis=0) > 1e-9
    near = np.hypot(pose[:-1, :, 0] - 1.5, pose[:-1, :, 1] - 2.0) <= p.refill_radius_m + 0.05
    assert rose.any(axis=0).all(), "a robot never refilled"
    assert np.all(near[rose]), "a tank rose away from the refill point"


def test_a_fighter_in_hot_air_gets_a_slot_standoff_from_there() -> None:
    """A fighter whose air reaches retreat_c marks its place hot; the plan after gives
    it a slot at least standoff_m from that place and still within the nozzle's reach
    of the fire (distances on the plane)."""
    from firefleet.control.mission import TacticsObservation, tactics_init, tactics_step

    p = TacticsParams(nav=FAST_NAV, fire_robots_min=1, fire_robots_max=1, explore_frac=0.0)
    pose = np.array([[4.2, 5.0, 0.0]])  # 1.8 m from the fire, facing it
    state = tactics_init(room(), pose, p)

    def obs(t: float, air: float) -> TacticsObservation:
        return TacticsObservation(
            t_s=t,
            pose_m=pose,
            fire_xy_m=FIRE,
            fire_robot=np.zeros(1, int),
            person_xy_m=np.zeros((0, 2)),
            person_robot=np.zeros(0, int),
            ranges={},
            tank_l=np.full(1, 20.0),
            damaged=np.zeros(1, bool),
            alive=np.ones(1, bool),
            air_c=np.full(1, air),
            fire_peak_c=np.full(1, 450.0),
        )

    t = 0.0
    for _ in range(30):
        state, orders = tactics_step(state, obs(t, 40.0), p, 0.1)
        t += 0.1
    assert MODES[orders.mode[0]] == "fight"
    assert len(state.hot_xy_m) == 0
    for _ in range(20):
        state, orders = tactics_step(state, obs(t, p.retreat_c + 5.0), p, 0.1)
        t += 0.1
    assert np.allclose(state.hot_xy_m, pose[:, :2])
    goal = state.goal_xy_m[0]
    assert np.hypot(*(goal - pose[0, :2])) >= p.standoff_m - 1e-9, goal
    assert np.hypot(*(goal - FIRE[0])) <= p.spray_range_m, goal


def _open_cm(width_m: float = 10.0, height_m: float = 5.0) -> tuple[OccupancyGrid, CoarseMap]:
    """A walled room on a 0.25 m grid and the team's coarse map of it (one cell a cell)."""
    h, w = round(height_m / 0.25), round(width_m / 0.25)
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    occ[:, 24] = True  # a wall at x = 6.0-6.25 m
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.25)
    return grid, coarse_map(build_costmap(grid, 0.1), 0.25)


def test_the_ledger_wets_the_cells_the_worlds_spray_wets() -> None:
    """The team's ledger of its water equals the world's spray model (another module,
    its own cone and line of sight) for nozzles in the open and aimed at a wall."""
    grid, cm = _open_cm()
    nozzles = np.array([[1.0, 2.4, 0.1], [4.6, 2.6, -0.2], [3.2, 1.1, 0.9]])
    on = np.array([True, True, False])
    fire = fire_init(np.ones(grid.shape), np.zeros(grid.shape, bool), FireParams())
    temp = np.full(grid.shape, 20.0)
    _, _, wet, used = spray_step(
        fire, temp, np.zeros(grid.shape), nozzles, on, grid, SprayParams(), 1.0
    )
    ledger = spray_ledger(np.zeros((0, 0)), cm, nozzles, on, 0.5, 3.0, math.radians(15.0))
    assert used.tolist() == [0.5, 0.5, 0.0]
    assert wet.sum() > 0
    np.testing.assert_allclose(ledger, wet, atol=1e-12)
    assert not ledger[:, 25:].any()  # nothing past the wall


def test_a_flame_seen_on_a_soaked_cell_moves_behind_the_water() -> None:
    """A flame detection on a soaked cell goes along its camera's ray to the first cell
    not soaked; a wall stops the walk; a gas detection or a dry cell stays."""
    _grid, cm = _open_cm()
    wet = np.zeros(cm.shape)
    cols = np.arange(cm.shape[1])
    wet[:, (cols >= 8) & (cols < 14)] = 2.0  # soaked: x from 2.0 to 3.5 m
    wet[:, 20:24] = 2.0  # soaked up to the wall at x = 6 m
    pose = np.array([[0.5, 2.5, 0.0], [4.0, 2.0, 0.0]])
    xy = np.array([[2.6, 2.5], [2.6, 2.5], [1.5, 2.5], [5.5, 2.0]])
    robot = np.array([0, 0, 0, 1])
    flames = np.array([True, False, True, True])
    out = behind_water(wet, cm, pose, xy, robot, flames, 1.3)
    assert 3.5 <= out[0, 0] <= 3.5 + 0.125
    assert out[0, 1] == 2.5
    np.testing.assert_array_equal(out[1:], xy[1:])  # gas; a dry cell; the wall behind


def test_a_flame_on_water_before_a_wall_moves_in_front_of_it() -> None:
    """Only soaked cells and a wall behind a flame detection on a soaked cell: it goes
    toward its camera to the first cell not soaked, within front_m (the range read
    long: small-house seed 4); none within front_m, or the camera nearer: unchanged."""
    _grid, cm = _open_cm()
    wet = np.zeros(cm.shape)
    wet[:, 21:24] = 2.0  # soaked from x = 5.25 m up to the wall at x = 6 m
    pose = np.array([[4.0, 2.0, 0.0], [5.3, 2.0, 0.0]])
    xy = np.array([[5.6, 2.0], [5.6, 2.0], [5.6, 2.0]])
    robot = np.array([0, 0, 1])
    out = behind_water(wet, cm, pose, xy, robot, np.ones(3, bool), 1.3)
    assert out[0].tolist() == [5.6 - 3 * 0.125, 2.0]  # the first dry cell: x 5.0-5.25 m
    short = behind_water(wet, cm, pose, xy, robot, np.ones(3, bool), 1.3, front_m=0.25)
    assert short[0].tolist() == [5.6, 2.0]  # 0.25 m reaches no dry cell
    assert out[2].tolist() == [5.6, 2.0]  # its camera 0.3 m off: a step short of it only


def test_flames_seen_on_soaked_floor_dry_the_ledger_there() -> None:
    """A flame detection on a cell the ledger holds soaked, with only soaked cells
    within behind_water's walk (the camera 0.3 m off, a wall behind): the cameras
    overrule the ledger, the cell is dry again and the flame one to aim at
    (``dry_flames``); a flame moved to a dry cell, and hot gas, leave it as it was."""
    _grid, cm = _open_cm()
    wet = np.zeros(cm.shape)
    wet[:, 21:24] = 2.0  # soaked from x = 5.25 m up to the wall at x = 6 m
    p = TacticsParams()
    k = replace(empty_knowledge(), wet_l_m2=wet)
    pose = np.array([[4.0, 2.0, 0.0], [5.3, 2.0, 0.0]])
    none = np.zeros((0, 2))
    no_robot = np.zeros(0, dtype=np.int64)
    looked = np.zeros(2, dtype=bool)

    def seen(xy: list[float], robot: int, peak_c: float) -> np.ndarray:
        k2, _ = update_knowledge(
            k,
            cm,
            pose,
            np.array([xy]),
            np.array([robot]),
            none,
            no_robot,
            looked,
            10.0,
            p,
            fire_peak_c=np.array([peak_c]),
        )
        assert len(k2.spot_xy_m) == 1
        out: np.ndarray = k2.wet_l_m2
        return out

    rc = tuple(int(v) for v in cm.cell_of(np.array([[5.6, 2.0]]))[0])
    assert wet[rc] == 2.0
    ledger = seen([5.6, 2.0], 1, 800.0)  # from 0.3 m: no dry cell on its ray
    assert ledger[rc] == 0.0
    assert np.count_nonzero(ledger != wet) == 1
    ledger = seen([5.6, 2.0], 0, 800.0)  # from 1.6 m: moved to the dry cell in front
    np.testing.assert_array_equal(ledger, wet)
    ledger = seen([5.6, 2.0], 1, 300.0)  # hot gas, not flames
    np.testing.assert_array_equal(ledger, wet)
    # the flame on the dried cell is one to aim at
    k3, _ = update_knowledge(
        k,
        cm,
        pose,
        np.array([[5.6, 2.0]]),
        np.array([1]),
        none,
        no_robot,
        looked,
        10.0,
        p,
        fire_peak_c=np.array([800.0]),
    )
    state = replace(tactics_init(_grid, pose, p), knowledge=k3)
    assert dry_flames(state, p).tolist() == [[5.6, 2.0]]


def test_a_fighter_stopped_on_its_way_turns_to_its_fire(monkeypatch: pytest.MonkeyPatch) -> None:
    """A fighter the navigation holds still (v = omega = 0: waiting for a teammate, or
    no safe move) short of its slot turns in place towards its fire at face_gain times
    the bearing error (clipped), so that its camera keeps the fire in view; it turned
    nowhere before (the maze, seed 0: two fighters faced the passage's walls for 400 s)."""
    from firefleet.control.navigation import navigation_step

    p = TacticsParams(
        soak_l_m2=NEVER,
        nav=FAST_NAV,
        fire_robots_min=1,
        fire_robots_max=1,
        explore_frac=0.0,
        sensing_range_m=6.0,
    )
    world = World(room(), p, np.array([[1.5, 5.0, 0.0]]), fire_xy=FIRE, water_l=NEVER)
    world.run(20.0, until=lambda w: w.orders is not None and w.orders.mode[0] == FIGHT)
    assert world.orders is not None
    assert world.orders.mode[0] == FIGHT
    real = navigation_step

    def held(nav, inputs, params, period_s):  # type: ignore[no-untyped-def]
        nav, v, w = real(nav, inputs, params, period_s)
        return replace(nav, status=("waiting",)), np.zeros_like(v), np.zeros_like(w)

    monkeypatch.setattr("firefleet.control.mission._step.navigation_step", held)
    world.pose[0, 2] = math.pi  # facing away from the fire, 4.5 m east of it
    world.step()
    o = world.orders
    assert o is not None
    assert o.mode[0] == FIGHT
    assert o.v_m_s[0] == 0.0
    fx, fy = world.state.knowledge.spot_xy_m.mean(axis=0)
    x, y, th = world.log[-1]["pose"][0]
    err = (math.atan2(fy - y, fx - x) - th + math.pi) % (2 * math.pi) - math.pi
    w_max = p.nav.dwa.omega_max_rad_s
    assert o.omega_rad_s[0] == pytest.approx(np.clip(p.face_gain * err, -w_max, w_max))
    assert abs(o.omega_rad_s[0]) > 0.5


def test_fighters_wet_the_front_and_the_fuel_beyond_it_not_the_same_cells() -> None:
    """A fire that never goes out (the harness's point), 40 s of one fighter: with the
    ledger it aims at the dry cells within front_m of the flames, so its water soaks
    half as many cells again per litre as a fighter whose ledger never fills (soak_l_m2
    never reached: it keeps one cone), and cells beyond the point (a firebreak)."""
    out = {}
    for soak in (1.3, NEVER):
        p = TacticsParams(
            nav=FAST_NAV,
            fire_robots_min=1,
            fire_robots_max=1,
            explore_frac=0.0,
            sensing_range_m=6.0,
            soak_l_m2=soak,
            refill_xy_m=(1.5, 2.0),
        )
        world = World(room(), p, np.array([[1.5, 5.0, 0.0]]), fire_xy=FIRE, water_l=NEVER)
        world.run(40.0)
        wet = world.state.knowledge.wet_l_m2
        cm = world.state.coarse
        xy = cm.goal_xy(np.argwhere(wet >= 1.3))
        used = p.tank_l - min(e["tank"][0] for e in world.log)
        beyond = (xy[:, 0] > FIRE[0, 0] + 0.3) & (np.hypot(*(xy - FIRE[0]).T) <= p.front_m)
        out[soak] = (len(xy) / used, int(beyond.sum()))
    assert out[1.3][0] >= 1.5 * out[NEVER][0], out
    assert out[1.3][1] >= 10, out


def test_dry_flames_answers_for_the_knowledge_it_is_asked_about() -> None:
    """``dry_flames`` keeps its last answer with the knowledge it was for: three flames
    on an open floor, all dry, then the same knowledge with the ledger soaking the one
    3 m from the others (a soaked flame with no dry one within ``standoff_m`` is out),
    then the first knowledge again: each answer is the brute force's for its knowledge."""
    walls = np.zeros((40, 80), dtype=bool)
    grid = OccupancyGrid(walls, ~walls, resolution_m=0.25)
    params = TacticsParams()
    state = tactics_init(grid, [[1.0, 1.0, 0.0]], params)
    flames = np.array([[5.0, 5.0], [5.5, 5.0], [8.5, 5.0]])
    k0 = replace(
        empty_knowledge(),
        spot_xy_m=flames,
        spot_fire=np.zeros(3, dtype=np.int64),
        spot_flame=np.ones(3, dtype=bool),
        spot_misses=np.zeros(3, dtype=np.int64),
    )
    wet = np.zeros(state.coarse.shape)
    wet[state.coarse.cell_of(flames[2:])[0, 0], state.coarse.cell_of(flames[2:])[0, 1]] = 5.0
    k1 = replace(k0, wet_l_m2=wet)
    assert dry_flames(replace(state, knowledge=k0), params).tolist() == flames.tolist()
    assert dry_flames(replace(state, knowledge=k1), params).tolist() == flames[:2].tolist()
    assert dry_flames(replace(state, knowledge=k0), params).tolist() == flames.tolist()
