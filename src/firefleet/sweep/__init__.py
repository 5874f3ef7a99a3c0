"""Sweeps: one scenario run over parameter points and seeds, on Dask.

``firefleet.sweep(scenario, grid, seeds)`` runs every (point, seed) as a task on a Dask
client (a ``LocalCluster`` of processes when none is given, or the notebook's own) and
returns one ``pyarrow.Table`` row per run. pyarrow, not pandas: it is what writes
``results.parquet`` anyway, it holds nulls in boolean and float columns without
conversions (a failed run's claims), and ``table.to_pandas()`` is one call for whoever
has pandas; firefleet does not need pandas.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario
from firefleet.sweep._execute import SweepInterrupted, SweepProgress, execute
from firefleet.sweep._grid import (
    Point,
    SweepAxis,
    parse_seeds,
    parse_set,
    points_of,
    scenario_data,
)
from firefleet.sweep._summary import summarize
from firefleet.sweep._table import (
    build_table,
    column_roles,
    csv_bytes,
    parquet_bytes,
    read_parquet,
    rows_of,
)
from firefleet.sweep._tasks import Row, claim_key, flat_metrics, run_batch, run_one

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = [
    "Point",
    "Row",
    "SweepAxis",
    "SweepInterrupted",
    "SweepProgress",
    "build_table",
    "claim_key",
    "column_roles",
    "csv_bytes",
    "execute",
    "flat_metrics",
    "local_client",
    "parquet_bytes",
    "parse_seeds",
    "parse_set",
    "points_of",
    "read_parquet",
    "reusable",
    "rows_of",
    "run_batch",
    "run_one",
    "run_points",
    "scenario_data",
    "summarize",
    "sweep",
]


def local_client(workers: int | None = None) -> Any:
    """A Dask client on a new ``LocalCluster``: ``workers`` processes (default: one per
    core), one thread each, no dashboard, quiet logs. Close it (``client.close()`` and
    ``client.cluster.close()``) or use it in a ``with`` block."""
    import logging
    import os
    import signal
    import threading

    from distributed import Client, LocalCluster

    n = workers if workers is not None else (os.cpu_count() or 1)
    if n < 1:
        raise InputError(f"--workers must be >= 1, got {n}")
    # The workers start with Ctrl-C ignored: a terminal's Ctrl-C reaches every process of
    # the group, and it is the client's to handle (cancel, keep what finished, close).
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        cluster = LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    finally:
        if main:
            signal.signal(signal.SIGINT, previous)
    return Client(cluster)  # type: ignore[no-untyped-call]


def reusable(
    points: Sequence[Point], seeds: Sequence[int], previous: pa.Table | None
) -> tuple[list[Row], list[tuple[int, int]]]:
    """The rows of ``previous`` to keep and the (point, seed) pairs still to run.

    A run is kept when it finished (no error) and its point's scenario digest and seed
    match; failed runs are run again.
    """
    digests = {p.digest: p.index for p in points}
    kept: list[Row] = []
    if previous is not None:
        for row in rows_of(previous):
            index = digests.get(row.pop("point_digest"))
            if row["error"] is None and index is not None and row["seed"] in seeds:
                kept.append({**row, "point": index})
    done = {(r["point"], r["seed"]) for r in kept}
    todo = [(p.index, s) for p in points for s in seeds if (p.index, s) not in done]
    return kept, todo


def run_points(
    client: Any,
    points: Sequence[Point],
    seeds: Sequence[int],
    scenario_name: str,
    *,
    previous: pa.Table | None = None,
    progress: Callable[[SweepProgress], None] | None = None,
) -> tuple[pa.Table, int]:
    """Run what ``previous`` lacks of points x seeds; the whole table and the runs reused.

    A run of ``previous`` is reused when it finished (no error) and its point's
    scenario digest and seed match; failed runs are run again.

    Raises
    ------
    SweepInterrupted
        On Ctrl-C; its ``rows`` then hold the reused and the finished runs.
    """
    kept, todo = reusable(points, seeds, previous)
    try:
        rows = execute(client, points, todo, progress=progress) if todo else []
    except SweepInterrupted as stop:
        raise SweepInterrupted(kept + stop.rows) from None
    return build_table(points, kept + rows, scenario_name), len(kept)


def sweep(
    scenario: str | Path | Scenario,
    grid: Mapping[str, Sequence[Any]] | None = None,
    seeds: Iterable[int] = (0,),
    client: Any = None,
    *,
    zipped: bool = False,
) -> pa.Table:
    """Run a scenario over a grid of parameter values and seeds; one row per run.

    Parameters
    ----------
    scenario : str, Path or Scenario
        A built-in name, a YAML path, or a scenario.
    grid : mapping of str to sequence, optional
        Dotted scenario key -> its values (plain data, as YAML would give them), e.g.
        ``{"command.speed_rad_s": [1.0, 2.0]}``; several keys form their product.
    seeds : iterable of int
        The seeds run at every point.
    client : distributed.Client, optional
        Where to run (a notebook's own client); default: a ``LocalCluster`` with one
        worker process per core, closed at the end.
    zipped : bool
        Pair the keys' values instead of forming their product.

    Returns
    -------
    pyarrow.Table
        Sorted by point, then seed; columns as :func:`build_table` describes. The same
        whatever the number of workers or the order the runs finish in, but for
        ``run_time_s``.

    Raises
    ------
    InputError
        For an unknown key, a bad value or no seeds, before anything runs.

    Examples
    --------
    >>> import firefleet
    >>> from distributed import Client
    >>> with Client(processes=False, n_workers=1, threads_per_worker=1,
    ...             dashboard_address=None) as client:
    ...     table = firefleet.sweep("motor-pid", {"command.speed_rad_s": [1.0, 2.0]},
    ...                             seeds=range(2), client=client)
    >>> table.column("command.speed_rad_s").to_pylist(), table.column("seed").to_pylist()
    ([1.0, 1.0, 2.0, 2.0], [0, 1, 0, 1])
    """
    from firefleet.scenarios.registry import load_scenario

    base = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    axes = [
        SweepAxis(str(key), tuple(values), tuple(_label(v) for v in values))
        for key, values in (grid or {}).items()
    ]
    for axis in axes:
        if not axis.values:
            raise InputError(f"grid[{axis.key!r}]: no values")
    seed_list = tuple(sorted({int(s) for s in seeds}))
    if not seed_list:
        raise InputError("seeds: an empty range of seeds")
    if seed_list[0] < 0:
        raise InputError(f"seeds must be >= 0, got {seed_list[0]}")
    points = points_of(base, axes, zipped=zipped)
    if client is not None:
        return run_points(client, points, seed_list, base.name)[0]
    with local_client() as own:
        try:
            return run_points(own, points, seed_list, base.name)[0]
        finally:
            own.cluster.close()


def _label(value: Any) -> str:
    import json

    return value if isinstance(value, str) else json.dumps(value)
