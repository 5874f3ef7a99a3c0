"""Hardware in the loop: `firefleet robot --sim` processes against one world process.

Every test starts its own processes on free ports (the plant's endpoint fixed by the
test, as a person would) and the fixture checks, with psutil, that none is left behind.
Real-time runs on a shared 2-core machine: the margins below are stated where they are
used.
"""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from firefleet import load_scenario
from firefleet.cli._main import main
from firefleet.net.messages import Command, TeamProgress, decode, encode
from firefleet.net.transport import Keys, free_port, open_session
from firefleet.robot import load_role, read_robot_config
from firefleet.robot._teamlink import Watchdog
from firefleet.sim.metrics import compute_metrics
from firefleet.sim.registry import task_kind
from tests._processes import no_stray_processes  # noqa: F401  (autouse: importing is using)

RUN_ID = 1  # the robot configs' default link.run_id, the plant's default with --external
TIMEOUT_S = 1.0  # link.timeout_s of the robots below


SCALE = 0.4
"""Experiment 1 scaled down for the suite (see :func:`_small_experiment_1`)."""


def _robot_configs(folder: Path, scenario: Path, listen: tuple[str, ...]) -> None:
    """``robot-{i}.yaml`` for the three robots of ``scenario`` (in ``folder``)."""
    for i in range(3):
        link: dict[str, Any] = {"timeout_s": TIMEOUT_S}
        if listen:  # a fixed endpoint of its own (that a test can connect to)
            link["listen"] = listen[i]
        config = {"scenario": scenario.name, "robot": i, "link": link}
        (folder / f"robot-{i}.yaml").write_text(yaml.safe_dump(config))


def _small_experiment_1(folder: Path, listen: tuple[str, ...] = ()) -> Path:
    """coop-different-paths scaled by :data:`SCALE`: paths, start points and times (the
    same speeds; 28 s instead of 70 s, so that the real-time run takes half a minute),
    with every claim of the original kept (the path lengths scaled, the arrival spread at
    issue 19's real-time bound, 0.2 s). In process it keeps them all (spread 0.09 s)."""
    text = (
        resources.files("firefleet.scenarios") / "builtin" / "coop-different-paths.yaml"
    ).read_text()
    data = yaml.safe_load(text)
    data["name"] = "coop-small"
    data["duration_s"] = data["duration_s"] * SCALE
    data["poses"] = [[x * SCALE, y * SCALE, h] for x, y, h in data["poses"]]
    command = data["command"]
    command["trajectory_s"] = min(command["trajectory_s"] * SCALE, data["duration_s"])
    for path in command["paths"]:  # y(x) = sum c_k x^k: y and x both scaled
        path["coefficients"] = [c * SCALE ** (1 - k) for k, c in enumerate(path["coefficients"])]
        path["x_start_m"] *= SCALE
        path["x_end_m"] *= SCALE
    for claim in data["claims"]:
        if claim["metric"] == "path_lengths_m":
            claim["value"] *= SCALE
        if claim["metric"] == "arrival_spread_s":
            claim["value"] = 0.2
    out = folder / "coop-small.yaml"
    out.write_text(yaml.safe_dump(data))
    _robot_configs(folder, out, listen)
    return out


def _short_experiment_1(folder: Path, duration_s: float, listen: tuple[str, ...] = ()) -> Path:
    """Experiment 1 (coop-different-paths) on the first eighth of each path (less for a
    ``duration_s`` under 9.25 s), in as much less time (the same speeds): at 11 s, the
    robots arrive at about 10.4 s. Its claims: the arrival spread (<= 0.2 s, issue 19's
    real-time bound) and the cross-track RMS."""
    text = (
        resources.files("firefleet.scenarios") / "builtin" / "coop-different-paths.yaml"
    ).read_text()
    data = yaml.safe_load(text)
    trajectory_s = min(70.0 / 8, duration_s - 0.5)
    for path in data["command"]["paths"]:
        cut = (path["x_end_m"] - path["x_start_m"]) * trajectory_s / 70.0
        path["x_end_m"] = path["x_start_m"] + cut
    data["command"]["trajectory_s"] = trajectory_s
    data["duration_s"] = duration_s
    data["name"] = "coop-short"
    keep = ("arrival_spread_s", "cross_track_rms_m")
    data["claims"] = [c for c in data["claims"] if c["metric"] in keep]
    data["claims"][0]["value"] = 0.2
    out = folder / "coop-short.yaml"
    out.write_text(yaml.safe_dump(data))
    _robot_configs(folder, out, listen)
    return out


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}


