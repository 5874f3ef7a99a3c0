"""The mission's smoke switches: ``command.perception``, ``command.stereo_team``,
``command.arrive_s`` and ``world.fuel.smoke_yield`` (bad input, one line, exit 2), and a
short run of a stereo-only team."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import firefleet
from firefleet.sim.kinds.mission import METRIC_NAMES, mission_metrics, mission_world
from firefleet.world import SMOKE

SMOKY = (
    Path(__file__).resolve().parents[2]
    / "src"
    / "firefleet"
    / "scenarios"
    / "builtin"
    / "mission-smoke.yaml"
)


def test_a_bad_perception_is_one_line_exit_2(tmp_path: Path) -> None:
    path = tmp_path / "smoke.yaml"
    path.write_text(SMOKY.read_text().replace("stereo_team: true ", "perception: infrared"))
    done = subprocess.run(
        [sys.executable, "-m", "firefleet.cli", "validate", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "command.perception" in lines[0]
    assert "infrared" in lines[0]


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        ("arrive_s: 150.0 ", "arrive_s: 420.0", "command.arrive_s 420 must be before"),
        ("arrive_s: 150.0 ", "arrive_s: -1.0", "command.arrive_s"),
        ("smoke_yield: 30.0", "smoke_yield: -2.0", "world.fuel.smoke_yield must be >= 0"),
        ("stereo_team: true ", "stereo_team: 3", "command.stereo_team"),
    ],
)
def test_bad_smoke_input_names_the_key(tmp_path: Path, old: str, new: str, says: str) -> None:
    text = SMOKY.read_text()
    assert old in text
    path = tmp_path / "smoke.yaml"
    path.write_text(text.replace(old, new))
    with pytest.raises(firefleet.InputError, match=re.escape(says)):
        firefleet.load_scenario(path)


def test_a_stereo_team_needs_no_thermal_camera_and_smoke_yield_scales_the_source(
    tmp_path: Path,
) -> None:
    text = SMOKY.read_text().replace(
        "sensors: {thermal: {}, ultrasonic: {count: 8}}", "sensors: {ultrasonic: {count: 8}}"
    )
    path = tmp_path / "stereo.yaml"
    path.write_text(text.replace("stereo_team: true ", "perception: stereo"))
    scenario = firefleet.load_scenario(path)
    assert scenario.command.perception == "stereo"  # type: ignore[union-attr]
    assert mission_world(scenario).smoke_params.source == pytest.approx(30.0 * SMOKE.source)
    thermal = tmp_path / "thermal.yaml"
    thermal.write_text(text)
    with pytest.raises(firefleet.InputError, match=r"sensors\.thermal"):
        firefleet.load_scenario(thermal)


def test_a_short_stereo_run_waits_then_moves_and_reports_no_stereo_team() -> None:
    """A stereo-only team (no thermal frames: the visible camera through the smoke, the
    stereo scan among its ranges) waits until ``arrive_s`` and then moves; without
    ``stereo_team`` the stereo metrics are NaN."""
    scenario = firefleet.load_scenario(SMOKY)
    replace: Any = dataclasses.replace
    cmd = replace(scenario.command, perception="stereo", stereo_team=False, arrive_s=2.0)
    scenario = dataclasses.replace(scenario, duration_s=6.0, command=cmd)
    result = firefleet.simulate(scenario, record_every=10)
    t = result.t
    before = result.pose[t < 2.0]
    assert np.abs(before - before[0]).max() < 1e-9  # nobody moved before the arrival
    assert np.abs(result.pose[-1, :, :2] - result.pose[0, :, :2]).max() > 0.05
    assert np.all(np.asarray(result.extra["mode"])[t < 2.0] == 4.0)  # idle
    metrics = mission_metrics(result)
    assert set(METRIC_NAMES) <= set(metrics)
    assert math.isnan(float(metrics["stereo_victims_found"]))  # type: ignore[arg-type]
    assert metrics["victims_found"] == 0.0
