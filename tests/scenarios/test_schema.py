"""The scenario schema: strict parsing, clear errors naming the field."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.scenarios import load_scenario, parse_scenario, read_scenario_file
from firefleet.scenarios.schema import Claim

MINIMAL: dict[str, Any] = {
    "name": "t",
    "title": "test",
    "duration_s": 1.0,
    "command": {"kind": "voltage-step", "voltage_v": 1.0},
}


def _with(**changes: Any) -> dict[str, Any]:
    return {**MINIMAL, **changes}


def test_minimal_scenario_gets_table2_defaults() -> None:
    scn = parse_scenario(MINIMAL)
    # Table 2 of the deliverable
    assert scn.motor.resistance_ohm == 3.07
    assert scn.motor.inductance_h == 0.04
    assert scn.robot.wheel_radius_m == 0.045
    assert scn.robot.axle_length_m == 0.2
    assert scn.dt_s == 0.01  # the deliverable's fixed step
    assert scn.n_steps == 100


def test_heading_is_typed_in_degrees_and_stored_in_radians() -> None:
    scn = parse_scenario(_with(poses=[[1.0, 2.0, 90.0], [0.0, 0.0, -45.0]]))
    np.testing.assert_allclose(scn.initial_poses, [[1, 2, np.pi / 2], [0, 0, -np.pi / 4]])


@pytest.mark.parametrize(
    ("data", "fragment"),
    [
        (
            _with(motor={"resistnce_ohm": 2.0}),
            "motor.resistnce_ohm: unknown key; did you mean 'resistance_ohm'?",
        ),
        (_with(duraton_s=1.0), "duraton_s: unknown key; did you mean 'duration_s'?"),
        (
            _with(command={"kind": "voltage-step", "voltage": 1.0}),
            "command.voltage: unknown key; did you mean 'voltage_v'?",
        ),
        (_with(dt_s=-0.01), "dt_s must be > 0, got -0.01"),
        (_with(poses=[[0.0, 0.0]]), "poses[0][2]: required, missing"),
        (
            _with(motor={"resistance_ohm": "3.07"}),
            "motor.resistance_ohm: Input should be a valid number",
        ),
        (
            _with(motor={"resistance_ohm": True}),
            "motor.resistance_ohm: Input should be a valid number",
        ),
        (_with(motor={"resistance_ohm": -1.0}), "motor.resistance_ohm must be > 0, got -1.0"),
        (_with(command={"kind": "torque-step"}), "command: Input tag 'torque-step'"),
        (_with(encoder={"window_steps": 0}), "encoder.window_steps must be >= 1"),
        (_with(speed_pid={"output_limit": 24.0}), "exceeds motor.supply_v (12.0 V)"),
        (
            _with(claims=[{"metric": "steady_sped_rad_s", "op": "<", "value": 1.0}]),
            "did you mean 'steady_speed_rad_s'?",
        ),
        (
            _with(claims=[{"metric": "peak_current_a", "op": "~", "value": 1.0}]),
            "needs rel_tol > 0",
        ),
        (["not", "a", "mapping"], "a scenario must be a mapping, got list"),
    ],
)
def test_bad_scenarios_name_the_problem(data: Any, fragment: str) -> None:
    with pytest.raises(InputError) as info:
        parse_scenario(data)
    assert fragment in str(info.value)


def test_every_problem_is_reported_on_its_own_line() -> None:
    with pytest.raises(InputError) as info:
        parse_scenario(_with(motor={"resistnce_ohm": 2.0}, robot={"wheel_radius": 0.1}))
    lines = str(info.value).splitlines()
    assert len(lines) == 2
    assert any("motor.resistnce_ohm" in line for line in lines)
    assert any(
        "robot.wheel_radius: unknown key; did you mean 'wheel_radius_m'?" in line for line in lines
    )


def test_file_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_scenario_file(tmp_path / "absent.yaml")
    dup = tmp_path / "dup.yaml"
    dup.write_text("name: a\nname: b\n")
    with pytest.raises(InputError, match="line 2: duplicate key 'name'"):
        read_scenario_file(dup)
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: [unclosed\n")
    with pytest.raises(InputError, match="not valid YAML"):
        read_scenario_file(broken)


def test_unknown_builtin_suggests_close_names() -> None:
    with pytest.raises(InputError, match="did you mean motor-pid"):
        load_scenario("motor-pdi")


def test_claims_check_their_bound() -> None:
    scn = parse_scenario(
        _with(
            claims=[
                {"metric": "steady_speed_rad_s", "op": "~", "value": 1.3955, "rel_tol": 0.005},
                {"metric": "peak_current_a", "op": "<", "value": 1.0},
            ]
        )
    )
    near, below = scn.claims
    assert near.holds(1.3955 * 1.004)
    assert not near.holds(1.3955 * 1.006)
    assert below.holds(0.99)
    assert not below.holds(1.0)
    assert not below.holds(float("nan"))
    assert near.expected == "1.3955 \u00b1 0.00698"  # 0.5 % of 1.3955, in rad/s


def test_claims_on_per_robot_metrics() -> None:
    every = Claim(metric="wait_time_s", op=">", value=0.0)
    second = Claim(metric="wait_time_s", op="<=", value=0.0, robot=2)
    waits = [3.5, 0.0, 1.25]
    # without a robot, every entry must satisfy the claim
    assert not every.holds(waits)
    assert every.holds([3.5, 0.1])
    assert second.holds(waits)
    assert second.select(waits) == 0.0
    assert second.label == "wait_time_s[robot 2]"
    # a robot the metric does not have, a scalar metric, NaN: the claim fails
    assert not Claim(metric="wait_time_s", op=">", value=0.0, robot=4).holds(waits)
    assert not second.holds(1.0)
    assert not every.holds([1.0, float("nan")])
    assert not every.holds([])


def test_claim_robots_are_numbered_from_one() -> None:
    claim = {"metric": "steady_speed_rad_s", "op": ">", "value": 0.0, "robot": 0}
    with pytest.raises(InputError, match=r"claims\[0\]: claim on steady_speed_rad_s: robot"):
        parse_scenario(_with(claims=[claim]))