def _firefleet(*args: str, log: Path) -> subprocess.Popen[bytes]:
    with log.open("wb") as sink:
        return subprocess.Popen(
            [sys.executable, "-m", "firefleet.cli", *args],
            stdout=sink,
            stderr=subprocess.STDOUT,
            env=_env(),
        )


def _wait_listening(port: int, timeout_s: float = 60.0) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        with socket.socket() as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.05)
    raise AssertionError(f"nothing listens on {port}")


class _Team:
    """The plant (``--external``) and three ``firefleet robot --sim`` processes."""

    def __init__(self, folder: Path, scenario: Path) -> None:
        self.folder = folder
        self.port = free_port()
        self.endpoint = f"tcp/127.0.0.1:{self.port}"
        self.plant = _firefleet(
            "team", str(scenario), "--external", "--listen", self.endpoint, "--clock",
            "realtime", "--no-plots", "--wait", "60", "--out", str(folder / "plant"),
            log=folder / "plant.log",
        )  # fmt: skip
        _wait_listening(self.port)
        self.robots = [self._robot(i) for i in range(3)]

    def _robot(self, i: int) -> subprocess.Popen[bytes]:
        config, out = self.folder / f"robot-{i}.yaml", self.folder / f"robot-{i}"
        return _firefleet(
            "robot", str(config), "--sim", self.endpoint, "--out", str(out),
            log=self.folder / f"robot-{i}.log",
        )  # fmt: skip

    def wait(self, timeout_s: float = 120.0) -> list[int]:
        codes = [p.wait(timeout=timeout_s) for p in (*self.robots, self.plant)]
        return codes

    def kill(self) -> None:
        for p in (*self.robots, self.plant):
            if p.poll() is None:
                p.kill()
            p.wait()

    def log(self, name: str) -> str:
        return (self.folder / f"{name}.log").read_text(errors="replace")

    def summary(self, robot: int) -> dict[str, Any]:
        data: dict[str, Any] = json.loads(
            (self.folder / f"robot-{robot}" / "summary.json").read_text()
        )
        return data


@pytest.fixture
def team_factory() -> Iterator[list[_Team]]:
    teams: list[_Team] = []
    yield teams
    for team in teams:
        team.kill()


def test_three_sim_robots_reproduce_experiment_1_in_real_time(
    tmp_path: Path, team_factory: list[_Team]
) -> None:
    """Three on-board loops against one plant, real time at 100 Hz, on experiment 1
    (coop-different-paths scaled to 28 s): every claim passes (arrival spread <= 0.2 s),
    and the arrivals are the in-process run's within 5 ticks (a command that misses its
    real-time tick is held by the plant: the honest margin on a loaded machine); no
    lost-link e-stop."""
    scenario = _small_experiment_1(tmp_path)
    team = _Team(tmp_path, scenario)
    team_factory.append(team)
    codes = team.wait()
    assert codes == [0, 0, 0, 0], team.log("plant") + team.log("robot-0")
    metrics = json.loads((tmp_path / "plant" / "metrics.json").read_text())
    claims = metrics["claims"]
    assert len(claims) == len(load_scenario("coop-different-paths").claims)
    assert all(c["passed"] for c in claims), claims
    assert metrics["arrival_spread_s"] <= 0.2
    assert metrics["network"]["failed_robots"] == []
    s = load_scenario(scenario)
    alone = compute_metrics(task_kind(s.command.kind).run(s, np.arange(s.n_steps + 1)))
    np.testing.assert_allclose(metrics["arrival_time_s"], alone["arrival_time_s"], atol=0.05)
    for i in range(3):
        summary = team.summary(i)
        assert summary["stop_reason"] == "plant stopped"
        assert summary["team_link"]["estops"] == 0
        # every teammate's progress heard (two teammates, about one message a tick each)
        assert summary["team_link"]["received"]["TeamProgress"] >= 2 * 0.9 * summary["ticks"]


