"""The simulator: determinism, team batching, built-in scenarios and their claims."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, Literal

import numpy as np
import pytest

from firefleet import builtin_names, compute_metrics, load_scenario, simulate
from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams
from firefleet.sim.metrics import metrics_document


def test_same_seed_same_arrays_bit_for_bit() -> None:
    scn = load_scenario("motor-pid")
    a, b = simulate(scn, seed=7), simulate(scn, seed=7)
    for name, arr in a.arrays().items():
        np.testing.assert_array_equal(arr, b.arrays()[name], err_msg=name)


def test_seed_changes_the_encoder_phase() -> None:
    scn = load_scenario("motor-pid")
    a, b = simulate(scn, seed=1), simulate(scn, seed=2)
    assert not np.array_equal(a.wheel_speed_measured_rad_s, b.wheel_speed_measured_rad_s)


@pytest.mark.parametrize("backend", ["auto", "array"])
def test_team_run_equals_single_robot_runs(backend: Literal["auto", "array"]) -> None:
    # With an ideal encoder the run has no randomness, so a team of three must equal
    # three single-robot runs, robot by robot (batch-first arrays, no per-robot state mixing).
    base = dataclasses.replace(
        load_scenario("motor-pid"), encoder=EncoderParams(counts_per_rev=0), duration_s=1.0
    )
    poses = ((0.0, 0.0, 0.0), (1.0, -2.0, 30.0), (-3.0, 0.5, -120.0))
    team = simulate(dataclasses.replace(base, poses=poses), backend=backend)
    for i, pose in enumerate(poses):
        one = simulate(dataclasses.replace(base, poses=(pose,)), backend=backend)
        for name, arr in one.arrays().items():
            if name == "t":
                continue
            np.testing.assert_array_equal(team.arrays()[name][:, i], arr[:, 0], err_msg=name)


def test_open_loop_robot_drives_straight_at_r_times_speed() -> None:
    scn = load_scenario("motor-open-loop")
    res = simulate(scn)
    # both wheels identical: heading unchanged, distance = r * integral of wheel speed
    np.testing.assert_allclose(res.pose[:, 0, 2], 0.0, atol=1e-12)
    np.testing.assert_allclose(res.pose[:, 0, 1], 0.0, atol=1e-12)
    w = res.wheel_speed_rad_s[:, 0, 0]
    # trapezoid of the recorded speed vs the exact angle: the speed is smooth, 10 ms steps
    distance = scn.robot.wheel_radius_m * np.sum((w[1:] + w[:-1]) / 2) * scn.dt_s
    assert res.pose[-1, 0, 0] == pytest.approx(distance, rel=1e-4)


def test_record_every_subsamples_the_same_run() -> None:
    scn = load_scenario("motor-pid")
    full, sparse = simulate(scn), simulate(scn, record_every=7)
    idx = np.r_[np.arange(0, scn.n_steps + 1, 7), scn.n_steps]
    np.testing.assert_array_equal(sparse.t, full.t[idx])
    np.testing.assert_array_equal(sparse.pose, full.pose[idx])


def test_bad_engine_arguments() -> None:
    scn = load_scenario("motor-pid")
    with pytest.raises(InputError, match="record_every"):
        simulate(scn, record_every=0)
    with pytest.raises(InputError, match="seed"):
        simulate(scn, seed=-1)
    with pytest.raises(InputError, match="backend"):
        simulate(scn, backend="gpu")  # type: ignore[arg-type]


MISSIONS = tuple(n for n in builtin_names() if load_scenario(n).command.kind == "mission")
"""Built-ins run once in the suite: the report (tests/test_cli.py::test_reproduce_writes_report)
runs every built-in and asserts every claim, and the check below reads that same run
(tests/conftest.py's ``builtin_document``) when the session runs the report; a session
without it simulates the cheap kinds here (the missions take minutes: the report only)."""


@pytest.mark.parametrize("name", [n for n in builtin_names() if n not in MISSIONS])
def test_builtin_scenario_claims_hold(
    name: str, builtin_document: Callable[[str], dict[str, Any]]
) -> None:
    scn = load_scenario(name)
    document = builtin_document(name)
    assert document["scenario"] == name
    assert set(document) - {"scenario", "claims"} == set(scn.metric_names)
    assert document["claims"], "every built-in scenario checks at least one claim"
    assert len(document["claims"]) >= len(scn.claims)
    failed = [c for c in document["claims"] if not c["passed"]]
    assert not failed, failed


@pytest.mark.parametrize("seed", range(1, 11))
def test_motor_pid_claims_hold_for_any_encoder_phase(seed: int) -> None:
    # The claims must not hinge on a lucky seed: the encoder's phase is random.
    scn = load_scenario("motor-pid")
    metrics = compute_metrics(simulate(scn, seed=seed))
    failed = [
        c for c in metrics_document(scn.name, scn.claims, metrics)["claims"] if not c["passed"]
    ]
    assert not failed, failed


def test_open_loop_steady_speed_is_the_analytic_value() -> None:
    scn = load_scenario("motor-open-loop")
    m = compute_metrics(simulate(scn))
    p = scn.motor
    analytic = p.torque_n_m_a / (
        p.resistance_ohm * p.damping_n_m_s + p.back_emf_v_s * p.torque_n_m_a
    )
    # 10 s is 55 slow time constants (0.18 s): the transient is gone to machine precision
    assert m["steady_speed_rad_s"] == pytest.approx(analytic, rel=1e-9)
    assert m["steady_current_a"] == pytest.approx(
        p.damping_n_m_s * analytic / p.torque_n_m_a, rel=1e-9
    )
