"""The world loop: its stages, and the fused (compiled) loops against the staged one."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from firefleet import builtin_names, load_scenario
from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams
from firefleet.scenarios import parse_scenario
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim.drive import discretise_drive, drive_init, drive_step, encoder_phase
from firefleet.sim.loop import (
    DecideInputs,
    Decider,
    IdealLink,
    NoEstimation,
    Stages,
    StaticWorld,
    WheelCommand,
    default_stages,
    run_loop,
)
from firefleet.sim.registry import task_kind

# The staged loop is the composition of the library's public functions, tick by tick:
# Trajectory.desired, controller_inputs, PathFollowingController.command, arrival,
# body_to_wheels, speed_control, drive_step (and dead_reckoning for the odometry). The
# compiled loop must do the same arithmetic but for the order of a few operations
# (body_to_wheels' (2 v + w L) / 2r against the kernel's (v + L w / 2) / r; NumPy's
# against libm's sin and cos): 1e-12 rad/s on the wheels and 1e-11 m on the poses over
# 3,000 steps (measured: 9e-13 m).
POSE_ATOL = 1e-11
ATOL = 1e-12


def _short(scn: Scenario, steps: int) -> Scenario:
    """The scenario cut to at most ``steps`` steps (the trajectory ending before)."""
    duration = min(scn.duration_s, steps * scn.dt_s)
    cmd = scn.command
    if isinstance(cmd, PathFollowing):
        cmd = dataclasses.replace(cmd, trajectory_s=min(cmd.trajectory_s, 0.8 * duration))
    return dataclasses.replace(scn, duration_s=duration, command=cmd)


def _fused_and_staged(scn: Scenario) -> tuple[dict[str, Any], dict[str, Any]]:
    kind = task_kind(scn.command.kind)
    assert kind.decider is not None
    rec = np.arange(scn.n_steps + 1)
    fused = run_loop(scn, kind.decider, rec, fused=kind.fused).arrays()
    staged = run_loop(scn, kind.decider, rec, stages=default_stages(scn, kind.decider)).arrays()
    assert list(fused) == list(staged)
    return fused, staged


def _assert_close(fused: dict[str, Any], staged: dict[str, Any]) -> None:
    for key, arr in fused.items():
        atol = POSE_ATOL if key == "pose" else ATOL
        np.testing.assert_allclose(staged[key], arr, rtol=0, atol=atol, err_msg=key)


def test_fused_path_following_equals_the_public_functions_step_by_step() -> None:
    # two robots on short paths, 3,000 steps: they catch their paths, the schedule goes
    # past the end (the extension) and both stop there (the stop rule)
    scn = parse_scenario(
        {
            "name": "short",
            "title": "two short paths",
            "duration_s": 30.0,
            "poses": [[0.0, -0.3, 20.0], [0.0, 1.0, 0.0]],
            "command": {
                "kind": "path-following",
                "paths": [
                    {"coefficients": [0.0, 0.0], "x_start_m": 0.0, "x_end_m": 4.0},
                    {"coefficients": [1.0, 0.2, -0.03], "x_start_m": 0.0, "x_end_m": 5.0},
                ],
                "trajectory_s": 18.0,
                "pieces": 60,
            },
        }
    )
    fused, staged = _fused_and_staged(scn)
    _assert_close(fused, staged)
    assert fused["desired_index"].max() > 60  # the schedule went past the end
    stopped = (fused["v_ref_m_s"][-1] == 0.0) & (fused["omega_ref_rad_s"][-1] == 0.0)
    assert stopped.all()  # and both robots stopped at their ends
    np.testing.assert_array_equal(staged["v_ref_m_s"] == 0.0, fused["v_ref_m_s"] == 0.0)


FUSED_SCENARIOS = [
    name
    for name in builtin_names()
    if (kind := task_kind(load_scenario(name).command.kind)).decider is not None
    and kind.fused is not None
]


@pytest.mark.parametrize("name", FUSED_SCENARIOS)
def test_every_fused_loop_equals_the_staged_loop(name: str) -> None:
    fused, staged = _fused_and_staged(_short(load_scenario(name), 1500))
    _assert_close(fused, staged)


def test_static_world_steps_the_load_and_the_ideal_link_delivers_as_sent() -> None:
    world = StaticWorld(torque_n_m=0.02, start_s=1.0)
    state = world.init(3)
    np.testing.assert_array_equal(world.step(state, 0.5).load_torque_n_m, np.zeros((3, 2)))
    # the load is on from start_s (1e-9 s of slack for k * dt)
    np.testing.assert_array_equal(world.step(state, 1.0 - 1e-12).load_torque_n_m, 0.02)
    sent = {"x_m": np.arange(3.0)}
    assert IdealLink().exchange(None, sent, 0.0, np.zeros((3, 3)))[0] is sent


def _probe(scenario: Scenario) -> tuple[list[Any], None]:
    return [], None


def _probe_decide(
    seen: list[Any], inputs: DecideInputs, params: None, dt_s: float
) -> tuple[list[Any], WheelCommand]:
    # turn in place at different speeds per robot; echo the time as a message
    seen.append((inputs.t_s, inputs.pose_estimate, dict(inputs.inbox)))
    n = inputs.pose_estimate.shape[0] if inputs.pose_estimate is not None else 2
    ref = np.stack([np.linspace(5.0, 10.0, n), np.linspace(-5.0, 2.0, n)], axis=1)
    return seen, WheelCommand(
        reference_rad_s=ref,
        series={"t_echo_s": np.full(n, inputs.t_s)},
        outbox={"t_s": np.array([inputs.t_s])},
    )


def test_stage_order_odometry_link_and_recording() -> None:
    # a decision that records what it sees: the odometry at tick k integrates the counts
    # of the k drive steps before it; the link delivers last tick's messages
    scn = dataclasses.replace(
        load_scenario("motor-pid"),
        duration_s=0.2,
        poses=((0.0, 0.0, 0.0), (1.0, 2.0, 30.0)),
        encoder=EncoderParams(counts_per_rev=512, window_steps=2),
    )
    decider = Decider(init=_probe, decide=_probe_decide, series=("t_echo_s",), uses_estimate=True)
    seen: list[Any] = []

    def init(scenario: Scenario) -> tuple[list[Any], None]:
        return seen, None

    decider = dataclasses.replace(decider, init=init)
    result = run_loop(scn, decider, np.array([0, 7, scn.n_steps]))
    assert len(seen) == scn.n_steps + 1
    np.testing.assert_array_equal(result.extra["t_echo_s"][:, 0], [0.0, 7 * scn.dt_s, 0.2])
    assert seen[0][2] == {}
    assert seen[5][2]["t_s"][0] == seen[4][0]
    # the reference: the wheel stack alone, with its own odometry, the same references
    rng = np.random.default_rng(scn.seed)
    stack = discretise_drive(scn.robot, scn.motor, scn.speed_pid, scn.encoder, scn.dt_s)
    drive = drive_init(scn.initial_poses, encoder_phase(scn.encoder, 2, rng), stack, odometry=True)
    ref = np.stack([np.linspace(5.0, 10.0, 2), np.linspace(-5.0, 2.0, 2)], axis=1)
    from firefleet.sim.drive import speed_control

    for k in range(scn.n_steps + 1):
        np.testing.assert_array_equal(seen[k][1], drive.odometry, err_msg=f"tick {k}")
        if k in (0, 7, scn.n_steps):
            row = [0, 7, scn.n_steps].index(k)
            np.testing.assert_array_equal(result.pose[row], drive.pose)
        drive, volt = speed_control(drive, ref, stack)
        drive = drive_step(drive, volt, stack)
    assert np.ptp(result.pose[:, :, 2]) > 0  # the robots did turn


def test_a_kind_without_estimate_sees_none() -> None:
    scn = dataclasses.replace(
        load_scenario("motor-pid"), duration_s=0.05, poses=((0.0, 0.0, 0.0),) * 2
    )
    seen: list[Any] = []

    def init(scenario: Scenario) -> tuple[list[Any], None]:
        return seen, None

    decider = Decider(init=init, decide=_probe_decide)
    stages = Stages(world=StaticWorld(), estimation=NoEstimation())
    run_loop(scn, decider, np.array([scn.n_steps]), stages=stages)
    assert all(s[1] is None for s in seen)
    assert stages.names()["estimation"] == "NoEstimation"


def test_backend_array_runs_the_staged_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    # the same run as the fused one, to the tolerance above, through the public entry point
    from firefleet import simulate
    from firefleet.sim import loop

    calls: list[int] = []
    staged_run = loop.run_staged

    def counted(*args: Any, **kwargs: Any) -> loop.Recording:
        calls.append(1)
        return staged_run(*args, **kwargs)

    monkeypatch.setattr(loop, "run_staged", counted)
    scn = _short(load_scenario("path-curved-off"), 600)
    fused = simulate(scn).arrays()
    assert not calls  # the compiled loop
    staged = simulate(scn, backend="array").arrays()
    assert calls == [1]
    _assert_close(fused, staged)


def test_run_loop_refuses_recording_steps_that_miss_the_end() -> None:
    scenario = load_scenario("motor-pid")
    decider = task_kind(scenario.command.kind).decider
    assert decider is not None
    with pytest.raises(InputError, match="end at the last step 1000"):
        run_loop(scenario, decider, np.array([0, 100, 200]))
    with pytest.raises(InputError, match="rise strictly"):
        run_loop(scenario, decider, np.array([0, 200, 100, 1000]))
