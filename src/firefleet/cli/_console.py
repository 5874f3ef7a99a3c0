"""What every command shares: exit statuses, the progress bar and the claims table."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from firefleet.errors import InputError
from firefleet.sim.engine import ProgressCallback

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_CLAIM_FAILED",
    "EXIT_OK",
    "ROBOT_ROWS",
    "all_passed",
    "check_flag",
    "claims_table",
    "metrics_table",
    "progress_bar",
    "shown",
]

EXIT_OK, EXIT_CLAIM_FAILED, EXIT_BAD_INPUT = 0, 1, 2


@contextmanager
def progress_bar(
    console: Console,
    label: str,
    *,
    clock: Callable[[], float] = time.monotonic,
    quiet_s: float = 2.0,
) -> Iterator[ProgressCallback]:
    """A progress callback ``(done, total)`` showing progress on ``console`` while open.

    On a terminal, a bar. Elsewhere (a pipe, a CI log) plain lines at each quarter of
    the work, from the first quarter reached after ``quiet_s`` seconds (``clock``), so a
    short run prints nothing and a long one a few lines.
    """
    if console.is_terminal:
        columns = (TextColumn("{task.description}"), BarColumn(), TimeRemainingColumn())
        with Progress(*columns, console=console, transient=True) as bar:
            task = bar.add_task(label, total=None)

            def update(done: int, total: int) -> None:
                bar.update(task, completed=done, total=total)

            yield update
        return
    start = clock()
    next_quarter = [1]

    def plain(done: int, total: int) -> None:
        if total <= 0 or 4 * done < next_quarter[0] * total:
            return
        while next_quarter[0] <= 4 and 4 * done >= next_quarter[0] * total:
            next_quarter[0] += 1
        elapsed_s = clock() - start
        if elapsed_s >= quiet_s:
            console.print(
                f"{label}: {100 * done // total} % ({elapsed_s:.0f} s)",
                markup=False,
                highlight=False,
                soft_wrap=True,
            )

    yield plain


def claims_table(
    title: str,
    values: Iterable[tuple[str, Any]],
    claims: Iterable[Mapping[str, Any]],
    *,
    columns: tuple[str, str] = ("metric", "measured"),
    items: Mapping[str, str] | None = None,
) -> Table:
    """One row per named value, with the claims on it and their verdicts; fits 80 columns.

    A claim belongs to the row of its name, or of its name before ``[`` (a claim on one
    robot of a per-robot metric, ``name[robot k]``). A per-robot value (a list) gets an
    indented row per robot, or, beyond :data:`ROBOT_ROWS` robots, rows for its minimum,
    mean and maximum and one per robot a claim names. ``items`` names what one value of
    a list is about where it is not a robot (``{"victims_found_s": "victim"}``, a task
    kind's ``list_items``): its rows read ``[victim k]``.
    """
    claims = list(claims)
    table = Table(title=title, title_justify="left")
    table.add_column(columns[0], no_wrap=True, overflow="fold")
    table.add_column(columns[1], justify="right", overflow="fold")
    table.add_column("claim", overflow="fold")
    table.add_column("result", no_wrap=True)
    for key, value in values:
        mine = [c for c in claims if c["name"].split("[")[0] == key]
        whole = [c for c in mine if c["name"] == key]
        if not isinstance(value, list):
            table.add_row(key, shown(value), *_verdicts(whole))
            continue
        table.add_row(key, "", *_verdicts(whole))
        picked = {
            int(c["name"].removeprefix(key + "[robot ").rstrip("]"))
            for c in mine
            if c["name"].startswith(key + "[robot ")
        }
        numbers = [v for v in value if v is not None]
        if len(value) > ROBOT_ROWS and numbers:
            for name, number in (
                ("min", min(numbers)),
                ("mean", sum(numbers) / len(numbers)),
                ("max", max(numbers)),
            ):
                table.add_row(f"  {name} of {len(value)}", shown(number), "", "")
        robots = range(1, len(value) + 1) if len(value) <= ROBOT_ROWS else sorted(picked)
        item = (items or {}).get(key, "robot")
        for k in robots:
            label = f"{key}[robot {k}]"
            here = [c for c in mine if c["name"] == label]
            measured = value[k - 1] if k <= len(value) else None
            table.add_row(escape(f"  [{item} {k}]"), shown(measured), *_verdicts(here))
    return table


def metrics_table(document: dict[str, Any], items: Mapping[str, str] | None = None) -> Table:
    """The claims table of a ``metrics.json`` document (``items``: :func:`claims_table`'s)."""
    values = [(k, v) for k, v in document.items() if k not in ("scenario", "claims")]
    return claims_table(
        f"{document['scenario']}: metrics and claims", values, document["claims"], items=items
    )


ROBOT_ROWS = 5
"""Per-robot values of at most this many robots get one table row each."""


def _verdicts(claims: list[Mapping[str, Any]]) -> tuple[str, str]:
    expected = "\n".join(escape(str(c["expected"])) for c in claims)
    verdict = "\n".join("[green]passed" if c["passed"] else "[red]FAILED" for c in claims)
    return expected, verdict


def shown(value: Any) -> str:
    """A measured value as the tables show it: ``n/a`` for none, 6 significant digits."""
    if value is None:
        return "n/a"
    if isinstance(value, list):
        return escape("[" + ", ".join(f"{v:.4g}" if v is not None else "n/a" for v in value) + "]")
    if isinstance(value, float):
        return f"{value:.6g}"
    return escape(str(value))


def all_passed(document: Mapping[str, Any]) -> bool:
    """Whether every claim of a metrics or summary document holds."""
    return all(c["passed"] for c in document["claims"])


def check_flag(ok: bool, flag: str, value: Any, expected: str) -> None:
    """Raise an InputError naming the flag a person typed unless ``ok``."""
    if not ok:
        raise InputError(f"{flag} must be {expected}, got {value}")
