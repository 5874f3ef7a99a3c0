"""Running a sweep's runs on a Dask client: batching, progress, failures, Ctrl-C.

The runs of a point are cut into tasks of several seeds when runs are short: a task
aims at ``target_task_s`` of work, judged from the shortest run seen so far for that
point (a worker's first run also loads the compiled kernels, so it overestimates), and
no task takes more than its share of what is left, so every worker keeps busy to the
end. A few tasks per worker thread are in flight at once, so a worker never waits for
the scheduler between two tasks.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from firefleet.sweep._grid import Point
from firefleet.sweep._tasks import Row, run_batch

__all__ = ["SweepInterrupted", "SweepProgress", "execute"]


@dataclass(frozen=True)
class SweepProgress:
    """Where a sweep is: runs ``done`` (finished or failed) of ``total``, ``failed``,
    ``running`` (in tasks a worker holds), and ``elapsed_s`` since the first task."""

    total: int
    done: int
    failed: int
    running: int
    elapsed_s: float


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep: the tasks were cancelled; ``rows`` holds the finished runs."""

    def __init__(self, rows: list[Row]) -> None:
        super().__init__("sweep interrupted")
        self.rows = rows


def execute(
    client: Any,
    points: Sequence[Point],
    todo: Sequence[tuple[int, int]],
    *,
    progress: Callable[[SweepProgress], None] | None = None,
    target_task_s: float = 0.2,
    per_thread: int = 3,
) -> list[Row]:
    """Run every (point index, seed) of ``todo`` on ``client``; one row per run.

    Parameters
    ----------
    client : distributed.Client
        Where the tasks go (a LocalCluster's or a remote scheduler's).
    points : sequence of Point
        The sweep's points, by index.
    todo : sequence of (int, int)
        (point index, seed) pairs to run, in the order to submit them.
    progress : callable, optional
        Called with a :class:`SweepProgress` after each task.
    target_task_s : float
        Work per task [s] when runs are short.
    per_thread : int
        Tasks in flight per worker thread.

    Returns
    -------
    list of dict
        The rows, in the order they finished (sort them to compare).

    Raises
    ------
    SweepInterrupted
        On Ctrl-C, after cancelling the tasks in flight, with the rows finished so far.
    """
    from distributed import as_completed

    pending: deque[tuple[int, int]] = deque(todo)
    fastest: dict[int, float] = {}
    rows: list[Row] = []
    inflight: dict[Any, tuple[int, list[int]]] = {}
    failed = 0
    start = time.monotonic()
    queue = as_completed()  # type: ignore[no-untyped-call]

    known = [0, -math.inf]  # worker threads, when last asked (asking is a round trip)

    def threads() -> int:
        if time.monotonic() - known[1] > 1.0:
            known[:] = [max(1, int(sum(client.nthreads().values()))), time.monotonic()]
        return int(known[0])

    def submit_more() -> None:
        limit = per_thread * threads()
        while pending and len(inflight) < limit:
            point = pending[0][0]
            seen = fastest.get(point, min(fastest.values(), default=math.inf))
            size = 1 if not math.isfinite(seen) else int(target_task_s / max(seen, 1e-6))
            size = max(1, min(size, math.ceil(len(pending) / threads())))
            seeds: list[int] = []
            while pending and pending[0][0] == point and len(seeds) < size:
                seeds.append(pending.popleft()[1])
            future = client.submit(run_batch, points[point].scenario, point, seeds, pure=False)
            inflight[future] = (point, seeds)
            queue.add(future)  # type: ignore[no-untyped-call]

    def report() -> None:
        if progress is not None:
            running = sum(len(s) for _, s in inflight.values())
            progress(
                SweepProgress(
                    len(todo), len(rows), failed, min(running, threads()), time.monotonic() - start
                )
            )

    try:
        submit_more()
        report()
        for future in queue:
            point, seeds = inflight.pop(future)
            if future.status == "finished":
                batch: list[Row] = future.result()
            else:  # the task itself died (a worker lost, an unpicklable result)
                exc = future.exception()
                error = f"task failed: {type(exc).__name__}: {exc}".replace("\n", " ")
                batch = [
                    {"point": point, "seed": s, "error": error, "run_time_s": math.nan}
                    for s in seeds
                ]
            future.release()
            for row in batch:
                failed += row["error"] is not None
                if row["error"] is None:
                    fastest[point] = min(fastest.get(point, math.inf), row["run_time_s"])
            rows.extend(batch)
            submit_more()
            report()
    except KeyboardInterrupt:
        client.cancel(list(inflight))
        raise SweepInterrupted(rows) from None
    return rows
