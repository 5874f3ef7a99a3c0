"""What every command shares: exit statuses, the progress bar and the claims table."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
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
    "all_passed",
    "check_flag",
    "claims_table",
    "progress_bar",
    "shown",
]

EXIT_OK, EXIT_CLAIM_FAILED, EXIT_BAD_INPUT = 0, 1, 2


@contextmanager
def progress_bar(console: Console, label: str) -> Iterator[ProgressCallback]:
    """A progress callback ``(done, total)`` drawing a bar on ``console`` while open."""
    columns = (TextColumn("{task.description}"), BarColumn(), TimeRemainingColumn())
    if not console.is_terminal:  # a log file gets no bar (and no blank lines from one)
        yield lambda done, total: None
        return
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        yield update


def claims_table(
    title: str,
    values: Iterable[tuple[str, Any]],
    claims: Iterable[Mapping[str, Any]],
    *,
    columns: tuple[str, str] = ("metric", "measured"),
) -> Table:
    """One row per named value, with the claims on it and their verdicts.

    A claim belongs to the row of its name, or of its name before ``[`` (a claim on one
    robot of a per-robot metric, ``name[robot k]``).
    """
    claims = list(claims)
    table = Table(title=title)
    table.add_column(columns[0])
    table.add_column(columns[1], justify="right")
    table.add_column("claim")
    table.add_column("result")
    for key, value in values:
        mine = [c for c in claims if c["name"].split("[")[0] == key]
        expected = escape(
            "; ".join(c["expected"] + c["name"].removeprefix(key).replace("[", " [") for c in mine)
        )
        verdict = " ".join("[green]passed" if c["passed"] else "[red]FAILED" for c in mine)
        table.add_row(key, shown(value), expected, verdict)
    return table


def shown(value: Any) -> str:
    """A measured value as the tables show it: ``n/a`` for none, 6 digits, lists at 4."""
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
