"""What a worker runs: a batch of seeds of one point, one row per run.

A task never raises for a run that fails: the run's row carries the error, and the
other runs of the batch go on. Every run draws its randomness from its own seed (the
scenario's ``seed`` replaced), so a row is the same whichever worker made it and in
whatever order.
"""

from __future__ import annotations

import math
import time
import traceback
from collections.abc import Sequence
from typing import Any

from firefleet.scenarios.schema import Claim, Scenario

__all__ = ["Row", "claim_key", "flat_metrics", "run_batch", "run_one"]

Row = dict[str, Any]
"""One run: ``point``, ``seed``, ``metric:NAME`` numbers, ``claim:KEY`` verdicts
(:func:`claim_key`), ``run_time_s`` and ``error`` (None for a run that finished)."""


def flat_metrics(metrics: dict[str, Any]) -> dict[str, float]:
    """Scalar columns of a run's metrics: a per-robot list becomes ``name[robot k]``.

    Examples
    --------
    >>> from firefleet.sweep import flat_metrics
    >>> flat_metrics({"rise_time_s": 0.1, "wait_s": [1.0, None], "peak": float("inf")})
    {'rise_time_s': 0.1, 'wait_s[robot 1]': 1.0, 'wait_s[robot 2]': nan, 'peak': inf}
    """
    flat: dict[str, float] = {}
    for name, value in metrics.items():
        if isinstance(value, list | tuple):
            for k, v in enumerate(value, start=1):
                flat[f"{name}[robot {k}]"] = math.nan if v is None else float(v)
        elif isinstance(value, bool | int | float):
            flat[name] = float(value)
        elif value is None:
            flat[name] = math.nan
    return flat


def claim_key(claim: Claim) -> str:
    """A claim's name in a sweep's table and summary: its label and its bound, so that two
    claims on one metric (``< 0.5`` and ``> 0.1``) stay apart.

    Examples
    --------
    >>> from firefleet.scenarios import Claim
    >>> from firefleet.sweep import claim_key
    >>> claim_key(Claim(metric="wait_time_s", op="<", value=1.0, robot=2))
    'wait_time_s[robot 2] < 1'
    """
    return f"{claim.label} {claim.expected}"


def run_one(scenario: Scenario, point: int, seed: int) -> Row:
    """Run one (point, seed) and return its row; an exception becomes the row's error.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sweep import run_one
    >>> row = run_one(load_scenario("motor-pid"), 0, 3)
    >>> row["seed"], row["error"], row["claim:rise_time_s < 0.2"], row["metric:rise_time_s"] < 0.2
    (3, None, True, True)
    """
    from firefleet.sim.engine import simulate
    from firefleet.sim.metrics import compute_metrics

    start = time.perf_counter()
    row: Row = {"point": point, "seed": seed}
    try:
        metrics = compute_metrics(simulate(scenario, seed=seed))
        for name, value in flat_metrics(metrics).items():
            row[f"metric:{name}"] = value
        for claim in scenario.claims:
            row[f"claim:{claim_key(claim)}"] = claim.holds(metrics.get(claim.metric))
        row["error"] = None
    except Exception as exc:  # a failing run is data: recorded, the sweep goes on
        where = traceback.extract_tb(exc.__traceback__)[-1:]
        at = f" (at {where[0].filename.rsplit('/', 1)[-1]}:{where[0].lineno})" if where else ""
        row["error"] = f"{type(exc).__name__}: {exc}{at}".replace("\n", " ")
    row["run_time_s"] = time.perf_counter() - start
    return row


def run_batch(scenario: Scenario, point: int, seeds: Sequence[int]) -> list[Row]:
    """Run several seeds of one point, one after the other, on one core.

    On a Dask worker, numba's parallel kernels are kept to one thread: the worker's
    cores are the worker processes' (one task per core), not one run's.
    """
    if _on_worker():
        import numba

        numba.set_num_threads(1)
    return [run_one(scenario, point, seed) for seed in seeds]


def _on_worker() -> bool:
    """True inside a task on a Dask worker (False in the client's own process)."""
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return False
    return True