def test_a_lost_teammate_estops_the_others_and_sigterm_stops_cleanly(
    tmp_path: Path, team_factory: list[_Team]
) -> None:
    """Mid-run, robot 1 gets SIGTERM: it leaves with exit 0, its last command on the wire
    is zero (the ones before were not) and, having said goodbye, it trips no one's
    e-stop. Then robot 3 is killed outright: robot 2 hears nothing from it and e-stops
    between ``timeout_s`` after its last message (at most a tick before the kill) and
    ``timeout_s`` + 0.25 s after the kill (a tick, plus scheduling on two shared cores),
    and commands zero from then on, latched to the end."""
    own = tuple(f"tcp/127.0.0.1:{free_port()}" for _ in range(3))
    scenario = _short_experiment_1(tmp_path, duration_s=6.0, listen=own)
    team = _Team(tmp_path, scenario)
    team_factory.append(team)
    keys = Keys(RUN_ID)
    seen: list[Command] = []
    _wait_listening(int(own[0].rsplit(":", 1)[1]))
    session = open_session(listen=["tcp/127.0.0.1:0"], connect=[team.endpoint, own[0]])
    try:

        def on_command(sample: Any) -> None:
            message = decode(sample.payload.to_bytes(), run_id=RUN_ID, n_robots=3)
            if isinstance(message, Command):
                seen.append(message)

        sub = session.declare_subscriber(keys.command(0), on_command)
        end = time.monotonic() + 60.0
        while len(seen) < 150 and time.monotonic() < end:  # 1.5 s of driving
            time.sleep(0.01)
        assert len(seen) >= 150, team.log("plant")
        team.robots[0].send_signal(signal.SIGTERM)
        assert team.robots[0].wait(timeout=20.0) == 0, team.log("robot-0")
        time.sleep(0.3)
        sub.undeclare()
    finally:
        session.close()
    assert seen[-1].reference_rad_s == (0.0, 0.0)
    assert max(abs(v) for c in seen[-50:-1] for v in c.reference_rad_s) > 1.0
    assert team.summary(0)["stop_reason"] == "signal"
    killed_s = time.monotonic()
    team.robots[2].kill()
    codes = team.wait()
    assert codes[1] == 0, team.log("robot-1")
    assert codes[3] == 1  # the plant: robots 1 and 3 failed (left mid-run)
    link = team.summary(1)["team_link"]
    assert link["estops"] == 1, link
    trip = link["estop_trips"][0]
    assert trip["silent"] == [3]
    latency_s = trip["t_monotonic_s"] - killed_s
    assert TIMEOUT_S - 0.02 <= latency_s <= TIMEOUT_S + 0.25, latency_s
    assert link["latched_at_end"]
    assert link["teammates_done"] == [1]  # robot 1's goodbye: not a lost link
    log = np.load(tmp_path / "robot-1" / "log.npz")
    assert np.all(log["reference_rad_s"][-50:] == 0.0)
    assert np.any(log["reference_rad_s"][:100] != 0.0)


def test_the_watchdog_trips_after_the_timeout_and_releases_after_rearm() -> None:
    dog = Watchdog(teammates=(0, 2), timeout_s=1.0, rearm_s=0.5, start_s=10.0)
    assert not dog.check(10.99)  # never heard, but not yet timeout_s since the start
    assert dog.check(11.01)
    assert dog.trips[0]["silent"] == [1, 3]
    dog.heard(0, 11.1)
    dog.heard(2, 11.1)
    assert dog.check(11.2)  # back, held for rearm_s
    assert dog.check(11.69)
    assert not dog.check(11.71)
    assert dog.releases == 1
    assert dog.stopped_s == pytest.approx(0.70)
    dog.heard(2, 11.8, alive=False)  # robot 3's goodbye: no longer watched
    dog.heard(0, 12.5)
    assert not dog.check(13.4)
    assert dog.check(13.51)
    assert dog.trips[-1]["silent"] == [1]


