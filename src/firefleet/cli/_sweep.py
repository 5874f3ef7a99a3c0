"""``firefleet sweep``: one scenario over parameter points and seeds, on Dask."""

from __future__ import annotations

import argparse
import contextlib
import math
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from firefleet.cli._console import EXIT_OK
from firefleet.errors import InputError
from firefleet.outputs import json_text, run_record, staged_dir

__all__ = ["EXIT_RUNS_FAILED", "add_parsers", "connect", "sweep_progress"]

EXIT_RUNS_FAILED = 10
"""A sweep some of whose runs raised exits ``10 + the number of failed runs`` (110 for
100 or more); 0 when every run finished (whatever its claims), 130 on Ctrl-C."""

EXIT_INTERRUPTED = 130
CONNECT_TIMEOUT_S = 3.0


def add_parsers(sub: Any) -> None:
    """Add ``sweep`` to the subcommands ``sub``."""
    p = sub.add_parser(
        "sweep",
        help="run a scenario over parameter values and seeds on Dask (local or a cluster)",
        description="Run SCENARIO once per (point, seed): a point is one value of each "
        "--set (their grid, or their pairs with --zip). Writes results.parquet, "
        "results.csv (one row per run), summary.json and plots into --out; a rerun with "
        "the same --out skips the runs already finished.",
    )
    p.add_argument("scenario", metavar="SCENARIO", help="built-in name or a YAML path")
    p.add_argument(
        "--seeds", default="0:10", metavar="A:B", help="seeds A to B-1, or N, or N,M,..."
    )
    p.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="KEY=V1,V2,...",
        help="a scenario key by its dotted path and its values (a YAML value each, or "
        "@file.yaml); several --set form a grid",
    )
    p.add_argument("--zip", action="store_true", help="pair the --set values instead of a grid")
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: one per core)"
    )
    where.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="a running Dask scheduler (its workers need firefleet installed)",
    )
    p.add_argument("--out", metavar="DIR", help="output folder (default: sweeps/SCENARIO)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    p.set_defaults(handler=cmd_sweep)


@contextlib.contextmanager
def connect(scheduler: str | None, workers: int | None) -> Iterator[Any]:
    """A Dask client: to ``scheduler``, or on a new LocalCluster of ``workers`` processes.

    Raises
    ------
    InputError
        Naming ``--scheduler`` when it cannot be reached within a few seconds or no
        worker joins it, or ``--workers`` when it is below 1.
    """
    if scheduler is None:
        if workers is not None and workers < 1:
            raise InputError(f"--workers must be >= 1, got {workers}")
        from firefleet.sweep import local_client

        client = local_client(workers)
        try:
            yield client
        finally:
            client.close()
            client.cluster.close()
        return
    if "://" not in scheduler or not scheduler.split("://", 1)[1]:
        raise InputError(f"--scheduler {scheduler}: expected an address such as tcp://HOST:8786")
    from distributed import Client

    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)  # type: ignore[no-untyped-call]
    except (OSError, TimeoutError, ValueError) as exc:
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(
            f"--scheduler {scheduler}: no scheduler reached within "
            f"{CONNECT_TIMEOUT_S:g} s ({detail[:120]})"
        ) from None
    try:
        try:
            client.wait_for_workers(1, timeout=30)
        except TimeoutError:
            raise InputError(f"--scheduler {scheduler}: no worker joined within 30 s") from None
        yield client
    finally:
        client.close()  # type: ignore[no-untyped-call]


