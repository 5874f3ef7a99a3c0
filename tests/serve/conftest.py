"""Run folders and a dashboard server on a free port, made once for the serve tests."""

from __future__ import annotations

import dataclasses
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import uvicorn
from rich.console import Console

from firefleet.cli._run import run_into
from firefleet.outputs import run_record, staged_dir
from firefleet.scenarios.registry import load_scenario
from firefleet.scenarios.schema import Scenario


def short(name: str, duration_s: float | None = None) -> Scenario:
    """A built-in scenario, cut to ``duration_s`` (its trajectory too) when given."""
    scenario = load_scenario(name)
    if duration_s is None:
        return scenario
    command: Any = scenario.command
    if hasattr(command, "trajectory_s"):
        command = dataclasses.replace(command, trajectory_s=duration_s - 5.0)
    return dataclasses.replace(scenario, duration_s=duration_s, command=command)


def write_run(folder: Path, scenario: Scenario, **kwargs: Any) -> Path:
    """``firefleet run`` into ``folder`` (staged, with its manifest), no plots."""
    command = ["firefleet", "run", scenario.name, "--out", str(folder)]
    with staged_dir(folder, record=run_record(command, seed=scenario.seed)) as stage:
        run_into(
            scenario, stage, plots=False, err=Console(quiet=True), command_line=command, **kwargs
        )
    return folder


@pytest.fixture(scope="session")
def runs_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``runs/``: coop-different-paths (3 robots, 80 s), formation-3, motor-pid."""
    root = tmp_path_factory.mktemp("runs")
    for name in ("coop-different-paths", "formation-3", "motor-pid"):
        write_run(root / name, short(name))
    return root


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Served:
    """A uvicorn server in a thread, stopped by :meth:`stop`."""

    def __init__(self, app: Any) -> None:
        self.port = free_port()
        config = uvicorn.Config(
            app,
            host="127.0.0.1",
            port=self.port,
            log_level="warning",
            ws="websockets-sansio",
            timeout_graceful_shutdown=2,
        )
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=self.server.run, daemon=True)
        self.thread.start()
        deadline = time.monotonic() + 20
        while not self.server.started:
            if time.monotonic() > deadline or not self.thread.is_alive():
                raise RuntimeError("the dashboard server did not start")
            time.sleep(0.02)
        self.url = f"http://127.0.0.1:{self.port}"

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=10)


@pytest.fixture(scope="session")
def served(runs_root: Path) -> Iterator[Served]:
    """The dashboard on ``runs_root``, bound to loopback, no token."""
    from firefleet.serve.app import create_app
    from firefleet.serve.runs import find_runs

    server = Served(create_app(find_runs([runs_root])))
    yield server
    server.stop()
