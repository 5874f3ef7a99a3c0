"""The on-board loop on fakes: it drives the robot's role as the simulator does, stops
on overruns and on SIGTERM with the motors e-stopped, and refuses bad configurations."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.robot import Message, load_role, open_adapters, parse_robot_config, run_onboard
from firefleet.sim.engine import simulate

ROOT = Path(__file__).resolve().parents[2]


def test_the_onboard_loop_follows_the_simulated_robot() -> None:
    config = parse_robot_config({"scenario": "coop-different-paths", "robot": 1, "duration_s": 4.0})
    scenario = load_role(config, Path("."))
    with open_adapters(config, fake=True) as adapters:
        result = run_onboard(config, scenario, adapters, stop=threading.Event())
    assert result.ticks == 400
    assert result.stop_reason == "duration"
    sim = simulate(scenario)
    k = int(np.searchsorted(sim.t, 3.99))
    # the same controller on the same (fake) motors, but in real time: commands reach the
    # board up to a period late, so the robots part by centimetres, not more
    np.testing.assert_allclose(result.pose[-1][:2], sim.pose[k, 1, :2], atol=0.1)
    assert np.hypot(*np.subtract(result.pose[-1][:2], result.pose[0][:2])) > 0.5  # it moved


def test_an_overrun_streak_stops_and_estops_the_robot() -> None:
    config = parse_robot_config(
        {"scenario": "coop-different-paths", "robot": 0, "duration_s": 5.0,
         "safety": {"overrun_streak": 5}}
    )  # fmt: skip
    scenario = load_role(config, Path("."))
    with open_adapters(config, fake=True) as adapters:
        motors = adapters.motors
        assert motors is not None  # a fake board, not the simulator
        poll = motors.poll

        def slow_poll() -> list[Message]:  # a link that takes 15 ms: every period overruns
            time.sleep(0.015)
            return poll()

        motors.poll = slow_poll  # type: ignore[method-assign]
        result = run_onboard(config, scenario, adapters, stop=threading.Event())
        time.sleep(0.1)
        board = adapters.board
        assert board is not None
        assert board._logic.estop  # the loop's last word to the board
    assert result.stop_reason == "overruns"
    assert result.worst_overrun_streak == 5
    assert result.ticks < 20


def test_sigterm_stops_the_robot_cleanly(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    process = subprocess.Popen(
        [sys.executable, "-m", "firefleet.cli", "robot", str(ROOT / "examples" / "robot-fake.yaml"),
         "--fake", "--out", str(tmp_path / "run")],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not list(tmp_path.glob("*")):
            time.sleep(0.1)  # the run has staged its folder: the loop is starting
        time.sleep(1.5)
        process.send_signal(signal.SIGTERM)
        stdout, _ = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0
    assert "stopped on signal" in stdout
    summary = (tmp_path / "run" / "summary.json").read_text()
    assert '"stop_reason": "signal"' in summary


def test_bad_configurations_are_one_line_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"r\.yaml: hardware\.motors\.adapter: Input should be"):
        parse_robot_config(
            {"scenario": "x", "hardware": {"motors": {"adapter": "uno"}}}, origin="r.yaml"
        )
    config = parse_robot_config({"scenario": "coop-different-paths", "robot": 7})
    with pytest.raises(InputError, match=r"robot: 7 but scenario 'coop-different-paths' has 3"):
        load_role(config, Path("."))
    bad = tmp_path / "bad.yaml"
    bad.write_text("scenario: coop-different-paths\nrobbot: 1\n")
    run = subprocess.run(
        [sys.executable, "-m", "firefleet.cli", "robot", str(bad), "--fake"],
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")}, capture_output=True, text=True,
        timeout=60, check=False,
    )  # fmt: skip
    assert run.returncode == 2
    assert "robbot: unknown key; did you mean 'robot'?" in run.stderr