@contextlib.contextmanager
def sweep_progress(
    console: Console, label: str, *, quiet_s: float = 2.0
) -> Iterator[Callable[[Any], None]]:
    """A callback taking :class:`firefleet.sweep.SweepProgress`: a bar on a terminal
    (done, failed, running, time left), else a line at every tenth of the runs, from
    the first tenth reached after ``quiet_s`` seconds (a short sweep prints none)."""
    if console.is_terminal:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeRemainingColumn,
        )

        columns = (
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]} failed, {task.fields[running]} running"),
            TimeRemainingColumn(),
        )
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task(label, total=None, failed=0, running=0)

            def update(state: Any) -> None:
                bar.update(
                    task,
                    completed=state.done,
                    total=state.total,
                    failed=state.failed,
                    running=state.running,
                )

            yield update
        return
    next_tenth = [1]

    def plain(state: Any) -> None:
        if state.total <= 0 or 10 * state.done < next_tenth[0] * state.total:
            return
        while next_tenth[0] <= 10 and 10 * state.done >= next_tenth[0] * state.total:
            next_tenth[0] += 1
        if state.elapsed_s < quiet_s:
            return
        left = (
            f", ~{state.elapsed_s * (state.total - state.done) / state.done:.0f} s left"
            if state.done
            else ""
        )
        console.print(
            f"{label}: {state.done}/{state.total} runs, {state.failed} failed, "
            f"{state.running} running, {state.elapsed_s:.0f} s{left}",
            markup=False,
            highlight=False,
            soft_wrap=True,
        )

    yield plain


def _previous(dest: Path) -> Any:
    """The table of a previous sweep in ``dest`` (to resume), or None."""
    from firefleet.sweep import column_roles, read_parquet

    path = dest / "results.parquet"
    if not path.is_file():
        return None
    try:
        table = read_parquet(path.read_bytes())
        column_roles(table)
    except (OSError, ValueError) as exc:
        raise InputError(f"--out {dest}: results.parquet is not a sweep's table: {exc}") from None
    return table


def _summary_table(summary: dict[str, Any]) -> Table:
    """Each claim's pass rate: a column per point (up to 6), else a row per point."""
    table = Table(title=f"{summary['scenario']}: pass rate of each claim", title_justify="left")
    entries = summary["points"]
    labels = list(entries[0]["claims"]) if entries else []

    def rate(entry: dict[str, Any], label: str) -> str:
        value = entry["claims"][label]["pass_rate"]
        return "n/a" if math.isnan(value) else f"{100 * value:.0f}%"

    def point_name(entry: dict[str, Any]) -> str:
        return ", ".join(entry["values"].values()) or "all runs"

    if summary["params"]:
        table.title = f"{table.title} at ({', '.join(summary['params'])})"
    if len(entries) <= 6:
        table.add_column("claim", overflow="fold")
        for entry in entries:
            table.add_column(escape(point_name(entry)), justify="right", no_wrap=True, min_width=4)
        failed = sum(e["failed"] for e in entries)
        table.caption = f"{entries[0]['runs']} runs per point" + (
            f"; {failed} failed (not counted)" if failed else ""
        )
        for label in labels:
            table.add_row(escape(label), *(rate(e, label) for e in entries))
        return table
    table.add_column("point", overflow="fold")
    table.add_column("runs (failed)", justify="right")
    for k in range(1, len(labels) + 1):
        table.add_column(f"c{k}", justify="right")
    for entry in entries:
        table.add_row(
            escape(point_name(entry)),
            f"{entry['runs']} ({entry['failed']})",
            *(rate(entry, label) for label in labels),
        )
    table.caption = escape("; ".join(f"c{k}: {label}" for k, label in enumerate(labels, start=1)))
    return table


