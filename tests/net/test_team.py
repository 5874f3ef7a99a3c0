"""Team runs over zenoh: robot processes, the in-process reference, failures, a rogue.

Every test starts its own processes (the plant picks a free port) and the fixture
checks, with psutil, that none is left behind, killing any it finds.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import signal
import struct
import time
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zenoh

from firefleet import load_scenario
from firefleet.cli._main import main
from firefleet.net.messages import Command, encode
from firefleet.net.team import run_team
from firefleet.net.transport import Keys, open_session
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim.registry import task_kind
from firefleet.sim.result import SimResult
from tests._processes import no_stray_processes  # noqa: F401  (autouse: importing is using)


def _short(duration_s: float = 2.0) -> Scenario:
    """coop-different-paths cut to ``duration_s`` (its trajectory too): three robots."""
    s = load_scenario("coop-different-paths")
    assert isinstance(s.command, PathFollowing)
    command = dataclasses.replace(s.command, trajectory_s=duration_s)
    return dataclasses.replace(s, duration_s=duration_s, command=command)


def _in_process(scenario: Scenario) -> SimResult:
    rec = np.arange(scenario.n_steps + 1)
    return task_kind(scenario.command.kind).run(scenario, rec, staged=True)


def test_cli_team_passes_the_claims_and_equals_the_in_process_run(tmp_path: Path) -> None:
    """Experiment 1 over zenoh in lock-step, at a 20 ms tick to keep the test short
    (4,000 ticks; the claims hold in process at that tick): every claim passes and the
    run is the in-process one to the last bit."""
    text = (
        resources.files("firefleet.scenarios") / "builtin" / "coop-different-paths.yaml"
    ).read_text()
    path = tmp_path / "coop.yaml"
    path.write_text(text.replace("duration_s: 80.0", "duration_s: 80.0\ndt_s: 0.02"))
    out = tmp_path / "out"
    status = main(["team", str(path), "--out", str(out), "--compare", "--no-plots"])
    doc = json.loads((out / "metrics.json").read_text())
    assert status == 0
    assert len(doc["claims"]) == 8
    assert all(c["passed"] for c in doc["claims"])
    assert doc["arrival_spread_s"] <= 0.1
    net = doc["network"]
    assert net["in_process_max_pose_difference_m"] == 0.0
    assert net["misses"] == [0, 0, 0]
    assert net["failed_robots"] == []
    assert net["dropped_total"] == 0
    assert net["ticks"] == 4001
    assert net["plant"]["received"]["Command"] == 3 * 4001
    assert (out / "result.npz").is_file()


def test_cli_team_bad_input_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["team", "coop-different-paths", "--timeout", "0", "--out", str(tmp_path / "x")]) == 2
    )
    assert "--timeout" in capsys.readouterr().err
    assert main(["team", "coop-different-paths", "--seed", "-1", "--out", str(tmp_path / "y")]) == 2
    assert "--seed" in capsys.readouterr().err
    assert main(["team", "formation-3", "--out", str(tmp_path / "z")]) == 2
    assert "runs its own loop" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
    assert not (tmp_path / "y").exists()
    assert not (tmp_path / "z").exists()


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGSTOP], ids=["killed", "hung"])
def test_failed_robot_is_noticed_within_a_second_and_marked_failed(sig: signal.Signals) -> None:
    """Kill (or freeze) robot 2's process a third of the way: the liveliness subscribers
    of the plant and of the two other robots notice (a protocol bound: the token goes
    with the process's links, at once when it dies, at the 0.8 s lease when it hangs),
    the run ends cleanly, robot 2 stops, and robots 1 and 3 are exactly the in-process
    ones."""
    scenario = _short(3.0)
    pids: list[int] = []
    killed: dict[str, float] = {}

    def started(info: dict[str, Any]) -> None:
        pids.extend(info["pids"])

    def progress(done: int, total: int) -> None:
        if not killed and done >= total // 3:
            killed["t"] = time.monotonic()
            killed["tick"] = done
            os.kill(pids[1], sig)

    result, net = run_team(
        scenario, np.arange(scenario.n_steps + 1), started=started, progress=progress
    )
    assert sorted(net.failed) == [1]
    notice_s = net.failed[1]["noticed_s"] - killed["t"]
    assert 0.0 <= notice_s < 1.0
    doc = net.document()
    assert doc["failed_robots"] == [2]
    failed_tick = int(net.failed[1]["tick"])
    assert killed["tick"] <= failed_tick < killed["tick"] + 100
    ref = _in_process(scenario)
    np.testing.assert_array_equal(result.pose[:, [0, 2]], ref.pose[:, [0, 2]])
    assert np.all(result.wheel_speed_ref_rad_s[failed_tick + 1 :, 1] == 0.0)
    assert not np.array_equal(result.pose[-1, 1], ref.pose[-1, 1])
    assert len(net.robots) == 2  # the two survivors said goodbye with their counters
    for survivor in net.robots:  # and they, too, saw robot 2's token go within 1 s
        assert 0.0 <= survivor["lost"]["2"] - killed["t"] < 1.0


def _nan_state(run_id: int) -> bytes:
    body = struct.pack("<6dIdB", 0.1, math.nan, 0.0, 0.0, 0.0, 0.0, 1, 0.5, 0)
    return struct.pack("<2sBBQHIH", b"FF", 1, 5, run_id, 0, 10, len(body)) + body


def test_rogue_publisher_is_dropped_and_counted() -> None:
    """A rogue peer on the run's keys sends garbage, oversized, foreign-run, wrong-robot
    and non-finite messages: each is counted by its reason and dropped, and the run is
    still exactly the in-process one."""
    scenario = _short(2.0)
    rogue: dict[str, Any] = {}
    repeats = 5

    def started(info: dict[str, Any]) -> None:
        keys = Keys(info["run_id"])
        session = open_session(listen=["tcp/127.0.0.1:0"], connect=[info["endpoint"]])
        rogue["session"] = session
        pubs = {
            key: session.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
            for key in (keys.command(0), keys.state(1), keys.sensors(2))
        }
        deadline = time.monotonic() + 10.0
        while not all(p.matching_status.matching for p in pubs.values()):
            assert time.monotonic() < deadline, "the rogue never saw the team's subscribers"
            time.sleep(0.01)
        rid = info["run_id"]
        foreign = encode(Command(rid ^ 1, 0, 0, t_s=0.0, reference_rad_s=(100.0, -100.0)))
        wrong_robot = encode(Command(rid, 9, 0, t_s=0.0, reference_rad_s=(100.0, -100.0)))
        batches = {
            keys.command(0): [b"garbage", b"\x00" * 40, b"F" * 20000, foreign, wrong_robot],
            keys.state(1): [_nan_state(rid)],
            keys.sensors(2): [b"\xff" * 64],
        }
        for key, payloads in batches.items():
            for payload in payloads * repeats:
                pubs[key].put(payload)

    try:
        result, net = run_team(scenario, np.arange(scenario.n_steps + 1), started=started)
    finally:
        if "session" in rogue:
            rogue["session"].close()
    plant = dict(net.counters.dropped)
    assert plant == {
        "short": repeats,
        "magic": repeats,
        "oversized": repeats,
        "foreign": repeats,
        "robot": repeats,
        "nonfinite": repeats,
    }, net.document()
    robot_3 = next(r for r in net.robots if r["robot"] == 2)
    assert robot_3["dropped"] == {"magic": repeats}
    assert net.document()["dropped_total"] == 7 * repeats
    assert net.failed == {}
    assert net.misses == [0, 0, 0]
    ref = _in_process(scenario)
    np.testing.assert_array_equal(result.pose, ref.pose)
    np.testing.assert_array_equal(result.wheel_speed_ref_rad_s, ref.wheel_speed_ref_rad_s)


def test_realtime_clock_runs_every_tick_and_counts_what_misses() -> None:
    """On the monotonic clock a command that misses its tick is held, not waited for:
    every tick runs, and the misses plus the commands taken account for every tick."""
    scenario = _short(1.0)
    result, net = run_team(scenario, np.arange(scenario.n_steps + 1), clock="realtime")
    ticks = scenario.n_steps + 1
    assert net.ticks == ticks
    assert result.pose.shape == (ticks, 3, 3)
    assert np.all(np.isfinite(result.pose))
    assert net.failed == {}
    received = net.counters.received["Command"]
    assert received <= 3 * ticks
    assert all(0 <= m <= ticks for m in net.misses)
    assert sum(net.misses) >= 3 * ticks - received  # every command not taken in time is a miss