def test_a_teammate_falling_silent_during_a_trip_joins_it() -> None:
    dog = Watchdog(teammates=(1, 2), timeout_s=1.0, rearm_s=0.5, start_s=0.0)
    dog.heard(1, 5.0)
    dog.heard(2, 5.0005)  # the two stop half a millisecond apart
    assert not dog.check(5.9999)
    assert dog.check(6.0002)  # robot 2 past the timeout, robot 3 not yet (0.9997 s)
    assert dog.trips[0]["silent"] == [2]
    assert dog.check(6.0102)  # the next period: robot 3 too, in the same trip
    assert len(dog.trips) == 1
    assert dog.trips[0]["silent"] == [2, 3]
    assert dog.trips[0]["silent_s"] == pytest.approx([1.0002, 1.0097])


def test_hil_usage_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = _short_experiment_1(tmp_path, duration_s=2.0)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    status = main(["team", str(scenario), "--external", "--listen", endpoint, "--wait", "0.5",
                   "--out", str(tmp_path / "p")])  # fmt: skip
    assert status == 2
    err = capsys.readouterr().err
    assert "--wait" in err
    assert "[1, 2, 3]" in err
    assert endpoint in err
    assert main(["team", str(scenario), "--external"]) == 2
    assert "--listen" in capsys.readouterr().err
    assert main(["team", str(scenario), "--run-id", "xyz"]) == 2
    assert "--run-id" in capsys.readouterr().err
    assert main(["robot", str(tmp_path / "robot-0.yaml"), "--sim", "tcp/10.0.0.1:7447"]) == 2
    assert "--sim" in capsys.readouterr().err
    examples = Path(__file__).resolve().parents[2] / "examples"
    for i in range(3):
        config, folder = read_robot_config(examples / f"robot-sim-{i}.yaml")
        assert config.robot == i
        assert config.link is not None
        assert config.link.run_id == f"{RUN_ID:016x}"
        assert load_role(config, folder).name == "coop-different-paths"
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump({"scenario": "coop-different-paths", "link": {"timeout_s": 0}}))
    assert main(["robot", str(bad), "--fake"]) == 2
    assert "link.timeout_s" in capsys.readouterr().err


