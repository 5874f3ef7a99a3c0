"""The dynamic window and the team controller, in a small closed loop."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.control.navigation import (
    DwaParams,
    NavigationInputs,
    NavigationParams,
    dwa_command,
    dwa_limits_from_motor,
    navigation_init,
    navigation_step,
)
from firefleet.control.navigation._dwa import _evaluate, in_window
from firefleet.errors import InputError
from firefleet.models.motor import MotorParams
from firefleet.world import OccupancyGrid

from ._nav_loop import doorway_map, run


def _walled(h: int, w: int) -> np.ndarray:
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return occ


def test_limits_follow_the_table_2_motor_at_12_v() -> None:
    m = MotorParams()
    v_w, a_w = dwa_limits_from_motor()
    w_top = (
        m.torque_n_m_a
        * 12.0
        / (m.resistance_ohm * m.damping_n_m_s + m.back_emf_v_s * m.torque_n_m_a)
    )
    assert v_w == pytest.approx(0.045 * w_top, rel=1e-9)
    # the analytic second-order step response w(t) at t = tau1, over tau1
    t1, t2 = m.time_constants_s
    w_tau = w_top * (1.0 - (t1 * math.exp(-1.0) - t2 * math.exp(-t1 / t2)) / (t1 - t2))
    assert a_w == pytest.approx(0.045 * w_tau / t1, rel=1e-6)
    p = DwaParams.from_motor()
    assert p.wheel_speed_max_m_s == pytest.approx(v_w)
    assert p.omega_max_rad_s == pytest.approx(2.0 * v_w / 0.2)


def _numpy_evaluate(
    pose: np.ndarray,
    v: float,
    w: float,
    obs: np.ndarray,
    rad: np.ndarray,
    radius: float,
    horizon: float,
    n_steps: int,
) -> tuple[float, float]:
    t = horizon * np.arange(n_steps + 1) / n_steps
    if abs(w) < 1e-9:
        x = pose[0] + v * t * np.cos(pose[2])
        y = pose[1] + v * t * np.sin(pose[2])
    else:
        x = pose[0] + v / w * (np.sin(pose[2] + w * t) - np.sin(pose[2]))
        y = pose[1] - v / w * (np.cos(pose[2] + w * t) - np.cos(pose[2]))
    c = (np.hypot(x[:, None] - obs[None, :, 0], y[:, None] - obs[None, :, 1]) - rad - radius).min(1)
    into = np.nonzero((c < 0.0) & (c < c[0] - 1e-9))[0]
    travel = np.inf if len(into) == 0 else max(v * horizon * (into[0] - 1) / n_steps, 0.0)
    return float(c.min()), float(travel)


def test_compiled_arc_evaluation_matches_numpy() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        pose = rng.uniform([-1, -1, -np.pi], [1, 1, np.pi])
        obs = rng.uniform(-2, 2, size=(12, 2))
        rad = rng.uniform(0, 0.2, size=12)
        v, w = rng.uniform(0, 0.7), rng.uniform(-4, 4) * (rng.random() > 0.2)
        reach = np.hypot(obs[:, 0] - pose[0], obs[:, 1] - pose[1]) - rad  # sorted by it
        order = np.argsort(reach)
        got = _evaluate(pose, v, w, obs[order], rad[order], reach[order], 0.15, 1.5, 15)
        ref = _numpy_evaluate(pose, v, w, obs, rad, 0.15, 1.5, 15)
        assert got[0] == pytest.approx(ref[0], abs=1e-12)
        assert got[1] == pytest.approx(ref[1], abs=1e-12) or got[1] == ref[1] == np.inf


@settings(max_examples=60, deadline=None)
@given(
    v0=st.floats(0.0, 0.75),
    w_frac=st.floats(-1.0, 1.0),
    v_ref=st.floats(-0.5, 1.5),
    w_ref=st.floats(-10.0, 10.0),
    ox=st.floats(-1.5, 1.5),
    oy=st.floats(-1.5, 1.5),
    dt=st.floats(0.02, 0.3),
)
def test_the_chosen_command_is_in_the_window_and_admissible(
    v0: float, w_frac: float, v_ref: float, w_ref: float, ox: float, oy: float, dt: float
) -> None:
    p = DwaParams()
    w0 = w_frac * (p.wheel_speed_max_m_s - v0) / (p.axle_length_m / 2.0)  # a feasible last command
    obs = np.array([[[ox, oy], [ox + 0.3, oy - 0.2], [1e9, 1e9]]])
    rad = np.array([[0.0, 0.15, 0.0]])
    v, w, _ = dwa_command([[0, 0, 0.3]], [[v0, w0]], [[v_ref, w_ref]], obs, rad, p, dt)
    assert in_window(np.stack([v, w], 1), [[v0, w0]], p, dt).all()
    _c, travel = _numpy_evaluate(
        np.array([0, 0, 0.3]), v[0], w[0], obs[0], rad[0], p.robot_radius_m, p.horizon_s, p.n_steps
    )
    # admissible (can stop before contact), or the slowest the window allows
    assert v[0] <= math.sqrt(2.0 * p.wheel_accel_m_s2 * travel) + 1e-9 or v[0] == pytest.approx(
        max(v0 - p.wheel_accel_m_s2 * dt, 0.0)
    )


def test_dwa_brakes_or_turns_before_a_wall_it_cannot_drive_at() -> None:
    p = DwaParams()
    wall = np.stack([np.full(21, 0.17), np.linspace(-1, 1, 21)], axis=1)[None]
    rad = np.zeros((1, 21))
    _, travel = _numpy_evaluate(np.zeros(3), 0.5, 0.0, wall[0], rad[0], 0.15, 1.5, 15)
    # straight on at 0.5 m/s: contact sooner than the wheels can stop (inadmissible)
    assert math.sqrt(2.0 * p.wheel_accel_m_s2 * travel) < 0.5
    v, w, c = dwa_command([[0, 0, 0]], [[0.5, 0.0]], [[0.5, 0.0]], wall, rad, p, 0.1)
    got_c, got_travel = _numpy_evaluate(np.zeros(3), v[0], w[0], wall[0], rad[0], 0.15, 1.5, 15)
    # admissible, or (nothing is) the hardest braking the window allows: 0.5 - a dt
    braking = 0.5 - p.wheel_accel_m_s2 * 0.1
    assert v[0] <= math.sqrt(2.0 * p.wheel_accel_m_s2 * got_travel) + 1e-9 or v[0] == braking
    assert v[0] < 0.5
    assert c[0] == pytest.approx(got_c)


def test_a_robot_facing_a_wall_with_the_goal_behind_it_gets_there() -> None:
    # PythonRobotics issue 379: heading straight at the goal, a wall in between
    occ = _walled(80, 120)
    occ[16:64, 40:42] = True
    grid = OccupancyGrid(occ, ~occ, 0.05)
    params = NavigationParams()
    r = run(grid, np.array([[1.2, 2.0, 0.0]]), np.array([[3.5, 2.0]]), params, 40.0)
    assert r.state.status == ("arrived",)
    assert np.hypot(*(r.poses[-1, 0, :2] - [3.5, 2.0])) <= params.goal_tolerance_m
    assert r.min_wall_clearance_m.min() > 0.0


def test_two_robots_cross_a_doorway_in_opposite_directions() -> None:
    grid = doorway_map()
    poses = np.array([[1.5, 2.0, 0.0], [6.5, 2.0, np.pi]])
    goals = np.array([[6.5, 2.6], [1.5, 1.4]])
    params = NavigationParams()
    r = run(grid, poses, goals, params, 60.0)
    assert r.state.status == ("arrived", "arrived")
    assert np.all(np.hypot(*(r.poses[-1, :, :2] - goals).T) <= params.goal_tolerance_m)
    assert r.min_wall_clearance_m.min() > 0.0
    assert r.min_robot_clearance_m > 0.0
    # no dithering in the doorway: the turn rate changes sign rarely
    w = r.commands[:, :, 1]
    flips = np.sum(np.sign(w[1:]) * np.sign(w[:-1]) < 0, axis=0)
    assert flips.max() <= 0.1 * len(w)


def test_four_robots_cross_one_doorway_without_collision_or_deadlock() -> None:
    grid = doorway_map()
    poses = np.array([[1.0, 1.0, 0.0], [1.0, 3.0, 0.0], [7.0, 1.0, np.pi], [7.0, 3.0, np.pi]])
    goals = np.array([[6.0, 1.5], [6.0, 2.5], [2.0, 1.5], [2.0, 2.5]])
    params = NavigationParams()
    r = run(grid, poses, goals, params, 120.0)
    assert r.state.status == ("arrived",) * 4
    assert np.all(np.hypot(*(r.poses[-1, :, :2] - goals).T) <= params.goal_tolerance_m)
    assert r.min_wall_clearance_m.min() > 0.0
    assert r.min_robot_clearance_m > 0.0
    # lower indices have priority: robot 0 is not slower than robot 3
    assert r.arrival_s[0] <= r.arrival_s[3]


def test_head_on_in_a_passage_only_one_fits_through() -> None:
    # a 2 m long, 0.9 m wide passage: the lower-priority robot makes way, nobody deadlocks
    occ = _walled(80, 200)
    occ[:, 80:120] = True
    occ[31:49, 80:120] = False
    grid = OccupancyGrid(occ, ~occ, 0.05)
    poses = np.array([[1.5, 2.0, 0.0], [8.5, 2.0, np.pi]])
    goals = np.array([[8.5, 2.0], [1.5, 2.0]])
    params = NavigationParams()
    r = run(grid, poses, goals, params, 60.0)
    assert r.state.status == ("arrived", "arrived")
    assert r.min_wall_clearance_m.min() > 0.0
    assert r.min_robot_clearance_m > 0.0
    assert r.arrival_s[0] < r.arrival_s[1]  # robot 0 has the right of way


def _held_pair(t_end_s: float) -> tuple[tuple[str, ...], list[int]]:
    """Robot 0 bound east along y = 1 (its poses held: it makes no progress), robot 1
    0.45 m beside its way, bound across it; navigation run to ``t_end_s``."""
    occ = _walled(40, 80)
    grid = OccupancyGrid(occ, ~occ, 0.1)
    params = NavigationParams()
    pose = np.array([[1.0, 1.0, 0.0], [3.0, 1.45, -np.pi / 2]])
    state = navigation_init(grid, pose, [[6.0, 1.0], [3.0, 0.4]], params)
    t = 0.0
    while t <= t_end_s:
        inputs = NavigationInputs(pose, {}, pose[:, :2], t)
        state, _, _ = navigation_step(state, inputs, params, 0.1)
        t += 0.1
    return state.status, state.aside_of.tolist()


def test_a_robot_beside_a_held_up_teammates_way_makes_way() -> None:
    # robot 1's way crosses robot 0's; robot 1 stands 0.45 m from robot 0's way ahead,
    # outside the 0.35 m that puts it in the way, so it waits for robot 0 to pass
    gap = 2 * NavigationParams().robot_radius_m + NavigationParams().margin_m
    assert gap < 0.45
    status, aside = _held_pair(1.0)
    assert status[1] == "waiting"
    assert aside == [-1, -1]
    # robot 0 held up for stuck_time_s (3 s): robot 1 makes way instead of waiting on
    # (the house, seed 3: a fighter in a doorway waited 600 s for a teammate whose
    # window found no way past it)
    status, aside = _held_pair(3.5)
    assert aside == [-1, 0]
    assert status[1] == "moving"


def test_a_robot_standing_beside_a_held_up_movers_way_makes_way() -> None:
    # a 1 m passage; robot 0 stands (its goal reached) by its wall: a way past it
    # exists, so it is not asked to move; once robot 1 is held up for stuck_time_s
    # (poses held) near it, it is (a school wing, seed 1: an explorer held 240 s behind
    # a fighter standing in a classroom's 1 m door)
    occ = np.zeros((40, 100), dtype=bool)
    occ[:15] = occ[25:] = True
    grid = OccupancyGrid(occ, ~occ, 0.1)
    params = NavigationParams()
    pose = np.array([[5.0, 1.75, 0.0], [4.0, 2.0, 0.0]])
    state = navigation_init(grid, pose, [[5.0, 1.75], [9.0, 2.0]], params)
    parked = []
    for k in range(40):
        inputs = NavigationInputs(pose, {}, pose[:, :2], 0.1 * k, np.ones(2, dtype=bool))
        state, _, _ = navigation_step(state, inputs, params, 0.1)
        assert state.parked is not None
        parked.append(bool(state.parked[0]))
    assert not any(parked[:25])  # 2.5 s: not yet held up
    assert parked[-1]
    assert state.aside_of.tolist() == [1, -1]


def test_an_unreachable_goal_is_reported_and_the_robot_stays() -> None:
    occ = _walled(60, 60)
    occ[10:30, 10] = occ[10:30, 30] = occ[10, 10:31] = occ[30, 10:31] = True  # a closed room
    grid = OccupancyGrid(occ, ~occ, 0.1)
    params = NavigationParams()
    pose = np.array([[4.5, 1.0, 0.0]])
    state = navigation_init(grid, pose, [[2.0, 4.0]], params)
    assert state.status == ("unreachable",)
    inputs = NavigationInputs(pose, {}, pose[:, :2], 0.0)
    state, v, w = navigation_step(state, inputs, params, 0.1)
    assert v.tolist() == [0.0]
    assert w.tolist() == [0.0]
    assert navigation_init(grid, pose, [[1.05, 3.0]], params).status == ("goal_blocked",)


def test_bad_inputs_name_what_is_wrong() -> None:
    occ = _walled(20, 20)
    grid = OccupancyGrid(occ, ~occ, 0.1)
    params = NavigationParams()
    with pytest.raises(InputError, match="goals_m"):
        navigation_init(grid, [[1.0, 1.0, 0.0]], [[1.0, 1.0], [1.5, 1.5]], params)
    state = navigation_init(grid, [[1.0, 1.0, 0.0]], [[1.5, 1.5]], params)
    pose = np.array([[1.0, 1.0, 0.0]])
    bad = NavigationInputs(pose, {"lidar": (np.ones((1, 4)), np.zeros(3))}, pose[:, :2], 0.0)
    with pytest.raises(InputError, match="bearings of 'lidar'"):
        navigation_step(state, bad, params, 0.1)
    with pytest.raises(InputError, match="dt_s"):
        navigation_step(state, NavigationInputs(pose, {}, pose[:, :2], 0.0), params, 0.0)
    with pytest.raises(InputError, match=r"navigation\.lookahead_m"):
        NavigationParams(lookahead_m=-1.0)
    with pytest.raises(InputError, match=r"dwa\.n_v"):
        DwaParams(n_v=1)
