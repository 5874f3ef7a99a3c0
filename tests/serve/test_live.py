"""Live mode: frames while the run simulates, the newest only, the run unchanged."""

from __future__ import annotations

import asyncio
import json
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from websockets.sync.client import connect

from firefleet import load_scenario, simulate
from firefleet.cli._main import main
from firefleet.serve.app import create_app
from firefleet.serve.live import LiveHub, simulate_live
from tests.serve.conftest import Served, free_port, short


def test_a_slow_reader_gets_the_newest_frame_and_the_rest_are_dropped() -> None:
    hub = LiveHub()

    async def read_late() -> list[tuple[int, str]]:
        first = await hub.frames(0)
        for k in range(2, 101):  # 99 frames while this reader is busy
            hub.publish({"k": k})
        second = await hub.frames(first[0])
        return [first, second]

    hub.publish({"k": 1})
    first, second = asyncio.run(read_late())
    assert json.loads(first[1]) == {"k": 1}
    assert second[0] == 100
    assert json.loads(second[1]) == {"k": 100}


def test_live_run_equals_the_staged_run_and_paces_to_the_speed() -> None:
    scenario = short("coop-different-paths", 12.0)
    steps = np.arange(scenario.n_steps + 1)
    hub = LiveHub()
    seen: list[float] = []

    def progress(done: int, total: int) -> None:
        seen.append(json.loads(hub.latest()[1] or "{}").get("t", -1.0))

    start = time.perf_counter()
    live = simulate_live(scenario, hub, steps, speed=10.0, fps=30.0, progress=progress)
    wall = time.perf_counter() - start
    reference = simulate(scenario, backend="array")
    for name, array in reference.arrays().items():
        np.testing.assert_array_equal(live.arrays()[name], array, err_msg=name)
    assert wall >= 12.0 / 10.0  # held to 10x real time: 12 s of run in >= 1.2 s
    frames = hub.latest()[0]
    assert 10 <= frames <= 30.0 * wall + 3  # ~30 a second, and the last one
    assert seen == sorted(seen)
    assert seen[len(seen) // 2] > 0.0  # frames came while it ran, not only at the end
    last = json.loads(hub.latest()[1])
    assert last["finished"]
    np.testing.assert_allclose(last["pose"], np.round(reference.pose[-1], 4))


def test_a_websocket_receives_frames_while_the_run_simulates() -> None:
    scenario = short("coop-different-paths", 10.0)
    hub = LiveHub()
    hub.set_hello({"type": "hello", "scenario": scenario.name})
    server = Served(create_app([], hub=hub))
    received: list[dict[str, object]] = []
    running = threading.Event()
    try:
        with connect(f"ws://127.0.0.1:{server.port}/ws/live") as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "hello"

            def run() -> None:
                running.set()
                simulate_live(scenario, hub, np.arange(scenario.n_steps + 1), speed=5.0)
                running.clear()

            worker = threading.Thread(target=run)
            worker.start()
            while True:
                message = json.loads(ws.recv(timeout=30))
                message["while_running"] = running.is_set()
                received.append(message)
                if message.get("finished"):
                    break
            worker.join()
    finally:
        server.stop()
    times = [float(m["t"]) for m in received]  # type: ignore[arg-type]
    assert times == sorted(times)
    assert times[-1] == 10.0
    assert sum(bool(m["while_running"]) for m in received) >= 10
    assert len({round(t, 3) for t in times}) == len(times)


def test_run_live_from_the_command_line_writes_the_run_and_frees_the_port(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    port = free_port()
    out = tmp_path / "live"
    argv = ["run", "motor-pid", "--live", "--live-speed", "0", "--serve-port", str(port)]
    assert main([*argv, "--no-plots", "--out", str(out)]) == 0
    assert f"live: http://127.0.0.1:{port}/live" in capsys.readouterr().out
    reference = simulate(load_scenario("motor-pid"), backend="array")
    with np.load(out / "result.npz") as z:
        np.testing.assert_array_equal(z["pose"], reference.pose)
    with socket.socket() as s:  # the live server has let go of its port
        s.bind(("127.0.0.1", port))


@pytest.mark.parametrize(
    ("flags", "said"),
    [
        (["--serve-port", "70000"], "--serve-port must be 1..65535, got 70000"),
        (["--live-speed", "-1"], "--live-speed must be >= 0 (0: as fast as it runs), got -1.0"),
    ],
)
def test_bad_live_flags_are_one_line_and_exit_2(
    flags: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["run", "motor-pid", "--live", *flags, "--out", str(tmp_path / "x")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert said in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()
