"""Benchmark: simulation speed of cooperative path following (issues 3 and 12).

The whole hierarchy every tick (trajectory planner, the two fuzzy systems, wheel-speed
PID, DC motors, encoders, odometry), as ``firefleet run`` does it:

1. ``coop-different-paths`` (3 robots, 80 s simulated, dt = 10 ms): simulated seconds
   per wall second. Floor: 10,000x real time (issue 12; was 200x).
2. A 1,000-robot team with the same stack (the three paths of ``coop-different-paths``
   repeated, 20 s simulated, every 10th step recorded). Floor: 50x real time (issue 12;
   was 10x).

Both run through ``firefleet.simulate`` without a progress callback: the compiled kernel
of ``firefleet.sim._kernels`` in one piece, the robots spread over every core. The CPU
time of the process (all threads) is printed beside the wall time: on a shared machine
the wall time also measures the other processes.

Best of several runs after one untimed warm-up (which also compiles the kernel). There is
no peer to compare with here: no other library simulates this controller; the fuzzy
engine's comparison with scikit-fuzzy is in ``bench/fuzzy.py``.

``make bench`` runs it through ``bench/run.py``; ``python bench/path_following.py`` runs
it alone.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from typing import Any

from rich.console import Console
from rich.table import Table

import firefleet
from firefleet.scenarios.schema import PathFollowing, Scenario

FLOOR_SMALL = 10_000.0
"""coop-different-paths: at least this many times faster than real time."""
FLOOR_LARGE = 50.0
"""1,000 robots: at least this many times faster than real time."""
LARGE_N = 1_000
LARGE_DURATION_S = 20.0


def _best(scn: Scenario, repeats: int, record_every: int) -> tuple[float, float]:
    """Best wall time and best process CPU time [s] of ``repeats`` runs after a warm-up."""
    firefleet.simulate(scn, record_every=record_every)  # warm-up (and JIT compile)
    best, best_cpu = float("inf"), float("inf")
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        firefleet.simulate(scn, record_every=record_every)
        best = min(best, time.perf_counter() - start)
        best_cpu = min(best_cpu, time.process_time() - start_cpu)
    return best, best_cpu


def large_team(base: Scenario, n: int, duration_s: float) -> Scenario:
    """``base`` with its robots and paths repeated to ``n`` robots, ``duration_s`` long."""
    cmd = base.command
    assert isinstance(cmd, PathFollowing)
    k = len(base.poses)
    poses = tuple(base.poses[i % k] for i in range(n))
    paths = tuple(cmd.paths[i % k] for i in range(n))
    command = dataclasses.replace(cmd, paths=paths, trajectory_s=duration_s)
    return dataclasses.replace(base, poses=poses, command=command, duration_s=duration_s)


def run(console: Console) -> dict[str, Any]:
    """Measure, print a table with the floors, return every number."""
    base = firefleet.load_scenario("coop-different-paths")
    small_s, small_cpu_s = _best(base, repeats=7, record_every=1)
    big = large_team(base, LARGE_N, LARGE_DURATION_S)
    large_s, large_cpu_s = _best(big, repeats=3, record_every=10)
    rows: list[dict[str, Any]] = [
        {
            "case": "coop-different-paths (3 robots)",
            "simulated_s": base.duration_s,
            "wall_s": small_s,
            "cpu_s": small_cpu_s,
            "x_real_time": base.duration_s / small_s,
            "robot_steps_per_s": base.n_robots * base.n_steps / small_s,
            "floor_x_real_time": FLOOR_SMALL,
        },
        {
            "case": f"{LARGE_N:,} robots, same stack",
            "simulated_s": big.duration_s,
            "wall_s": large_s,
            "cpu_s": large_cpu_s,
            "x_real_time": big.duration_s / large_s,
            "robot_steps_per_s": big.n_robots * big.n_steps / large_s,
            "floor_x_real_time": FLOOR_LARGE,
        },
    ]
    for row in rows:
        row["pass"] = row["x_real_time"] >= row["floor_x_real_time"]
    table = Table(title="path following: simulation speed (best of runs)")
    for col in ("case", "wall time", "CPU time", "x real time", "robot-steps/s", "floor"):
        table.add_column(col, justify="left" if col == "case" else "right")
    for row in rows:
        verdict = "[green]PASS" if row["pass"] else "[red]FAIL"
        table.add_row(
            row["case"],
            f"{row['wall_s'] * 1e3:.1f} ms",
            f"{row['cpu_s'] * 1e3:.1f} ms",
            f"{row['x_real_time']:,.0f}x",
            f"{row['robot_steps_per_s']:,.0f}",
            f">= {row['floor_x_real_time']:,.0f}x {verdict}",
        )
    console.print(table)
    return {"rows": rows}


if __name__ == "__main__":
    run(Console())
    sys.exit(0)
