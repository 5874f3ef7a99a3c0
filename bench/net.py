"""Benchmark: robots as processes over zenoh (issue 16, point 3).

1. Round trip between two processes on loopback (zenoh peers, TCP, multicast scouting
   off, :func:`firefleet.net.transport.open_session`): this process publishes on
   ``firefleet/bench/ping``, an echo process (this file run with ``--echo``) puts the
   same bytes back on ``firefleet/bench/pong``; p50 and p99 of 2,000 round trips after
   200 untimed ones, for an encoded state message (81 B), 64 B and 1 KiB. Anchor
   measured when the issue was written: ~140 us p50 for 64 B.
2. ``firefleet team coop-different-paths`` in lock-step (:func:`firefleet.net.team.run_team`):
   ticks per second with 3 robot processes (10 s simulated, 1,001 ticks) and with 20
   (the three paths repeated, 5 s, 501 ticks); start-up (processes spawned until every
   hello) apart. Best of 2.
3. The overhead per tick against the in-process run of the same scenario: the staged
   world loop (:func:`firefleet.sim.loop.run_staged`, the reference the team run equals
   bit for bit) and the compiled one (``firefleet run``).

``make bench`` runs it through ``bench/run.py``; ``python bench/net.py`` runs it alone.
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

import _harness as h
import firefleet
from firefleet.net.messages import State, encode
from firefleet.net.team import run_team
from firefleet.net.transport import free_port, open_session
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim.registry import task_kind

PING, PONG = "firefleet/bench/ping", "firefleet/bench/pong"
ROUND_TRIPS = 2_000
WARMUP = 200


def echo(endpoint: str) -> None:
    """The echo process: every ping back as a pong, until stdin closes."""
    session = open_session(listen=["tcp/127.0.0.1:0"], connect=[endpoint])
    pub = session.declare_publisher(PONG)
    sub = session.declare_subscriber(PING, lambda s: pub.put(s.payload.to_bytes()))
    sys.stdout.write("ready\n")
    sys.stdout.flush()
    sys.stdin.read()
    sub.undeclare()
    session.close()


def round_trips(sizes: dict[str, bytes]) -> dict[str, dict[str, float]]:
    """p50, p99 and mean round trip [us] per payload, against an echo process."""
    import zenoh

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    session = open_session(listen=[endpoint], connect=[])
    proc = subprocess.Popen(
        [sys.executable, str(Path(__file__).resolve()), "--echo", endpoint],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
    )
    try:
        assert proc.stdout is not None
        proc.stdout.readline()
        sub = session.declare_subscriber(PONG, zenoh.handlers.FifoChannel(16))
        pub = session.declare_publisher(PING)
        deadline = time.monotonic() + 10.0
        while not pub.matching_status.matching:
            if time.monotonic() > deadline:
                raise RuntimeError("the echo process never subscribed")
            time.sleep(0.01)
        out = {}
        for name, payload in sizes.items():
            times = np.empty(ROUND_TRIPS)
            for i in range(WARMUP + ROUND_TRIPS):
                t0 = time.perf_counter()
                pub.put(payload)
                back = sub.recv()
                dt = time.perf_counter() - t0
                if i >= WARMUP:
                    times[i - WARMUP] = dt
            assert back.payload.to_bytes() == payload
            us = times * 1e6
            out[name] = {
                "bytes": len(payload),
                "p50_us": float(np.percentile(us, 50)),
                "p99_us": float(np.percentile(us, 99)),
                "mean_us": float(us.mean()),
            }
        sub.undeclare()
        return out
    finally:
        if proc.stdin is not None:
            proc.stdin.close()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        session.close()


def team_of(base: Scenario, n: int, duration_s: float) -> Scenario:
    """``base`` cut to ``duration_s`` with its robots and paths repeated to ``n``."""
    cmd = base.command
    assert isinstance(cmd, PathFollowing)
    k = len(base.poses)
    command = dataclasses.replace(
        cmd, paths=tuple(cmd.paths[i % k] for i in range(n)), trajectory_s=duration_s
    )
    poses = tuple(base.poses[i % k] for i in range(n))
    return dataclasses.replace(base, poses=poses, command=command, duration_s=duration_s)


def team_rate(scenario: Scenario, repeats: int) -> dict[str, Any]:
    """Lock-step ticks per second over zenoh and the in-process loops' time per tick."""
    rec = np.arange(scenario.n_steps + 1)
    kind = task_kind(scenario.command.kind)
    best, start_up, diff, misses = np.inf, np.inf, np.nan, 0
    for _ in range(repeats):
        result, net = run_team(scenario, rec)
        best = min(best, net.wall_s)
        start_up = min(start_up, net.start_s)
        misses += sum(net.misses)
    staged = h.best_of(lambda: kind.run(scenario, rec, staged=True), 2)
    fused = h.best_of(lambda: kind.run(scenario, rec), 3)
    alone = kind.run(scenario, rec, staged=True)
    diff = float(np.max(np.abs(result.pose - alone.pose)))
    ticks = scenario.n_steps + 1
    return {
        "robots": scenario.n_robots,
        "ticks": ticks,
        "wall_s": best,
        "ticks_per_s": ticks / best,
        "start_up_s": start_up,
        "misses": misses,
        "us_per_tick": best / ticks * 1e6,
        "staged_us_per_tick": staged.best_s / ticks * 1e6,
        "fused_us_per_tick": fused.best_s / ticks * 1e6,
        "overhead_us_per_tick_vs_staged": (best - staged.best_s) / ticks * 1e6,
        "max_pose_difference_m": diff,
    }