def test_the_team_link_on_fakes_estops_when_teammates_stop_publishing(tmp_path: Path) -> None:
    """``--fake`` with a team link: the robot publishes its progress each period and
    hears its teammates' (here the test plays robots 2 and 3 at 100 Hz, reporting
    themselves at the path's end so they hold no one back); when they stop publishing,
    it e-stops between ``timeout_s`` after their last message and 0.25 s later (margin
    as above), and commands zero from then on."""
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    config = {
        "scenario": "coop-different-paths", "robot": 0, "duration_s": 4.0,
        "link": {"timeout_s": TIMEOUT_S, "listen": endpoint},
    }  # fmt: skip
    (tmp_path / "robot.yaml").write_text(yaml.safe_dump(config))
    robot = _firefleet(
        "robot", str(tmp_path / "robot.yaml"), "--fake", "--out", str(tmp_path / "out"),
        log=tmp_path / "robot.log",
    )  # fmt: skip
    try:
        _wait_listening(port)
        keys = Keys(RUN_ID)
        heard: list[TeamProgress] = []
        session = open_session(listen=["tcp/127.0.0.1:0"], connect=[endpoint])
        try:

            def on_progress(sample: Any) -> None:
                message = decode(sample.payload.to_bytes(), run_id=RUN_ID, n_robots=3)
                if isinstance(message, TeamProgress):
                    heard.append(message)

            sub = session.declare_subscriber(keys.team(0), on_progress)
            pubs = [session.declare_publisher(keys.team(j)) for j in (1, 2)]
            end = time.monotonic() + 60.0
            while len(heard) < 20 and time.monotonic() < end:  # the robot is running
                time.sleep(0.01)
            for k in range(150):  # 1.5 s of teammates at 100 Hz
                for j, pub in zip((1, 2), pubs, strict=True):
                    values = [math.nan] * 6
                    values[2 * j : 2 * j + 2] = [200.0, 0.0]
                    ages = [math.inf] * 3
                    ages[j] = 0.0
                    pub.put(encode(TeamProgress(RUN_ID, j, k, width=2, values=tuple(values),
                                                age_s=tuple(ages), alive=(True,) * 3)))  # fmt: skip
                time.sleep(0.01)
            last_s = time.monotonic()
            assert robot.wait(timeout=30.0) == 0, (tmp_path / "robot.log").read_text()
            sub.undeclare()
        finally:
            session.close()
    finally:
        if robot.poll() is None:
            robot.kill()
        robot.wait()
    assert len(heard) >= 100
    assert all(h.robot == 0 and h.width == 2 and math.isfinite(h.values[0]) for h in heard[:-1])
    assert heard[-1].alive[0] is False  # its goodbye at the end
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    link = summary["team_link"]
    assert link["received"]["TeamProgress"] >= 250
    trips = link["estop_trips"]
    # it may have tripped at the start (teammates not yet heard for timeout_s) and been
    # released; the last trip is the one the silence caused
    assert trips[-1]["silent"] == [2, 3]
    latency_s = trips[-1]["t_monotonic_s"] - last_s
    assert TIMEOUT_S - 0.02 <= latency_s <= TIMEOUT_S + 0.25, latency_s
    log = np.load(tmp_path / "out" / "log.npz")
    stopped = log["t"] > log["t"][-1] - 0.5
    assert np.all(log["reference_rad_s"][stopped] == 0.0)


def test_an_overrun_streak_in_sim_stops_the_robot_with_a_zero_command(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``--sim`` in process against a test plant that sends sensors every 10 ms: a
    controller slowed to 15 ms a period overruns every period, and ``overrun_streak``
    (3) of them in a row end the loop (``overruns``) with a zero command sent last."""
    from firefleet.net.messages import Sensors
    from firefleet.net.robot import RobotController
    from firefleet.robot import open_adapters, parse_robot_config, run_onboard

    slow = RobotController.step

    def step(self: RobotController, sensors: Sensors) -> Any:
        time.sleep(0.015)
        return slow(self, sensors)

    monkeypatch.setattr(RobotController, "step", step)
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    config = parse_robot_config(
        {"scenario": "coop-different-paths", "robot": 1, "safety": {"overrun_streak": 3}}
    )
    scenario = load_scenario("coop-different-paths")
    keys = Keys(RUN_ID)
    seen: list[Command] = []
    plant = open_session(listen=[endpoint], connect=[])
    try:

        def on_command(sample: Any) -> None:
            message = decode(sample.payload.to_bytes(), run_id=RUN_ID, n_robots=3)
            if isinstance(message, Command):
                seen.append(message)

        sub = plant.declare_subscriber(keys.command(1), on_command)
        done: list[Any] = []
        with open_adapters(config, fake=False, sim=endpoint, n_robots=3, dt_s=0.01) as adapters:
            stop = threading.Event()
            worker = threading.Thread(
                target=lambda: done.append(run_onboard(config, scenario, adapters, stop=stop))
            )
            worker.start()
            for k in range(300):
                if done:
                    break
                sensors = Sensors(RUN_ID, 1, k, t_s=k * 0.01, counts=(0.0, 0.0),
                                  measured_rad_s=(0.0, 0.0))  # fmt: skip
                plant.put(keys.sensors(1), encode(sensors))
                time.sleep(0.01)
            stop.set()
            worker.join(timeout=10.0)
        time.sleep(0.2)
        sub.undeclare()
    finally:
        plant.close()
    result = done[0]
    assert result.stop_reason == "overruns"
    assert result.worst_overrun_streak == 3
    assert seen[-1].reference_rad_s == (0.0, 0.0)
    assert any(c.reference_rad_s != (0.0, 0.0) for c in seen[:-1])
