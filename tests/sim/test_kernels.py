"""The compiled team kernels against the NumPy composition of the library's public steps."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from firefleet import builtin_names, load_scenario, simulate
from firefleet.control.path_following import PathFollowingController, controller_inputs
from firefleet.models.kinematics import RobotGeometry, body_to_wheels
from firefleet.planning.trajectory import Trajectory
from firefleet.scenarios.schema import PathFollowing, Scenario, WheelSpeedStep
from firefleet.sim._kernels import PARALLEL_MIN_ROBOTS, run_motor_team
from firefleet.sim.drive import (
    discretise_drive,
    drive_init,
    drive_step,
    encoder_phase,
    speed_control,
)

MOTOR_SCENARIOS = [
    n
    for n in builtin_names()
    if load_scenario(n).command.kind in ("voltage-step", "wheel-speed-step")
]

POSE_ATOL = 1e-12
"""Poses go through sin and cos: the C library's in the kernel, NumPy's in the array path,
which may differ in the last bit (on the machine this was written on they do not); a run
of 1,000 steps on poses under 10 m keeps such differences below 1e-12."""


@pytest.mark.parametrize("name", MOTOR_SCENARIOS)
@pytest.mark.parametrize("n_robots", [1, 3, 70])
@pytest.mark.parametrize("counts_per_rev", [0, 2048])
def test_motor_kernel_equals_the_numpy_wheel_stack(
    name: str, n_robots: int, counts_per_rev: int
) -> None:
    # the kernel (serial for one robot, on every core for teams) against the
    # "array" backend, which steps sim.drive's speed_control and drive_step with NumPy:
    # the wheel arrays are pure IEEE arithmetic in the same order, so bit for bit
    scn = load_scenario(name)
    poses = ((0.0, 0.0, 0.0), (1.0, 2.0, 30.0), (3.0, -1.0, -170.0))
    scn = dataclasses.replace(
        scn,
        poses=tuple(poses[i % 3] for i in range(n_robots)),
        encoder=dataclasses.replace(scn.encoder, counts_per_rev=counts_per_rev),
        duration_s=3.0,
    )
    compiled = simulate(scn, seed=3).arrays()
    reference = simulate(scn, seed=3, backend="array").arrays()
    for key, arr in reference.items():
        if key == "pose":
            np.testing.assert_allclose(compiled[key], arr, rtol=0, atol=POSE_ATOL)
        else:
            np.testing.assert_array_equal(compiled[key], arr, err_msg=key)
    if counts_per_rev and scn.command.kind == "wheel-speed-step":
        # random encoder phases: the wheels really differ and the robots turn
        assert np.ptp(reference["pose"][:, 0, 2]) > 0


def test_motor_kernel_moves_with_the_true_wheels_and_axle() -> None:
    # a robot whose wheels are 2 % and -1 % off and whose axle is 5 % longer: the
    # kernel's pose follows sim.drive.drive_step with the same DriveStack
    scn = load_scenario("motor-pid")
    stack = discretise_drive(
        scn.robot,
        scn.motor,
        scn.speed_pid,
        scn.encoder,
        scn.dt_s,
        wheel_radius_scale=(1.02, 0.99),
        axle_scale=1.05,
    )
    n, n_steps = 4, 300
    pose = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [-2.0, 0.5, 3.0], [0.0, -1.0, -2.0]])
    phase = encoder_phase(scn.encoder, n, np.random.default_rng(5))
    out = run_motor_team(
        stack,
        pose,
        phase,
        open_loop=False,
        level=2.0,
        level_start_s=0.0,
        load_torque_n_m=0.3,
        load_start_s=1.0,
        n_steps=n_steps,
        rec_steps=np.arange(n_steps + 1),
    )
    state = drive_init(pose, phase, stack)
    for k in range(n_steps):
        state, volt = speed_control(state, np.full((n, 2), 2.0), stack)
        np.testing.assert_array_equal(out["voltage"][k], volt)
        load = 0.3 if k * scn.dt_s >= 1.0 - 1e-9 else 0.0
        state = drive_step(state, volt, stack, load_torque_n_m=load)
        np.testing.assert_array_equal(out["measured"][k + 1], state.measured_rad_s)
        np.testing.assert_allclose(out["pose"][k + 1], state.pose, rtol=0, atol=POSE_ATOL)
    # both wheels turn some 6 rad in 3 s, so the true radii turn the robot by about
    # r (1.02 - 0.99) 6 / (1.05 L) = 0.039 rad (nominal wheels: a few mrad at most)
    assert out["pose"][-1, 0, 2] == pytest.approx(0.039, abs=0.004)


def test_motor_kernel_progress_is_reported_and_changes_nothing() -> None:
    scn = load_scenario("motor-pid")
    calls: list[tuple[int, int]] = []
    quiet = simulate(scn).arrays()
    loud = simulate(scn, progress=lambda done, total: calls.append((done, total))).arrays()
    for key, arr in quiet.items():
        np.testing.assert_array_equal(loud[key], arr, err_msg=key)
    assert calls[-1] == (scn.n_steps, scn.n_steps)
    assert len(calls) >= 50
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)


# Values of coop-different-paths recorded from main's path-following kernel before it was
# rebuilt from the models' compiled steps (commit e41e726, x86-64, glibc's sin and cos):
# step 8000 (the end) of the true and the dead-reckoned poses (3 robots x (x, y, theta))
# and the voltages at step 4000 (3 robots x (right, left)).
MAIN_POSE_END = [
    "0x1.f37fb33f9c8c0p+3",
    "0x1.36b2cdef32f56p+1",
    "-0x1.17fa997306800p-8",
    "0x1.3db5679009a29p+4",
    "0x1.c4526d14e3e43p-3",
    "-0x1.3d8068bd5c000p-9",
    "0x1.92cdb8ab75e7fp+4",
    "-0x1.e5e86a43fea5fp-1",
    "-0x1.14f0ed1bbe000p-11",
]
MAIN_ODOMETRY_END = [
    "0x1.f391f863c4eabp+3",
    "0x1.3733d8bd3bc1dp+1",
    "-0x1.05616905f8600p-8",
    "0x1.3db5c41c37a13p+4",
    "0x1.c5367c6e38a8ap-3",
    "-0x1.f6a7a29553000p-10",
    "0x1.92ccf2ca2256ap+4",
    "-0x1.e6d25f24172d1p-1",
    "-0x1.197c987c95000p-11",
]
MAIN_VOLTAGE_4000 = [
    "0x1.26efcb2223512p+2",
    "0x1.237838af2b4a5p+2",
    "0x1.588801b557ee2p+2",
    "0x1.557075e4e0ce4p+2",
    "0x1.91a30f94e315dp+2",
    "0x1.8fce2a75c70f1p+2",
]


def _hex(values: list[str]) -> np.ndarray:
    return np.array([float.fromhex(v) for v in values])


# coop-different-paths' paths 1 and 2 as they were when the numbers above were pinned
# (main at e41e726); the scenario's paths now leave their start climbing (Figure 34).
MAIN_PATHS_1_2 = (
    (
        (
            11.430300023807044,
            -7.1444037271913805e-06,
            0.0007148985522853329,
            -0.02387577949400721,
            0.0022923670124682777,
            -5.8767259772699115e-05,
        ),
        15.59302128317522,
    ),
    (
        (
            6.720700008344271,
            -2.503912445825743e-06,
            0.0002505174609547687,
            -0.008363205789802467,
            0.0006313999745830191,
            -1.2724544451591667e-05,
        ),
        19.838253962570413,
    ),
)


def _coop_as_on_main() -> Scenario:
    from firefleet.planning.paths import PolynomialPath

    scn = load_scenario("coop-different-paths")
    cmd = scn.command
    assert isinstance(cmd, PathFollowing)
    old = tuple(
        PolynomialPath(coefficients=c, x_start_m=0.01, x_end_m=x_end) for c, x_end in MAIN_PATHS_1_2
    )
    paths = (*old, cmd.paths[2])
    return dataclasses.replace(scn, command=dataclasses.replace(cmd, paths=paths), claims=())


def test_path_following_kernel_equals_mains_kernel_bit_for_bit() -> None:
    # the same operations in the same order as the kernel it replaced: the same doubles,
    # 80 s of three robots with quantised encoders (a changed bit would grow)
    res = simulate(_coop_as_on_main())
    np.testing.assert_array_equal(res.pose[-1].ravel(), _hex(MAIN_POSE_END))
    np.testing.assert_array_equal(res.extra["odometry_pose"][-1].ravel(), _hex(MAIN_ODOMETRY_END))
    np.testing.assert_array_equal(res.voltage_v[4000].ravel(), _hex(MAIN_VOLTAGE_4000))


def test_path_following_kernel_equals_the_public_functions_step_by_step() -> None:
    # the library's public functions composed with NumPy, step by step: the trajectory's
    # desired point, controller_inputs (eqs. 9-11) on the odometry, the controller's
    # command (the two fuzzy systems), body_to_wheels, and sim.drive's speed_control and
    # drive_step with odometry. 3,000 steps (30 s), before any robot nears its path's
    # end (no arrival rule, no extrapolation past the last point).
    scn = load_scenario("coop-different-paths")
    cmd = scn.command
    assert isinstance(cmd, PathFollowing)
    n_steps = 3000
    res = simulate(scn)  # compared over its first n_steps
    ctl = PathFollowingController.from_command(cmd)
    traj = Trajectory.from_paths(cmd.paths, pieces=cmd.pieces, duration_s=cmd.trajectory_s)
    assert traj.index(n_steps * scn.dt_s) < traj.pieces
    stack = discretise_drive(scn.robot, scn.motor, scn.speed_pid, scn.encoder, scn.dt_s)
    phase = encoder_phase(scn.encoder, scn.n_robots, np.random.default_rng(scn.seed))
    state = drive_init(scn.initial_poses, phase, stack, odometry=True)
    geometry = RobotGeometry(scn.robot.wheel_radius_m, scn.robot.axle_length_m)
    worst = {"pose": 0.0, "odometry": 0.0, "v": 0.0, "voltage": 0.0}
    for k in range(n_steps):
        t = k * scn.dt_s
        assert state.odometry is not None
        inputs = controller_inputs(state.odometry, traj.desired(t))
        v, omega, _ = ctl.command(inputs)
        state, volt = speed_control(state, body_to_wheels(v, omega, geometry), stack)
        load = scn.load.torque_n_m if t >= scn.load.start_s - 1e-9 else 0.0
        state = drive_step(state, volt, stack, load_torque_n_m=load)
        assert state.odometry is not None
        worst["v"] = max(worst["v"], float(np.abs(res.extra["v_ref_m_s"][k] - v).max()))
        worst["voltage"] = max(worst["voltage"], float(np.abs(res.voltage_v[k] - volt).max()))
        worst["pose"] = max(worst["pose"], float(np.abs(res.pose[k + 1] - state.pose).max()))
        worst["odometry"] = max(
            worst["odometry"],
            float(np.abs(res.extra["odometry_pose"][k + 1] - state.odometry).max()),
        )
    # The two differ in rounding only: body_to_wheels computes (2 v + omega L) / (2 r)
    # where the kernel computes (v + L omega / 2) / r, and the fuzzy evaluation sums in
    # another order (1e-16 relative each). Measured: 1.1e-16 m/s in v, 6.4e-14 V, and
    # 8.7e-13 m in the true pose after 3,000 steps; the odometry is equal bit for bit
    # (the same counts). An encoder count flipped by such a difference would show as
    # 0.15 rad/s, some 1e-3 m: the bounds leave 100 times the measured room.
    assert worst["v"] < 1e-13
    assert worst["voltage"] < 1e-11
    assert worst["pose"] < 1e-10
    assert worst["odometry"] < 1e-10


def test_parallel_motor_kernel_equals_serial() -> None:
    base = load_scenario("motor-pid")
    n = PARALLEL_MIN_ROBOTS + 3
    team = dataclasses.replace(base, poses=((0.0, 0.0, 0.0),) * n, duration_s=2.0)
    together = simulate(team, seed=11)
    phase = encoder_phase(base.encoder, n, np.random.default_rng(11))
    stack = discretise_drive(base.robot, base.motor, base.speed_pid, base.encoder, base.dt_s)
    cmd = base.command
    assert isinstance(cmd, WheelSpeedStep)
    for i in (0, n // 2, n - 1):
        alone = run_motor_team(
            stack,
            np.zeros((1, 3)),
            phase[i : i + 1],
            open_loop=False,
            level=cmd.speed_rad_s,
            level_start_s=cmd.start_s,
            load_torque_n_m=base.load.torque_n_m,
            load_start_s=base.load.start_s,
            n_steps=team.n_steps,
            rec_steps=np.arange(team.n_steps + 1),
        )
        np.testing.assert_array_equal(alone["pose"][:, 0], together.pose[:, i])
        np.testing.assert_array_equal(alone["voltage"][:, 0], together.voltage_v[:, i])


def test_path_following_in_pieces_equals_one_piece() -> None:
    # with a progress callback the run goes in 100 pieces, without one in one piece: the
    # state carried from piece to piece makes them the same run
    scn = load_scenario("coop-different-paths")
    calls: list[int] = []
    pieces = simulate(scn, progress=lambda done, total: calls.append(done)).arrays()
    whole = simulate(scn).arrays()
    assert len(calls) >= 50
    for key, arr in whole.items():
        np.testing.assert_array_equal(pieces[key], arr, err_msg=key)
