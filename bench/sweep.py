"""Benchmark: sweeps on Dask (issue 18).

1. Overhead per task on a ``LocalCluster``: 400 tasks of one trivial run each (a 0.1 s
   open-loop motor step, about 0.1 ms of work), batching off: wall time per task and
   tasks per second, with 1 and 2 workers.
2. 1,000 runs of ``motor-pid`` (seeds 0-999) with 1 and with 2 workers, short runs
   batched as ``firefleet sweep`` does; the speed-up, and the same runs one after the
   other in this process (no Dask) for the ideal.
3. Memory: a worker's resident set size sampled at each quarter of a 1,000-task sweep
   (batching off): flat when results are not kept on the workers.

The clusters are started before the clock starts. Best of a few repeats; on a machine
shared with other work, the speed-up measures the free cores too.

``make bench`` runs it through ``bench/run.py``; ``python bench/sweep.py`` runs it alone.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from typing import Any

from rich.console import Console
from rich.table import Table

import firefleet
from _harness import Floor, Row, TopicResult
from firefleet.sweep import execute, local_client, points_of

OVERHEAD_TASKS = 400
RUNS = 1_000
MEMORY_TASKS = 1_000


def _trivial() -> Any:
    base = firefleet.load_scenario("motor-open-loop")
    return dataclasses.replace(base, duration_s=0.1, claims=())


def _timed(client: Any, points: Any, todo: list[tuple[int, int]], **kw: Any) -> float:
    start = time.perf_counter()
    rows = execute(client, points, todo, **kw)
    took = time.perf_counter() - start
    assert len(rows) == len(todo)
    assert all(r["error"] is None for r in rows)
    return took


def _rss_mb() -> float:
    import psutil  # type: ignore[import-untyped]

    return float(psutil.Process().memory_info().rss / 1e6)


def run(console: Console) -> TopicResult:
    """Measure, print the tables, return rows and floors."""
    trivial = points_of(_trivial(), [])
    pid = points_of(firefleet.load_scenario("motor-pid"), [])
    overhead: dict[int, float] = {}
    sweep_s: dict[int, float] = {}
    memory: list[dict[str, float]] = []
    for workers in (1, 2):
        with local_client(workers) as client:
            todo = [(0, s) for s in range(OVERHEAD_TASKS)]
            _timed(client, trivial, todo[:20], target_task_s=0.0)  # warm the workers
            overhead[workers] = min(
                _timed(client, trivial, todo, target_task_s=0.0) for _ in range(3)
            )
            runs = [(0, s) for s in range(RUNS)]
            _timed(client, pid, runs[:50])  # compile/load the kernels on every worker
            sweep_s[workers] = min(_timed(client, pid, runs) for _ in range(3))
            if workers == 2:
                tasks = [(0, s) for s in range(MEMORY_TASKS)]
                marks = {MEMORY_TASKS * q // 4 for q in range(1, 5)}

                def sample(state: Any, client: Any = client, marks: set[int] = marks) -> None:
                    if state.done in marks:
                        marks.discard(state.done)
                        per_worker = client.run(_rss_mb)
                        memory.append({"done": state.done, **per_worker})

                execute(client, pid, tasks, progress=sample, target_task_s=0.0)
            client.cluster.close()
    start = time.perf_counter()
    for s in range(RUNS):
        firefleet.compute_metrics(firefleet.simulate(pid[0].scenario, seed=s))
    serial_s = time.perf_counter() - start

    per_task_ms = {w: 1e3 * t / OVERHEAD_TASKS for w, t in overhead.items()}
    speedup = sweep_s[1] / sweep_s[2]
    workers_rss = [k for k in memory[0] if k != "done"] if memory else []
    growth = max((memory[-1][k] / memory[0][k] for k in workers_rss), default=float("nan"))
    table = Table(title="sweep on a LocalCluster (best of 3)")
    for col in ("case", "1 worker", "2 workers"):
        table.add_column(col, justify="left" if col == "case" else "right")
    table.add_row(
        f"{OVERHEAD_TASKS} one-run tasks: wall time per task",
        f"{per_task_ms[1]:.2f} ms",
        f"{per_task_ms[2]:.2f} ms",
    )
    table.add_row(
        "  tasks per second",
        f"{OVERHEAD_TASKS / overhead[1]:,.0f}",
        f"{OVERHEAD_TASKS / overhead[2]:,.0f}",
    )
    table.add_row(
        f"{RUNS:,} runs of motor-pid (batched)", f"{sweep_s[1]:.2f} s", f"{sweep_s[2]:.2f} s"
    )
    table.add_row("  speed-up over 1 worker", "1.00x", f"{speedup:.2f}x")
    table.add_row(f"  the same {RUNS:,} runs in this process, no Dask", f"{serial_s:.2f} s", "")
    console.print(table)
    mem = Table(title=f"worker resident memory over a {MEMORY_TASKS:,}-task sweep (MB)")
    mem.add_column("tasks done", justify="right")
    for k, _ in enumerate(workers_rss):
        mem.add_column(f"worker {k + 1}", justify="right")
    for sample_row in memory:
        mem.add_row(str(sample_row["done"]), *(f"{sample_row[k]:.1f}" for k in workers_rss))
    console.print(mem)
    console.print(f"largest growth from the first quarter to the end: {growth:.3f}x")

    rows = (
        Row(
            "sweep.overhead.w2.ms_per_task",
            per_task_ms[2],
            "ms",
            False,
            label="Dask overhead per task, 2 workers",
        ),
        Row(
            "sweep.overhead.w2.tasks_per_s",
            OVERHEAD_TASKS / overhead[2],
            "tasks/s",
            label="one-run tasks per second, 2 workers",
        ),
        Row(
            "sweep.motor_pid_1000.w1.wall_s",
            sweep_s[1],
            "s",
            False,
            label="1,000 motor-pid runs, 1 worker",
        ),
        Row(
            "sweep.motor_pid_1000.w2.wall_s",
            sweep_s[2],
            "s",
            False,
            label="1,000 motor-pid runs, 2 workers",
        ),
        Row("sweep.motor_pid_1000.speedup_w2", speedup, "x", label="speed-up of 2 workers over 1"),
        Row(
            "sweep.memory.worker_rss_growth",
            growth,
            "x",
            False,
            "memory",
            label="worker RSS, end over first quarter",
        ),
    )
    floors = (
        Floor.on(
            rows[4], ">=", 1.5, "2 workers at least 1.5x faster than 1 (1,000 motor-pid runs)"
        ),
        Floor.on(rows[5], "<=", 1.10, "a worker's memory flat over 1,000 tasks (<= 10 % growth)"),
    )
    details = {
        "overhead_wall_s": overhead,
        "motor_pid_1000_wall_s": sweep_s,
        "motor_pid_1000_serial_in_process_s": serial_s,
        "worker_rss_mb": memory,
    }
    return TopicResult(rows=rows, floors=floors, details=details)


if __name__ == "__main__":
    run(Console())
    sys.exit(0)
