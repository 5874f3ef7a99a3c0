"""Sweeps on Dask: the same numbers as runs made one by one, through a LocalCluster and
through a separate scheduler and worker; resume; failures; Ctrl-C."""

from __future__ import annotations

import contextlib
import math
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.compute as pc
import pytest

import firefleet
from firefleet import load_scenario
from firefleet.sim.metrics import compute_metrics
from firefleet.sweep import (
    SweepInterrupted,
    claim_key,
    flat_metrics,
    local_client,
    parse_set,
    points_of,
    run_points,
)

GRID = {"command.speed_rad_s": [1.0, 2.5]}
SEEDS = range(3)


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    with local_client(2) as own:
        try:
            yield own
        finally:
            own.cluster.close()


def _without_times(table: pa.Table) -> pa.Table:
    return table.drop_columns(["run_time_s"])


def test_a_local_sweep_equals_the_runs_made_one_by_one(client: Any) -> None:
    table = firefleet.sweep("motor-pid", GRID, SEEDS, client=client)
    assert table.num_rows == 6
    assert table.column("seed").to_pylist() == [0, 1, 2, 0, 1, 2]
    assert table.column("command.speed_rad_s").to_pylist() == [1.0] * 3 + [2.5] * 3
    assert table.column("error").null_count == 6
    base = load_scenario("motor-pid")
    rows = table.to_pylist()
    seen_claims = 0
    for row in rows:
        scenario = points_of(base, [parse_set(f"command.speed_rad_s={row['command.speed_rad_s']}")])
        alone = compute_metrics(firefleet.simulate(scenario[0].scenario, seed=row["seed"]))
        expected = flat_metrics(alone)
        assert set(expected) <= set(row)
        for name, value in expected.items():  # bit for bit: the same run, elsewhere
            assert row[name] == value or (math.isnan(value) and math.isnan(row[name])), name
        for claim in base.claims:
            assert row[f"claim:{claim_key(claim)}"] == claim.holds(alone.get(claim.metric))
            seen_claims += 1
    assert seen_claims == 6 * len(base.claims)
    # seeds matter (the encoder's phase): the runs of one point are not copies
    assert len({r["settling_time_s"] for r in rows[:3]}) > 1


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@contextlib.contextmanager
def _started(args: list[str], env: dict[str, str]) -> Iterator[subprocess.Popen[bytes]]:
    process = subprocess.Popen(
        args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        yield process
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait(timeout=15)


def test_a_separate_scheduler_and_worker_give_the_same_table(client: Any) -> None:
    from distributed import Client

    dask = str(Path(sys.executable).with_name("dask"))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    scheduler = [dask, "scheduler", "--host", "127.0.0.1", "--port", str(port)]
    worker = [dask, "worker", address, "--nworkers", "1", "--nthreads", "1"]
    with _started([*scheduler, "--dashboard-address", ":0"], env) as sched:
        with _started([*worker, "--dashboard-address", ":0"], env) as work:
            with Client(address, timeout=30) as remote:  # type: ignore[no-untyped-call]
                remote.wait_for_workers(1, timeout=60)
                far = firefleet.sweep("motor-pid", GRID, SEEDS, client=remote)
            assert work.poll() is None
        assert sched.poll() is None
    near = firefleet.sweep("motor-pid", GRID, SEEDS, client=client)
    assert _without_times(far).equals(_without_times(near))
    assert sched.returncode is not None
    assert work.returncode is not None


def test_resume_runs_only_what_is_missing(client: Any) -> None:
    points = points_of(load_scenario("motor-pid"), [parse_set("command.speed_rad_s=1,2.5")])
    first, reused = run_points(client, points, (0, 1), "motor-pid")
    assert (first.num_rows, reused) == (4, 0)
    whole, reused = run_points(client, points, (0, 1, 2), "motor-pid", previous=first)
    assert (whole.num_rows, reused) == (6, 4)
    # the reused rows are the previous ones, run times included (they were not run again)
    kept = whole.filter(pc.less(whole.column("seed"), 2))
    assert kept.equals(first)
    fresh = firefleet.sweep("motor-pid", GRID, SEEDS, client=client)
    assert _without_times(whole).equals(_without_times(fresh))
    # a previous table of another scenario (other digests) reuses nothing
    other = points_of(load_scenario("motor-pid"), [parse_set("command.speed_rad_s=3")])
    _, reused = run_points(client, other, (0, 1), "motor-pid", previous=first)
    assert reused == 0


def test_a_failing_run_is_recorded_and_the_others_finish(client: Any) -> None:
    scenario = load_scenario("path-straight")
    points = points_of(scenario, [parse_set("command.controller_fis=no-such.fis,''")])
    table, _ = run_points(client, points, (0, 1), scenario.name)
    errors = table.column("error").to_pylist()
    assert errors[:2] == [errors[0]] * 2
    assert "no-such.fis: no such file" in errors[0]
    assert errors[2:] == [None, None]
    claims = [name for name in table.column_names if name.startswith("claim:")]
    assert all(table.column(name).to_pylist()[:2] == [None, None] for name in claims)
    assert all(v is not None for name in claims for v in table.column(name).to_pylist()[2:])


def test_ctrl_c_cancels_and_keeps_what_finished(client: Any) -> None:
    points = points_of(load_scenario("motor-pid"), [])
    calls = []

    def interrupt_after_two(state: Any) -> None:
        calls.append(state.done)
        if state.done >= 2:
            raise KeyboardInterrupt

    seeds = tuple(range(40))
    with pytest.raises(SweepInterrupted) as info:
        run_points(client, points, seeds, "motor-pid", progress=interrupt_after_two)
    finished = info.value.rows
    assert 2 <= len(finished) < 40
    deadline = time.monotonic() + 30
    while client.processing() and any(client.processing().values()):
        assert time.monotonic() < deadline, "tasks left running after Ctrl-C"
        time.sleep(0.05)
    assert calls[0] == 0
    assert calls[-1] == len(finished)
