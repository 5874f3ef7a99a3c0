"""Knowledge merging, the coarse map's coverage, the ring's geometry, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import ArrayLike

from firefleet.control.formation import ring_spacing
from firefleet.control.mission import (
    Knowledge,
    TacticsObservation,
    TacticsParams,
    TacticsState,
    regular_ring,
    tactics_init,
    tactics_step,
)
from firefleet.control.mission._coverage import cone_coverage, line_of_sight
from firefleet.control.mission._knowledge import empty_knowledge, fires_of, update_knowledge
from firefleet.control.navigation import (
    NavigationParams,
    navigation_init,
    navigation_retarget,
)
from firefleet.errors import InputError
from firefleet.world import OccupancyGrid
from tests.control.mission.test_team import room

P = TacticsParams()
NONE2 = np.zeros((0, 2))
NONE = np.zeros(0, dtype=np.int64)


def _update(
    k: Knowledge,
    state: TacticsState,
    pose: np.ndarray,
    fires: ArrayLike = NONE2,
    people: ArrayLike = NONE2,
    looked: np.ndarray | None = None,
    peak_c: float | None = None,
) -> tuple[Knowledge, bool]:
    n = len(pose)
    f = np.asarray(fires, float).reshape(-1, 2)
    q = np.asarray(people, float).reshape(-1, 2)
    peaks = None if peak_c is None else np.full(len(f), peak_c)
    return update_knowledge(
        k,
        state.coarse,
        pose,
        f,
        np.zeros(len(f), dtype=np.int64),
        q,
        np.zeros(len(q), dtype=np.int64),
        np.ones(n, bool) if looked is None else looked,
        0.0,
        P,
        fire_peak_c=peaks,
    )


def test_fire_detections_merge_into_fires_with_their_extent() -> None:
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    pose = np.array([[1.0, 9.0, math.pi / 2]])  # looking at the wall: sees none of them
    line = np.array([[5.0 + 0.6 * i, 5.0] for i in range(6)])  # a 3 m burning line
    far = np.array([[10.0, 2.0]])
    k, changed = _update(empty_knowledge(), state, pose, fires=np.vstack([line, far]))
    ids, xy, extent = fires_of(k)
    assert changed
    assert len(ids) == 2
    assert np.allclose(xy[0], [6.5, 5.0])
    assert np.allclose(xy[1], far[0])
    assert extent[0] == pytest.approx(1.5)  # the spots' largest distance from the mean
    # a detection near a spot (within half fire_merge_m) refreshes it: no new spot
    k2, changed = _update(k, state, pose, fires=[[6.1, 5.05]])
    assert not changed
    assert len(k2.spot_xy_m) == len(k.spot_xy_m)
    # a chain of detections from one fire to the other, each within fire_merge_m of
    # the last, joins them into one
    chain = [[8.5, 4.3], [9.0, 3.6], [9.5, 2.9], [10.0, 2.2]]
    k3, changed = _update(k, state, pose, fires=chain)
    assert changed
    assert len(fires_of(k3)[0]) == 1


def test_a_fire_looked_at_without_detection_goes_out() -> None:
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    k, _ = _update(empty_knowledge(), state, np.array([[1.0, 9.0, 0.0]]), fires=[[4.0, 5.0]])
    looking = np.array([[1.5, 5.0, 0.0]])  # 2.5 m away, facing it
    for i in range(P.fire_out_looks):
        assert len(fires_of(k)[0]) == 1, i
        k, changed = _update(k, state, looking)
    assert changed
    assert len(fires_of(k)[0]) == 0
    # looking away never puts it out
    k, _ = _update(empty_knowledge(), state, looking, fires=[[4.0, 5.0]])
    for _ in range(3 * P.fire_out_looks):
        k, _ = _update(k, state, np.array([[1.5, 5.0, math.pi]]))
    assert len(fires_of(k)[0]) == 1


def test_a_hot_spot_a_depth_error_put_inside_a_rack_goes_out_when_its_face_is_seen() -> None:
    """A spot without flames (the hot floor a burnt-out fire leaves) 0.2 m inside a rack
    that lines an aisle (the detector's depth error: racks hold no fuel) goes out after
    ``fire_out_looks`` looks down the aisle that see no fire: they see the rack's face,
    and the spot is looked at there (no ray from the aisle reaches the spot itself). A
    flame spot is looked at where it was placed."""
    grid = room()
    occ = grid.occupied.copy()
    res = grid.resolution_m
    occ[round(1.0 / res) : round(8.0 / res), round(4.0 / res) : round(5.5 / res)] = True  # rack
    rack = OccupancyGrid(occ, ~occ, res, name="rack")
    state = tactics_init(rack, [[6.5, 9.0, 0.0]], P)
    spot = [5.3, 5.0]  # 0.2 m inside the rack's east face (x = 5.5 m)
    gas = 0.5 * P.flame_c
    k, _ = _update(empty_knowledge(), state, np.array([[6.5, 9.0, 0.0]]), [spot], peak_c=gas)
    down = np.array([[6.3, 8.0, math.atan2(5.0 - 8.0, 5.3 - 6.3)]])  # 3.2 m up the aisle
    assert not line_of_sight(state.coarse, down[:, :2], np.array([spot]))[0]
    for i in range(P.fire_out_looks):
        assert len(fires_of(k)[0]) == 1, i
        k, _ = _update(k, state, down)
    assert len(fires_of(k)[0]) == 0
    # a detection still there keeps it
    k, _ = _update(empty_knowledge(), state, np.array([[6.5, 9.0, 0.0]]), [spot], peak_c=gas)
    for _ in range(2 * P.fire_out_looks):
        k, _ = _update(k, state, down, fires=[[5.55, 5.0]], peak_c=gas)
    assert len(fires_of(k)[0]) == 1
    # flames there are looked at where they were placed: these looks never reach them
    k, _ = _update(empty_knowledge(), state, np.array([[6.5, 9.0, 0.0]]), [spot])
    for _ in range(2 * P.fire_out_looks):
        k, _ = _update(k, state, down)
    assert len(fires_of(k)[0]) == 1


def test_a_victim_is_confirmed_by_repeated_detections_from_within_2_m() -> None:
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    person = [[6.0, 5.0]]
    k, _ = _update(empty_knowledge(), state, np.array([[2.0, 5.0, 0.0]]), people=person)
    k, _ = _update(k, state, np.array([[2.5, 5.0, 0.0]]), people=person)
    assert not k.victim_confirmed[0]  # seen twice, from 4 and 3.5 m
    k, _ = _update(k, state, np.array([[4.5, 5.0, 0.0]]), people=person)
    assert not k.victim_confirmed[0]  # once from 1.5 m
    k, changed = _update(k, state, np.array([[4.2, 5.0, 0.0]]), people=person)
    assert changed
    assert k.victim_confirmed[0]
    assert len(k.victim_xy_m) == 1


def test_coverage_stops_at_walls_and_line_of_sight() -> None:
    grid = room()
    occ = np.array(grid.occupied)
    occ[:, 119:121] = True  # a wall at x = 6 m
    from firefleet.world import OccupancyGrid

    g2 = OccupancyGrid(occ, ~occ, 0.05)
    state = tactics_init(g2, [[1.0, 5.0, 0.0]], P)
    cm = state.coarse
    rows, cols = cone_coverage(cm, np.array([[4.0, 5.0, 0.0]]), 4.0, P.hfov_rad)
    x = cm.grid.center_of(np.stack([rows * cm.factor, cols * cm.factor], 1))[:, 0]
    assert x.max() < 6.3
    assert x.min() > 3.5
    assert line_of_sight(cm, np.array([[4.0, 5.0]]), np.array([[5.5, 6.0]]))[0]
    assert not line_of_sight(cm, np.array([[4.0, 5.0]]), np.array([[7.5, 5.0]]))[0]


@pytest.mark.parametrize("m", [2, 3, 5, 8])
def test_regular_ring_is_the_formation_laws_equilibrium(m: int) -> None:
    rng = np.random.default_rng(m)
    start = rng.uniform(-3.0, 3.0, (m, 2))
    p = regular_ring(np.array([1.0, -1.0]), 2.0, start)
    rel = p - [1.0, -1.0]
    assert np.allclose(np.hypot(*rel.T), 2.0)
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    gaps = np.diff(np.sort(ang), append=np.sort(ang)[0] + 2 * np.pi)
    assert np.allclose(gaps, 2 * np.pi / m, atol=1e-4)
    # the angular order is the robots' own (order preservation)
    a0 = np.arctan2(start[:, 1] + 1.0, start[:, 0] - 1.0)
    order0 = np.argsort(a0)
    cyc = np.argsort(ang)
    k = int(np.flatnonzero(cyc == order0[0])[0])
    assert np.array_equal(np.roll(cyc, -k), order0)
    # and the formation's own spacing force vanishes there
    assert np.abs(ring_spacing(p, [1.0, -1.0], stiffness_n_m=1.0)).max() < 1e-3


def test_retargeting_changes_only_the_robots_named() -> None:
    grid = room()
    params = NavigationParams()
    nav = navigation_init(
        grid, [[1.0, 2.0, 0.0], [1.0, 8.0, 0.0]], [[5.0, 2.0], [5.0, 8.0]], params
    )
    new = navigation_retarget(nav, [[0.0, 0.0], [9.0, 8.0]], [False, True])
    assert new.paths[0] is nav.paths[0]
    assert new.goals_m[0].tolist() == [5.0, 2.0]
    assert new.paths[1] is None
    assert new.goals_m[1].tolist() == [9.0, 8.0]
    assert new.status == ("moving", "moving")
    with pytest.raises(InputError, match="which"):
        navigation_retarget(nav, [[0.0, 0.0]] * 2, [True])
    with pytest.raises(InputError, match="goals_m"):
        navigation_retarget(nav, [[np.nan, 0.0]] * 2, [True, False])


def _obs(n: int, **kw: object) -> TacticsObservation:
    base: dict[str, object] = dict(
        t_s=0.0,
        pose_m=np.array([[1.0, 5.0, 0.0]] * n),
        fire_xy_m=NONE2,
        fire_robot=NONE,
        person_xy_m=NONE2,
        person_robot=NONE,
        ranges={},
        tank_l=np.full(n, 20.0),
        damaged=np.zeros(n, bool),
        alive=np.ones(n, bool),
    )
    base.update(kw)
    return TacticsObservation(**base)  # type: ignore[arg-type]


def test_bad_input_names_the_key() -> None:
    with pytest.raises(InputError, match=r"tactics\.standoff_m must be > 0"):
        TacticsParams(standoff_m=-1.0)
    with pytest.raises(InputError, match="fire_robots_max"):
        TacticsParams(fire_robots_min=3, fire_robots_max=2)
    with pytest.raises(InputError, match="at least one robot"):
        tactics_init(room(), np.zeros((0, 3)), P)
    with pytest.raises(InputError, match=r"poses\[1\].*off the map"):
        tactics_init(room(), [[1.0, 1.0, 0.0], [30.0, 1.0, 0.0]], P)
    with pytest.raises(InputError, match="refill_xy_m"):
        tactics_init(room(), [[1.0, 1.0, 0.0]], TacticsParams(refill_xy_m=(-5.0, 1.0)))
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    with pytest.raises(InputError, match=r"obs\.pose_m"):
        tactics_step(state, _obs(2), P, 0.01)
    with pytest.raises(InputError, match="tank_l"):
        tactics_step(state, _obs(1, tank_l=np.zeros(3)), P, 0.01)
    with pytest.raises(InputError, match="dt_s"):
        tactics_step(state, _obs(1), P, 0.0)


def test_a_victim_looked_at_without_a_person_is_dismissed_until_seen_again() -> None:
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    ghost = [[6.0, 5.0]]
    k, _ = _update(empty_knowledge(), state, np.array([[2.0, 5.0, 0.0]]), people=ghost)
    looking = np.array([[3.0, 5.0, 0.0]])  # 3 m away, facing it, nothing there
    for _ in range(P.victim_out_looks - 1):
        k, changed = _update(k, state, looking)
        assert not changed
    assert not k.dismissed(P)[0]
    k, changed = _update(k, state, looking)
    assert changed
    assert k.dismissed(P)[0]
    k, changed = _update(k, state, looking, people=ghost)  # a person there after all
    assert changed
    assert not k.dismissed(P)[0]
    # a confirmed victim is never dismissed
    k, _ = _update(empty_knowledge(), state, np.array([[5.0, 5.0, 0.0]]), people=ghost)
    k, _ = _update(k, state, np.array([[5.0, 5.0, 0.0]]), people=ghost)
    assert k.victim_confirmed[0]
    for _ in range(2 * P.victim_out_looks):
        k, _ = _update(k, state, looking)
    assert not k.dismissed(P)[0]


def test_paths_go_round_a_known_fire() -> None:
    from dataclasses import replace

    from firefleet.control.mission._fight import fire_costmap
    from firefleet.control.navigation import astar

    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    k, _ = _update(empty_knowledge(), state, np.array([[1.0, 9.0, 0.0]]), fires=[[6.0, 5.0]])
    start, goal = np.array([2.0, 5.0]), np.array([10.0, 5.0])
    plain = astar(state.nav.costmap, start, goal).xy_m
    assert plain is not None
    assert np.hypot(*(plain - [6.0, 5.0]).T).min() < 0.1  # straight through it
    hot = fire_costmap(replace(state, knowledge=k), np.array([[2.0, 5.0, 0.0]]), P).nav.costmap
    around = astar(hot, start, goal).xy_m
    assert around is not None
    assert np.hypot(*(around - [6.0, 5.0]).T).min() >= P.fire_keepout_m - 0.05
    # within fire_block_m of it: 1 + 11 fire_cost per metre (never blocked: a robot
    # standing 0.5 m from the fire can always plan its way out)
    grid = hot.grid
    rc = tuple(grid.cell_of([6.0, 5.6]))
    assert not hot.blocked[rc]
    assert hot.cost[rc] == pytest.approx(state.nav.costmap.cost[rc] + 11 * P.fire_cost)
    out = astar(hot, np.array([6.5, 5.0]), goal)
    assert out.found


def test_explored_fraction_equals_the_map_cells_count() -> None:
    from dataclasses import replace

    from firefleet.world import load_map

    grid = load_map("office")
    state = tactics_init(grid, [[1.0, 5.0, 0.0]], P)
    rng = np.random.default_rng(0)
    covered = rng.random(state.covered_coarse.shape) < 0.4
    s = replace(state, covered_coarse=covered)
    free = np.asarray(grid.free)
    assert s.explored_frac == pytest.approx((s.covered & free).sum() / free.sum(), abs=1e-12)


def test_spots_read_at_flame_temperature_are_flames() -> None:
    """A spot is flames once a detection reading flame_c or more put or refreshed it
    (within half fire_merge_m); cooler readings (hot gas) never make it so."""
    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    pose = np.array([[1.0, 9.0, math.pi / 2]])  # looking at the wall: no looks count

    def add(k: Knowledge, xy: list[float], peak_c: float) -> Knowledge:
        out, _ = update_knowledge(
            k,
            state.coarse,
            pose,
            np.array([xy]),
            np.zeros(1, dtype=np.int64),
            NONE2,
            NONE,
            np.ones(1, bool),
            0.0,
            P,
            np.array([peak_c]),
        )
        return out

    k = add(empty_knowledge(), [6.0, 5.0], P.flame_c - 1.0)  # hot gas
    k = add(k, [8.0, 5.0], P.flame_c)  # flames, a new spot of another fire
    assert k.spot_flame.tolist() == [False, True]
    k = add(k, [6.0 + 0.4 * P.fire_merge_m, 5.0], 450.0)  # refreshes the first spot
    assert k.spot_flame.tolist() == [True, True]
    assert len(k.spot_xy_m) == 2
    k = add(k, [6.0 + 0.8 * P.fire_merge_m, 5.0], 100.0)  # joins it as a new, cool spot
    assert k.spot_flame.tolist() == [True, True, False]


def _named(pose: np.ndarray, person_xy: np.ndarray) -> bool:
    """Whether the mission's renderer and the real detector name a person at
    ``person_xy`` from ``pose`` (office, 20 C air, the mission's field grid)."""
    from firefleet.perception.thermal import detect
    from firefleet.sim.kinds._mission_world import SCENE
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid_depth
    from firefleet.world import coarsen, load_map

    field = coarsen(load_map("office"), 5)
    frames, depth = render_thermal_grid_depth(
        pose[None],
        field,
        np.full(field.shape, 20.0),
        np.zeros(field.shape, bool),
        person_xy[None],
        ThermalCameraParams(supersample=2, netd_k=0.05),
        rng=np.random.default_rng(0),
        scene=SCENE,
    )
    return any(d.kind == "person" for d in detect(frames[0], depth_m=depth[0]).detections)


@pytest.mark.parametrize(
    "pose", [[10.5, 3.5, -0.6], [13.5, 3.0, math.pi], [6.0, 5.0, 0.0], [1.0, 1.5, 0.3]]
)
def test_a_person_in_a_covered_cell_is_named_by_the_detector(pose: list[float]) -> None:
    """The coverage counts a cell searched only where the real detector, on the frame the
    mission renders, names a person standing there; a person nearer than the camera's
    nearest range is not named, and not counted (office seed 1: a person 0.7-2 m from a
    robot that never faced them from farther was left unfound in a room counted 100 %
    covered)."""
    from firefleet.world import load_map

    state = tactics_init(load_map("office"), [[*pose[:2], 0.0]], P)
    cm = state.coarse
    p = np.array([pose])
    rows, cols = cone_coverage(
        cm, p, P.sensing_range_m, P.hfov_rad, P.sensing_near_m, P.person_half_width_m
    )
    cells = np.unique(np.stack([rows, cols], 1), axis=0)
    cells = cells[cm.standable[cells[:, 0], cells[:, 1]]]
    assert len(cells) > 10
    rng = np.random.default_rng(1)
    for rc in cells[rng.choice(len(cells), 6, replace=False)]:
        xy = cm.grid.center_of((rc.astype(float) + 0.5) * cm.factor - 0.5)
        assert _named(p[0], xy), (rc, xy)
    # straight ahead at 1.2 m: not named by the detector, and not covered
    ahead = p[0, :2] + 1.2 * np.array([math.cos(pose[2]), math.sin(pose[2])])
    assert not _named(p[0], ahead)
    a_rc = cm.cell_of(ahead[None])[0]
    assert not np.any((rows == a_rc[0]) & (cols == a_rc[1]))


def test_a_fire_no_detection_joined_for_fire_forget_s_is_forgotten() -> None:
    """Two fires seen at 0 s, the first seen again at 100 s (a detection near one of
    its spots), nothing looked at since (so no look puts them out): at 120 s both are
    kept, at 120.1 s the second is gone with its spots, at 220.1 s the first too; a
    fire seen anew after that is a new fire. With ``fire_forget_s = inf`` both stay."""
    from dataclasses import replace

    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    away = np.array([[1.0, 9.0, math.pi / 2]])  # facing the wall: looks at neither
    blind = np.zeros(1, dtype=bool)

    def at(k: Knowledge, t_s: float, fires: ArrayLike, params: TacticsParams) -> Knowledge:
        f = np.asarray(fires, float).reshape(-1, 2)
        k2, _ = update_knowledge(
            k, state.coarse, away, f, np.zeros(len(f), dtype=np.int64), NONE2, NONE,
            blind, t_s, params,
        )  # fmt: skip
        return k2

    for forget_s, gone in ((P.fire_forget_s, True), (math.inf, False)):
        p = replace(P, fire_forget_s=forget_s)
        k = at(empty_knowledge(), 0.0, [[4.0, 5.0], [4.8, 5.0], [9.0, 2.0]], p)
        assert len(fires_of(k)[0]) == 2
        k = at(k, 100.0, [[4.1, 5.1]], p)  # the first fire, seen again
        k = at(k, 120.0, NONE2, p)
        assert len(fires_of(k)[0]) == 2
        k = at(k, 120.1, NONE2, p)
        assert len(k.spot_xy_m) == (2 if gone else 3)
        if gone:
            assert np.allclose(fires_of(k)[1], [[4.4, 5.0]])  # the first fire's two spots
        k = at(k, 220.1, NONE2, p)
        assert len(fires_of(k)[0]) == (0 if gone else 2)
        k = at(k, 300.0, [[9.0, 2.0]], p)
        ids = fires_of(k)[0]
        assert len(ids) == (1 if gone else 2)
        if gone:
            assert ids.tolist() == [2]  # a new id


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan])
def test_fire_forget_s_must_be_positive(bad: float) -> None:
    with pytest.raises(InputError, match=r"tactics\.fire_forget_s"):
        TacticsParams(fire_forget_s=bad)