def run(console: Console) -> h.TopicResult:
    """Measure, print the tables, return the rows."""
    state = encode(
        State(
            run_id=1,
            robot=0,
            tick=0,
            t_s=0.0,
            pose=(0.0, 0.0, 0.0),
            wheel_speed_rad_s=(0.0, 0.0),
            segment=0,
            fraction=0.0,
            arrived=False,
        )
    )
    rtt = round_trips({"state": state, "b64": bytes(64), "kib1": bytes(1024)})
    table = Table(title="zenoh round trip between two processes on loopback (us)")
    for col in ("message", "bytes", "p50", "p99", "mean"):
        table.add_column(col, justify="right")
    for name, r in rtt.items():
        table.add_row(
            name, str(r["bytes"]), f"{r['p50_us']:.0f}", f"{r['p99_us']:.0f}", f"{r['mean_us']:.0f}"
        )
    console.print(table)

    base = firefleet.load_scenario("coop-different-paths")
    teams = {3: team_rate(team_of(base, 3, 10.0), 2), 20: team_rate(team_of(base, 20, 5.0), 2)}
    table = Table(title="firefleet team coop-different-paths, lock-step over zenoh")
    for col in (
        "robots",
        "ticks/s",
        "us/tick",
        "in-process staged us/tick",
        "compiled us/tick",
        "overhead us/tick",
        "start-up s",
        "misses",
        "max |pose diff| m",
    ):
        table.add_column(col, justify="right")
    for n, r in teams.items():
        table.add_row(
            str(n),
            f"{r['ticks_per_s']:.0f}",
            f"{r['us_per_tick']:.0f}",
            f"{r['staged_us_per_tick']:.0f}",
            f"{r['fused_us_per_tick']:.2f}",
            f"{r['overhead_us_per_tick_vs_staged']:.0f}",
            f"{r['start_up_s']:.1f}",
            str(r["misses"]),
            f"{r['max_pose_difference_m']:.3g}",
        )
    console.print(table)

    rows = [
        h.Row(
            f"net.rtt.{name}.{q}_us",
            r[f"{q}_us"],
            "us",
            False,
            label=f"zenoh round trip, {r['bytes']} B, {q}",
        )
        for name, r in rtt.items()
        for q in ("p50", "p99")
    ]
    for n, r in teams.items():
        rows.append(
            h.Row(
                f"net.team.n{n}.ticks_per_s",
                r["ticks_per_s"],
                "ticks/s",
                label=f"team over zenoh, {n} robot processes, lock-step",
            )
        )
        rows.append(
            h.Row(
                f"net.team.n{n}.overhead_us_per_tick",
                r["overhead_us_per_tick_vs_staged"],
                "us",
                False,
                label=f"{n} robots: zenoh lock-step tick minus the in-process staged tick",
            )
        )
    floors = [
        h.Floor(
            f"team over zenoh ({n} robots) equals the in-process run: max |pose diff|",
            r["max_pose_difference_m"],
            0.0,
            "m",
            "<=",
        )
        for n, r in teams.items()
    ]
    return h.TopicResult(tuple(rows), tuple(floors), {"round_trip": rtt, "team": teams})


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--echo":
        echo(sys.argv[2])
    else:
        h.single_threaded_blas()
        run(Console())