def cmd_sweep(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet sweep SCENARIO``."""
    from firefleet.scenarios.registry import load_scenario
    from firefleet.sweep import (
        SweepInterrupted,
        build_table,
        csv_bytes,
        parquet_bytes,
        parse_seeds,
        parse_set,
        points_of,
        reusable,
        run_points,
        summarize,
    )

    scenario = load_scenario(args.scenario)
    seeds = parse_seeds(args.seeds)
    axes = [parse_set(text) for text in args.sets]
    for axis in axes:
        if axis.key in ("seed", "name"):
            raise InputError(f"--set {axis.key}: not a sweep key (give seeds with --seeds)")
    points = points_of(scenario, axes, zipped=args.zip)
    dest = Path(args.out) if args.out else Path("sweeps") / scenario.name
    previous = _previous(dest)
    record = run_record(args.command_line, seed=None)
    interrupted = False
    start = time.monotonic()
    with staged_dir(dest, record=record) as stage:
        needed = bool(reusable(points, seeds, previous)[1])  # no cluster for nothing
        where = connect(args.scheduler, args.workers) if needed else contextlib.nullcontext()
        with where as client:
            label = f"{scenario.name}: {len(points)} point(s) x {len(seeds)} seed(s)"
            try:
                with sweep_progress(err, label) as progress:
                    table, reused = run_points(
                        client, points, seeds, scenario.name, previous=previous, progress=progress
                    )
            except SweepInterrupted as stop:
                interrupted = True
                table, reused = build_table(points, stop.rows, scenario.name), 0
        summary = summarize(table, points)
        summary["complete"] = not interrupted and table.num_rows == len(points) * len(seeds)
        (stage / "results.parquet").write_bytes(parquet_bytes(table))
        (stage / "results.csv").write_bytes(csv_bytes(table))
        (stage / "summary.json").write_text(json_text(summary), encoding="utf-8")
        if not args.no_plots and table.num_rows:
            from firefleet.report.sweep import sweep_figures  # matplotlib only when plotting

            (stage / "plots").mkdir()
            for name, data in sweep_figures(table, summary, scenario.claims).items():
                (stage / "plots" / name).write_bytes(data)
    out.print(_summary_table(summary))
    failed = int(summary["failed"])
    took = time.monotonic() - start
    out.print(
        f"{table.num_rows} runs ({reused} reused from {dest}/), {failed} failed, {took:.1f} s",
        markup=False,
        highlight=False,
    )
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    if interrupted:
        err.print(
            f"firefleet: interrupted; the {table.num_rows} finished runs are in {dest}/ "
            "(run the same command again to finish)",
            markup=False,
            highlight=False,
        )
        return EXIT_INTERRUPTED
    if failed:
        err.print(
            f"firefleet: {failed} of {table.num_rows} runs failed (column 'error' of "
            f"{dest}/results.csv); exit status {EXIT_RUNS_FAILED} + {min(failed, 100)}",
            markup=False,
            highlight=False,
        )
        return EXIT_RUNS_FAILED + min(failed, 100)
    return EXIT_OK


def seed_pass_rates(
    entries: list[Any],
    scenarios: list[Any],
    seeds: tuple[int, ...],
    typed: str,
    stage: Path,
    out: Console,
    err: Console,
) -> list[Any]:
    """``firefleet reproduce --seeds``: every scenario over ``seeds`` on a LocalCluster.

    Writes each scenario's runs as ``NAME/seeds.csv`` in ``stage`` and returns the report
    entries with each claim's pass rate (a run that raised counts as not holding).
    """
    import dataclasses

    from firefleet.sweep import build_table, claim_key, csv_bytes, execute, points_of

    points = [
        dataclasses.replace(points_of(scn, [])[0], index=k) for k, scn in enumerate(scenarios)
    ]
    todo = [(p.index, s) for p in points for s in seeds]
    label = f"{len(scenarios)} experiments x {len(seeds)} seeds"
    with connect(None, None) as client, sweep_progress(err, label) as progress:
        rows = execute(client, points, todo, progress=progress)
    by_name: dict[str, tuple[Any, list[Any]]] = {}
    for point in points:
        mine = [r for r in rows if r["point"] == point.index]
        by_name[point.scenario.name] = (point, mine)
    updated = []
    for entry in entries:
        if entry.name not in by_name:
            updated.append(entry)
            continue
        point, mine = by_name[entry.name]
        table = build_table([point], mine, entry.name)
        (stage / entry.folder / "seeds.csv").write_bytes(csv_bytes(table))
        rates = {
            claim_key(claim): (
                sum(r.get(f"claim:{claim_key(claim)}") is True for r in mine),
                len(mine),
            )
            for claim in point.scenario.claims
        }
        always = sum(passed == runs for passed, runs in rates.values())
        failed = sum(r["error"] is not None for r in mine)
        note = f", {failed} run(s) failed" if failed else ""
        out.print(
            f"{entry.name:<24} seeds {typed}: {always} of {len(rates)} claims hold on every "
            f"seed{note}",
            markup=False,
            highlight=False,
        )
        updated.append(
            dataclasses.replace(
                entry, pass_rates=rates, seeds=typed, links=(*entry.links, "seeds.csv")
            )
        )
    return updated
