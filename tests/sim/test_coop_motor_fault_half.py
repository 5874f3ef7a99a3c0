"""Why coop-motor-fault is not the issue's half voltage from 20 s to 40 s (the measured
reason written in the scenario): experiment 1 needs under half of robot 2's supply on
average, so halving its voltage, as a scale or as a cap at 6 V, leaves every arrival as it
is and the open-loop clock passes too."""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np
import pytest

from firefleet import load_scenario
from firefleet.scenarios._network import MotorFault
from firefleet.scenarios.schema import PathFollowing
from firefleet.sim.kinds.path_following import path_following_metrics
from firefleet.sim.registry import task_kind
from firefleet.sim.result import SimResult

KIND = task_kind("path-following")


Mode = Literal["closed", "clock"]


def _arrivals(coordination: Mode, faults: tuple[MotorFault, ...]) -> tuple[list[float], SimResult]:
    base = load_scenario("coop-motor-fault")
    assert isinstance(base.command, PathFollowing)
    scn = dataclasses.replace(
        base,
        faults=faults,
        command=dataclasses.replace(base.command, coordination=coordination),
    )
    result = KIND.run(scn, np.arange(0, scn.n_steps + 1))
    return list(path_following_metrics(result)["arrival_time_s"]), result  # type: ignore[arg-type]


def test_robot_2_needs_under_half_its_supply_on_average() -> None:
    _, result = _arrivals("closed", ())
    t = result.t
    window = (t >= 20.0) & (t < 40.0)
    volts = np.abs(result.voltage_v[window, 1])
    supply = load_scenario("coop-motor-fault").motor.supply_v
    assert volts.mean() < 0.45 * supply  # 4.8 V of 12 V
    assert 0.5 * supply < volts.max() < 0.6 * supply  # 6.5 V at a speed change
    # back-EMF at the fastest wheel: under half the supply (the need is the EMF plus R i)
    omega = np.abs(result.wheel_speed_rad_s[window, 1]).max()
    assert 0.65 * omega < 0.5 * supply


@pytest.mark.parametrize("coordination", ["closed", "clock"])
def test_half_voltage_from_20_to_40_s_leaves_the_arrivals(coordination: Mode) -> None:
    clean, _ = _arrivals(coordination, ())
    half, _ = _arrivals(coordination, (MotorFault(robot=2, start_s=20.0, end_s=40.0),))
    np.testing.assert_allclose(half, clean, atol=0.011)
    assert max(half) - min(half) <= 0.5  # the clock does not fail under it
