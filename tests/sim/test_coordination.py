"""Closed-loop x-coordination (issue 16): the law, the fault, fused == staged."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from firefleet import load_scenario
from firefleet.control.coordination import coordinated_release, heard_minimum
from firefleet.errors import InputError
from firefleet.scenarios import parse_scenario
from firefleet.scenarios.schema import MotorFault, PathFollowing, Scenario
from firefleet.sim.kinds.path_following import path_following_metrics
from firefleet.sim.loop import default_stages, run_loop
from firefleet.sim.registry import task_kind

from .test_loop import _assert_close


def _with(scn: Scenario, **command: Any) -> Scenario:
    assert isinstance(scn.command, PathFollowing)
    return dataclasses.replace(scn, command=dataclasses.replace(scn.command, **command))


def _metrics(scn: Scenario, *, staged: bool = False) -> dict[str, Any]:
    kind = task_kind("path-following")
    result = kind.run(scn, np.arange(0, scn.n_steps + 1, 10), staged=staged)
    return dict(path_following_metrics(result))


def test_coop_motor_fault_passes_closed_loop_and_fails_on_the_clock() -> None:
    scn = load_scenario("coop-motor-fault")
    closed = _metrics(scn)
    clock = _metrics(_with(scn, coordination="clock"))
    assert closed["arrival_spread_s"] <= 0.5  # measured 0.1 s
    assert clock["arrival_spread_s"] > 0.5  # measured 1.8 s: robot 2 arrives late
    # the team waited for robot 2: later than on the clock, and together
    assert min(closed["arrival_time_s"]) > max(
        clock["arrival_time_s"][0], clock["arrival_time_s"][2]
    )


def test_the_fault_slows_the_robot_and_without_it_closed_equals_the_clock_bit_for_bit() -> None:
    scn = load_scenario("coop-different-paths")  # the whole run: the law never holds
    kind = task_kind("path-following")
    rec = np.arange(0, scn.n_steps + 1, 10)
    closed = kind.run(_with(scn, coordination="closed"), rec).arrays()
    clock = kind.run(_with(scn, coordination="clock"), rec).arrays()
    for key, value in clock.items():
        if key != "message_age_max_s":  # nothing is heard on the clock
            np.testing.assert_array_equal(closed[key], value, err_msg=key)
    np.testing.assert_array_equal(closed["message_age_max_s"][1:], scn.dt_s)


def _fault_scenario() -> Scenario:
    scn = _with(load_scenario("coop-different-paths"), trajectory_s=14.0, pieces=60)
    return dataclasses.replace(
        scn,
        duration_s=16.0,
        faults=(MotorFault(robot=2, start_s=3.0, end_s=8.0, voltage_scale=0.0),),
    )


@pytest.mark.parametrize("coordination", ["closed", "clock"])
def test_fused_equals_staged_with_a_fault(coordination: str) -> None:
    scn = _with(_fault_scenario(), coordination=coordination)
    kind = task_kind("path-following")
    assert kind.decider is not None
    rec = np.arange(scn.n_steps + 1)
    fused = run_loop(scn, kind.decider, rec, fused=kind.fused).arrays()
    staged = run_loop(scn, kind.decider, rec, stages=default_stages(scn, kind.decider)).arrays()
    _assert_close(fused, staged)
    # robot 2's motors got nothing from 3 s to 8 s
    t = fused["t"]
    window = (t >= 3.0 + 1e-9) & (t < 8.0 - 1e-9)
    assert np.all(fused["voltage_v"][window, 1] == 0.0)
    assert np.any(fused["voltage_v"][window, 0] != 0.0)
    j = fused["desired_index"]
    clock = np.floor(t / (14.0 / 60) + 1e-9) + 1
    if coordination == "closed":  # the team held its points for robot 2, together
        assert np.all(j[-1] < clock[-1] - 5)
        assert np.ptp(j[t > 8.0], axis=1).max() == 0
    else:
        np.testing.assert_array_equal(j, np.repeat(clock[:, None], 3, axis=1))


def test_the_law_against_its_definition() -> None:
    rng = np.random.default_rng(3)
    for _ in range(200):
        n = 4
        zeta = rng.uniform(0, 50, (n, n))
        rate = rng.uniform(0, 3, (n, n))
        age = rng.uniform(0, 2, (n, n))
        zmin, age_max, stale = heard_minimum(zeta, rate, age, 1.0)
        for i in range(n):
            fresh = [m for m in range(n) if age[i, m] <= 1.0]
            assert stale[i] == n - len(fresh)
            if fresh:
                assert zmin[i] == min(zeta[i, m] + rate[i, m] * age[i, m] for m in fresh)
                assert age_max[i] == max(age[i, m] for m in fresh)
            else:
                assert np.isnan(zmin[i])
                assert np.isnan(age_max[i])
        released = rng.integers(0, 40, n)
        held = rng.integers(0, 30, n)
        k = int(rng.integers(100, 4000))
        j, held2 = coordinated_release(released, held, k, 0.01, 0.35, zmin, 10)
        for i in range(n):
            c = int(np.floor((k - held[i]) * 0.01 / 0.35 + 1e-9)) + 1
            hold = not np.isnan(zmin[i]) and c > released[i] and c > np.floor(zmin[i]) + 10
            assert (j[i], held2[i]) == ((released[i], held[i] + 1) if hold else (c, held[i]))


@pytest.mark.parametrize(
    ("fault", "message"),
    [
        ({"robot": 4, "start_s": 1.0, "end_s": 2.0}, "faults.robot = 4"),
        ({"robot": 1, "start_s": 2.0, "end_s": 1.0}, "faults.end_s"),
        ({"robot": 1, "start_s": 1.0, "end_s": 2.0, "voltage_scale": 1.5}, "voltage_scale"),
    ],
)
def test_bad_faults_name_the_key(fault: dict[str, float], message: str) -> None:
    data = {
        "name": "x",
        "title": "x",
        "duration_s": 1.0,
        "poses": [[0, 0, 0]] * 3,
        "command": {"kind": "wheel-speed-step", "speed_rad_s": 1.0},
        "faults": [fault],
    }
    with pytest.raises(InputError, match=message):
        parse_scenario(data)
