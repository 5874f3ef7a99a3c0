"""Person detections checked against the floor plan (``_people``), against frames the
mission's renderer draws and the real detector reads."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from firefleet.control.mission import (
    CoarseMap,
    Knowledge,
    TacticsObservation,
    TacticsParams,
    tactics_init,
    tactics_step,
)
from firefleet.control.mission._coverage import clear_sight
from firefleet.control.mission._knowledge import empty_knowledge, update_knowledge, watch_victims
from firefleet.control.mission._params import CONFIRM, EXPLORE
from firefleet.control.mission._people import person_plausible, wall_distance
from firefleet.errors import InputError

P = TacticsParams()


def _office_cm() -> CoarseMap:
    from firefleet.world import load_map

    return tactics_init(load_map("office"), [[1.0, 1.5, 0.0]], P).coarse


def _people_seen(
    pose: list[float], temp_c: np.ndarray, people: np.ndarray, seed: int
) -> list[tuple[float, float, float]]:
    """Person detections (x [m], y [m], peak [C]) of one frame rendered as the mission
    renders it (office field grid, the mission's scene, 3 % depth noise) and read by
    the real detector, placed on the map as the mission kind places them."""
    from firefleet.perception.thermal import detect
    from firefleet.sim.kinds._mission_world import SCENE
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid_depth
    from firefleet.world import coarsen, load_map

    field = coarsen(load_map("office"), 5)
    rng = np.random.default_rng(seed)
    frames, depth = render_thermal_grid_depth(
        np.array(pose)[None],
        field,
        temp_c,
        np.zeros(field.shape, bool),
        people.reshape(-1, 2),
        ThermalCameraParams(supersample=2, netd_k=0.05),
        rng=rng,
        scene=SCENE,
    )
    depth = depth * (1.0 + 0.03 * rng.standard_normal(depth.shape))
    out = []
    for d in detect(frames[0], depth_m=depth[0]).detections:
        if d.kind == "person" and d.range_m is not None:
            a = pose[2] + d.bearing_rad
            out.append(
                (pose[0] + d.range_m * math.cos(a), pose[1] + d.range_m * math.sin(a), d.peak_c)
            )
    return out


def _field_xy() -> tuple[np.ndarray, np.ndarray]:
    from firefleet.world import coarsen, load_map

    field = coarsen(load_map("office"), 5)
    h, w = field.shape
    ys = field.origin_m[1] + (h - 1 - np.arange(h) + 0.5) * field.resolution_m
    xs = field.origin_m[0] + (np.arange(w) + 0.5) * field.resolution_m
    return np.meshgrid(xs, ys)


POSES = [[17.9, 4.58, math.radians(-157)], [18.5, 4.9, math.radians(-160)], [14.5, 4.9, -0.35]]


def test_a_hot_wall_the_detector_names_a_person_is_dropped_and_a_person_by_it_kept() -> None:
    """The corridor's south wall heated to 50 C over 1.5 m (the hot gas from a fire
    room's door: mission-office seed 1 saw 33-63 C there) is named a person by the real
    detector from three poses; every such detection is dropped, while people standing
    0.35 m from the same wall (where mission-smoke puts one), before the hot wall itself
    (their region takes in the wall: a 50 C peak) and in the rooms are named and kept."""
    cm = _office_cm()
    x, y = _field_xy()
    hot = np.full(x.shape, 20.0)
    hot[(y > 4.25) & (y < 4.5) & (x > 15.5) & (x < 17.0)] = 50.0
    seen = [(pose, _people_seen(pose, hot, np.zeros(0), s)) for s, pose in enumerate(POSES)]
    wall = np.array([d[:2] for _, ds in seen for d in ds])
    wall_robot = np.array([pose[:2] for pose, ds in seen for _ in ds])
    assert len(wall) >= 3  # the detector is fooled from every pose
    assert not person_plausible(cm, wall_robot, wall, P.person_wall_m).any()
    cool = np.full(x.shape, 20.0)
    people = [
        ([15.3, 4.9, 0.1], [17.6, 4.6], cool),
        ([19.4, 4.9, math.pi], [17.6, 4.6], cool),
        ([13.5, 5.1, 0.0], [16.0, 5.4], cool),
        ([12.5, 4.7, math.atan2(-2.7, -0.5)], [12.0, 2.0], cool),  # through the room's door
        ([14.0, 5.0, -0.15], [16.3, 4.6], hot),  # before the hot wall
        ([18.6, 5.0, math.pi + 0.2], [16.3, 4.6], hot),
    ]
    for s, (pose, xy, temp) in enumerate(people):
        named = _people_seen(pose, temp, np.array(xy), 10 + s)
        assert len(named) == 1, (pose, xy)
        pxy = np.array([named[0][:2]])
        assert np.hypot(*(pxy[0] - xy)) < 0.2
        if temp is hot:
            assert named[0][2] > 45.0  # not a skin temperature: the wall's
        keep = person_plausible(cm, np.array([pose[:2]]), pxy, P.person_wall_m)
        assert keep.tolist() == [True], (pose, xy, pxy)


def test_wall_distance_is_the_brute_force_distance_to_the_wall_squares() -> None:
    """Against every opaque cell's square, searched over the whole map."""
    cm = _office_cm()
    rng = np.random.default_rng(3)
    pts = np.c_[rng.uniform(0.0, 20.0, 300), rng.uniform(0.0, 10.0, 300)]  # the office
    got = wall_distance(cm, pts, 0.6)
    hc, wc = cm.shape
    r, c = np.mgrid[-1 : hc + 1, -1 : wc + 1]
    inside = (r >= 0) & (r < hc) & (c >= 0) & (c < wc)
    opaque = ~inside
    opaque[inside] = cm.opaque[r[inside], c[inside]]
    ctr = cm.centre_xy(np.stack([r[opaque], c[opaque]], axis=-1))
    gx = np.maximum(np.abs(pts[:, None, 0] - ctr[None, :, 0]) - cm.cell_m / 2, 0.0)
    gy = np.maximum(np.abs(pts[:, None, 1] - ctr[None, :, 1]) - cm.cell_m / 2, 0.0)
    ref = np.hypot(gx, gy).min(axis=1)
    ref = np.where(ref <= 0.6, ref, np.inf)
    assert np.array_equal(np.isinf(got), np.isinf(ref))
    fin = np.isfinite(ref)
    np.testing.assert_allclose(got[fin], ref[fin], atol=1e-12)
    assert (got[fin] == 0).sum() > 10
    assert (got[fin] > 0).sum() > 10
    assert wall_distance(cm, np.array([[-0.1, 5.0], [10.0, 10.2]]), 0.6).tolist() == [0.0, 0.0]


def test_behind_a_wall_and_bad_input() -> None:
    cm = _office_cm()
    # from the corridor: the south-middle room's person is behind the wall, not at the door
    a = np.array([[12.5, 4.9], [10.0, 4.9]])
    b = np.array([[12.0, 2.0], [12.0, 2.0]])
    assert (~clear_sight(cm, a, b)).tolist() == [False, True]  # a wall between
    assert person_plausible(cm, a, b, P.person_wall_m).tolist() == [True, False]
    assert person_plausible(cm, np.zeros((0, 2)), np.zeros((0, 2)), 0.15).shape == (0,)
    with pytest.raises(InputError, match="robot_xy_m"):
        person_plausible(cm, a[:1], b, 0.15)
    with pytest.raises(InputError, match="person_wall_m"):
        TacticsParams(person_wall_m=-0.1)
    with pytest.raises(InputError, match="confirm_watch_s"):
        TacticsParams(confirm_watch_s=0.0)


def test_the_knowledge_takes_no_victim_from_a_wall() -> None:
    """A wall's "person" makes no victim; a person in the room does."""
    from firefleet.world import load_map

    state = tactics_init(load_map("office"), [[17.9, 4.58, -2.7]], P)
    pose = np.array([[17.9, 4.58, -2.7], [12.5, 4.7, -1.75]])
    k, changed = update_knowledge(
        empty_knowledge(),
        state.coarse,
        pose,
        np.zeros((0, 2)),
        np.zeros(0, dtype=np.int64),
        np.array([[16.4, 4.28], [12.0, 2.05]]),
        np.array([0, 1]),
        np.zeros(2, bool),
        5.0,
        P,
    )
    assert changed
    np.testing.assert_allclose(k.victim_xy_m, [[12.0, 2.05]])


def _obs(t: float, pose: np.ndarray, people: np.ndarray, robot: np.ndarray) -> TacticsObservation:
    n = len(pose)
    return TacticsObservation(
        t_s=t,
        pose_m=pose,
        fire_xy_m=np.zeros((0, 2)),
        fire_robot=np.zeros(0, dtype=np.int64),
        person_xy_m=people.reshape(-1, 2),
        person_robot=robot,
        ranges={},
        tank_l=np.full(n, P.tank_l),
        damaged=np.zeros(n, bool),
        alive=np.ones(n, bool),
    )


def _confirm_run(
    params: TacticsParams, duration_s: float, ghost_every: bool
) -> tuple[list[int], Knowledge]:
    """Two robots held still in a 12 m x 10 m room: robot 0 4 m from a "person" robot 1
    names from 5 m away at every tick (a false detection nobody confirms: robot 0's
    own camera sees nothing there). Returns robot 0's mode at each tick."""
    from tests.control.mission.test_team import room

    pose = np.array([[3.6, 5.0, 0.0], [6.0, 9.0, -math.pi / 2]])
    ghost = np.array([[6.0, 4.0]])
    state = tactics_init(room(), pose, params)
    modes = []
    for k in range(round(duration_s / 0.1)):
        t = round(0.1 * k, 9)
        people = ghost if ghost_every or k == 0 else np.zeros((0, 2))
        robot = np.ones(len(people), dtype=np.int64)
        state, orders = tactics_step(state, _obs(t, pose, people, robot), params, 0.1)
        modes.append(int(orders.mode[0]))
    return modes, state.knowledge


def test_a_confirmer_gives_up_a_person_it_watches_without_confirming() -> None:
    """Robot 0 is sent to confirm; held still 2.6 m from the "person" (in sight, within
    the confirmation radius) it settles after ``stall_s`` and watches; after
    ``confirm_watch_s`` of watching it gives the victim up and explores. Without the
    clock (the code before) it confirms forever: each far detection resets the misses
    its own looks count (mission-office seed 1: 360 s)."""
    p = TacticsParams(confirm_radius_m=3.0)
    modes, k = _confirm_run(p, 40.0, ghost_every=True)
    first = modes.index(CONFIRM)
    assert first < 15
    left = first + modes[first:].index(EXPLORE)
    # settles after stall_s, then watches confirm_watch_s (at the 10 Hz orders)
    assert (
        (p.stall_s + p.confirm_watch_s) / 0.1
        <= left - first
        <= (p.stall_s + p.confirm_watch_s + 2.0) / 0.1
    )
    assert k.victim_given_up.tolist() == [True]
    assert not k.victim_confirmed[0]
    never = TacticsParams(confirm_radius_m=3.0, confirm_watch_s=1e6)
    modes, k = _confirm_run(never, 40.0, ghost_every=True)
    assert modes[-1] == CONFIRM
    assert not k.dismissed(never)[0]


def test_watch_clock_runs_only_in_sight_and_a_close_detection_still_confirms() -> None:
    from tests.control.mission.test_team import room

    state = tactics_init(room(), [[1.0, 5.0, 0.0]], P)
    cm = state.coarse
    k, _ = update_knowledge(
        empty_knowledge(),
        cm,
        np.array([[1.0, 5.0, 0.0]]),
        np.zeros((0, 2)),
        np.zeros(0, dtype=np.int64),
        np.array([[6.0, 5.0]]),
        np.array([0]),
        np.zeros(1, bool),
        0.0,
        P,
    )
    one = np.array([0])
    far = np.array([[1.0, 5.0, 0.0]])  # 5 m: beyond the confirmation radius
    for _ in range(200):
        k, gave = watch_victims(k, cm, far, one, np.array([0]), 0.1, P)
        assert not gave
    assert k.victim_watch_s.tolist() == [0.0]
    near = np.array([[4.0, 5.0, 0.0]])  # 2 m: in sight
    steps = 0
    while not k.victim_given_up[0]:
        k, gave = watch_victims(k, cm, near, one, np.array([0]), 0.1, P)
        steps += 1
    assert gave
    assert steps == round(P.confirm_watch_s / 0.1)
    assert k.dismissed(P)[0]
    # a detection from afar does not bring it back; two from within 2 m confirm it
    pose = np.array([[0.5, 5.0, 0.0], [4.2, 5.0, 0.0]])
    for r, c in ((0, False), (1, False), (1, True)):
        k, _ = update_knowledge(
            k,
            cm,
            pose,
            np.zeros((0, 2)),
            np.zeros(0, dtype=np.int64),
            np.array([[6.0, 5.0]]),
            np.array([r]),
            np.zeros(2, bool),
            1.0,
            P,
        )
        assert bool(k.victim_confirmed[0]) is c
        assert bool(k.dismissed(P)[0]) is (not c)


def test_a_confirmer_held_up_behind_a_wall_does_not_settle_there() -> None:
    """Office: a person seen at (12, 2) through the south-middle room's door by robot 1,
    which is then damaged; robot 0, in the corridor 2.9 m away behind the room's wall,
    is sent to confirm and held still. It used to settle there after ``stall_s`` (and
    stand for good); it is sent to a viewpoint again, and its watch clock never runs."""
    from firefleet.world import load_map

    pose = np.array([[10.0, 4.7, 0.0], [12.5, 4.7, math.atan2(-2.7, -0.5)]])
    state = tactics_init(load_map("office"), pose, P)
    for k in range(round(30.0 / 0.1)):
        t = round(0.1 * k, 9)
        obs = _obs(
            t,
            pose,
            np.array([[12.0, 2.0]]) if k == 0 else np.zeros((0, 2)),
            np.ones(1 if k == 0 else 0, dtype=np.int64),
        )
        if k > 0:
            obs = replace(obs, damaged=np.array([False, True]))
        state, orders = tactics_step(state, obs, P, 0.1)
        if t > P.stall_s + 1.0:
            assert orders.mode[0] == CONFIRM
            assert state.nav.status[0] != "arrived"
    goal = state.goal_xy_m[0]
    assert np.isfinite(goal).all()
    assert 1.5 <= np.hypot(*(goal - [12.0, 2.0])) <= P.confirm_radius_m
    assert state.knowledge.victim_watch_s.tolist() == [0.0]
