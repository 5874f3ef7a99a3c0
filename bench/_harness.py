"""The bench's one helper: timing, memory, machine information, rows, floors, the results file.

Every topic module (``bench/<topic>.py``) measures with these functions and returns a
:class:`TopicResult` from its ``run(console)``:

- **rows**, the numbers a later run is compared with (:class:`Row`: a stable ``key``
  such as ``"motor.team.n10000.steps_per_s"``, a value, a unit, which direction is
  better, and whether it is a speed or a memory number);
- **floors**, the promises the bench checks (:class:`Floor`: measured against a bound,
  PASS/FAIL);
- **details**, every other number (JSON-able), written to the results file as it is.

``bench/run.py`` collects the topics' results, prints one table of floors, writes the
results file (:func:`write_results`) and compares every row with ``bench/baseline.json``
(:func:`compare`, :func:`regressions`): a speed row more than
:data:`REGRESSION_TOLERANCE` slower than its baseline is flagged.

Timing is the best of N calls after an untimed warm-up (``time.perf_counter``): the
best is what the machine can do; other processes on a shared machine only ever add time.
Memory is the tracemalloc peak of one call (Python and NumPy allocations) and the
process's peak resident set size.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import importlib.metadata
import json
import math
import os
import platform
import re
import resource
import sys
import time
import tracemalloc
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, Literal

from rich.table import Table

__all__ = [
    "BLAS_THREAD_VARS",
    "REGRESSION_TOLERANCE",
    "Comparison",
    "Floor",
    "Op",
    "Row",
    "Timing",
    "TopicResult",
    "baseline_document",
    "best_of",
    "best_of_interleaved",
    "collect_floors",
    "compare",
    "comparison_table",
    "floors_table",
    "load_baseline",
    "machine_info",
    "machine_line",
    "max_rss_bytes",
    "regression_summary",
    "regressions",
    "single_threaded_blas",
    "traced_peak_bytes",
    "write_results",
]

REGRESSION_TOLERANCE = 0.10
"""A speed row whose time grew by more than this fraction over its baseline is flagged."""

BLAS_THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""Environment variables that set the BLAS/OpenMP thread count (read when numpy loads)."""

Op = Literal[">=", ">", "<=", "<"]
Kind = Literal["speed", "memory"]

# ---------------------------------------------------------------------------- timing


@dataclasses.dataclass(frozen=True)
class Timing:
    """Wall times of repeated calls [s]; ``best_s`` is their minimum."""

    times_s: tuple[float, ...]

    @property
    def best_s(self) -> float:
        """The fastest call [s]."""
        return min(self.times_s)

    def to_dict(self) -> dict[str, Any]:
        """``{"best_s": ..., "times_s": [...]}``."""
        return {"best_s": self.best_s, "times_s": list(self.times_s)}


def best_of(fn: Callable[[], object], repeats: int, *, warmup: int = 1) -> Timing:
    """Time ``repeats`` calls of ``fn`` after ``warmup`` untimed ones (compilation, caches)."""
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return Timing(tuple(times))


def best_of_interleaved(
    fns: Mapping[str, Callable[[], object]], rounds: int, *, warmup: int = 1
) -> dict[str, Timing]:
    """Like :func:`best_of` for several contestants timed in turn, round after round.

    Interleaving exposes every contestant to the same background load, which keeps
    their ratio honest on a shared machine.
    """
    if rounds < 1:
        raise ValueError(f"rounds must be >= 1, got {rounds}")
    for _ in range(warmup):
        for fn in fns.values():
            fn()
    times: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(rounds):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    return {name: Timing(tuple(ts)) for name, ts in times.items()}


# ---------------------------------------------------------------------------- memory


def traced_peak_bytes(fn: Callable[[], object]) -> int:
    """Peak of the memory traced by tracemalloc (Python and NumPy) during one call [B]."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return int(peak)


def max_rss_bytes() -> int:
    """The process's peak resident set size so far [B] (Linux reports kB, macOS bytes)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss) if sys.platform == "darwin" else int(rss) * 1024


# ------------------------------------------------------------------------- machine


def _cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else ``platform.processor()``)."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8").splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def _version(dist: str) -> str | None:
    """Installed version of a distribution, None when absent."""
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


def machine_info() -> dict[str, Any]:
    """CPU, cores, load, Python and library versions, BLAS thread settings (JSON-able)."""
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        load = None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {
        "date_utc": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "cpu": _cpu_model(),
        "cores_available": cores,
        "cores_total": os.cpu_count(),
        "load_average_1_5_15": load,
        "platform": platform.platform(),
        "python": f"{platform.python_implementation()} {platform.python_version()}",
        "versions": {
            dist: _version(dist)
            for dist in ("firefleet", "numpy", "numba", "scipy", "control", "opencv-python")
        },
        "blas_threads_env": {v: os.environ.get(v) for v in BLAS_THREAD_VARS},
    }


def single_threaded_blas() -> None:
    """Re-execute this script with one BLAS thread unless the caller chose a number.

    OpenBLAS workers woken by one small matrix call busy-wait for a while: on a shared
    two-CPU machine they took a whole CPU and doubled single runs whenever another
    process wanted it. The variables only take effect before numpy loads, hence the
    re-execution; call this first thing in ``main``.
    """
    if os.name != "posix" or any(v in os.environ for v in BLAS_THREAD_VARS):
        return
    env = {**os.environ, **dict.fromkeys(BLAS_THREAD_VARS, "1")}
    os.execve(sys.executable, [sys.executable, *sys.argv], env)


# -------------------------------------------------------------------- rows, floors


_KEY = re.compile(r"^[a-z0-9_]+(\.[a-z0-9_]+)+$")


@dataclasses.dataclass(frozen=True)
class Row:
    """One number a later run is compared with.

    Parameters
    ----------
    key : str
        Stable dotted id, ``"<topic>.<case>.<quantity>"`` in lower case (the baseline is
        matched on it: keep it when the code behind it changes).
    value : float
        The measurement, in ``unit``.
    unit : str
        ``"steps/s"``, ``"s"``, ``"x real time"``, ``"MB"``, ...
    higher_is_better : bool
        True for rates and speed-ups, False for times and memory.
    kind : {"speed", "memory"}
        Only speed rows count in the regression rule; memory rows are shown as ratios.
    label : str
        A human description for tables.
    """

    key: str
    value: float
    unit: str
    higher_is_better: bool = True
    kind: Kind = "speed"
    label: str = ""

    def __post_init__(self) -> None:
        if not _KEY.match(self.key):
            raise ValueError(f"row key must be dotted lower-case words, got {self.key!r}")

    def to_dict(self) -> dict[str, Any]:
        """The row without its key (the key is the results file's dictionary key)."""
        d = dataclasses.asdict(self)
        del d["key"]
        return d


@dataclasses.dataclass(frozen=True)
class Floor:
    """A promise the bench checks: ``measured op bound`` (e.g. ``steps/s >= 3000``)."""

    name: str
    measured: float
    bound: float
    unit: str
    op: Op = ">="
    key: str | None = None
    """The :class:`Row` key the floor is measured on, when there is one."""

    @property
    def passed(self) -> bool:
        """Whether the measurement keeps the promise."""
        m, b = self.measured, self.bound
        return {">=": m >= b, ">": m > b, "<=": m <= b, "<": m < b}[self.op]

    @classmethod
    def on(cls, row: Row, op: Op, bound: float, name: str | None = None) -> Floor:
        """A floor on a row's value (its label names it unless ``name`` is given)."""
        return cls(name or row.label or row.key, row.value, bound, row.unit, op, row.key)

    def to_dict(self) -> dict[str, Any]:
        """JSON-able, with the verdict."""
        return {**dataclasses.asdict(self), "passed": self.passed}


@dataclasses.dataclass(frozen=True)
class TopicResult:
    """What a topic module's ``run(console)`` returns."""

    rows: tuple[Row, ...]
    floors: tuple[Floor, ...] = ()
    details: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    def row(self, key: str) -> Row:
        """The row with this key (KeyError names the keys there are)."""
        for r in self.rows:
            if r.key == key:
                return r
        raise KeyError(f"no row {key!r}; rows: {[r.key for r in self.rows]}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-able: rows by key, floors with verdicts, the details."""
        return {
            "rows": {r.key: r.to_dict() for r in self.rows},
            "floors": [f.to_dict() for f in self.floors],
            "details": dict(self.details),
        }


# -------------------------------------------------------------- results, baseline


def write_results(path: Path, document: Mapping[str, Any]) -> None:
    """Write the results document as indented JSON (non-finite numbers as null)."""

    def finite(x: Any) -> Any:
        if isinstance(x, float) and not math.isfinite(x):
            return None
        if isinstance(x, Mapping):
            return {str(k): finite(v) for k, v in x.items()}
        if isinstance(x, list | tuple):
            return [finite(v) for v in x]
        return x

    path.write_text(json.dumps(finite(document), indent=2) + "\n", encoding="utf-8")


def load_baseline(path: Path) -> dict[str, Row]:
    """The rows of a baseline file (``{"rows": {key: {"value", "unit", ...}}}``) by key."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    return {key: Row(key=key, **fields) for key, fields in doc["rows"].items()}


def baseline_document(
    rows: Iterable[Row], machine: Mapping[str, Any], commit: str | None, note: str = ""
) -> dict[str, Any]:
    """What ``bench/baseline.json`` holds: the commit, the machine, each row's number."""
    return {
        "commit": commit,
        "note": note,
        "machine": dict(machine),
        "rows": {r.key: r.to_dict() for r in rows},
    }


@dataclasses.dataclass(frozen=True)
class Comparison:
    """A row measured now against its baseline."""

    row: Row
    baseline: float

    @property
    def slowdown(self) -> float:
        """How many times worse than the baseline: > 1 slower (or bigger), < 1 faster.

        For a rate (higher is better) ``baseline / measured``; for a time or a size
        ``measured / baseline``.
        """
        now, base = self.row.value, self.baseline
        if self.row.higher_is_better:
            return base / now if now > 0 else float("inf")
        return now / base if base > 0 else float("inf")

    def regressed(self, tolerance: float = REGRESSION_TOLERANCE) -> bool:
        """A speed row more than ``tolerance`` slower than its baseline."""
        return self.row.kind == "speed" and self.slowdown > 1.0 + tolerance


def compare(rows: Iterable[Row], baseline: Mapping[str, Row]) -> list[Comparison]:
    """Every row that has a baseline, in the rows' order."""
    return [Comparison(r, baseline[r.key].value) for r in rows if r.key in baseline]


def regressions(
    comparisons: Iterable[Comparison], tolerance: float = REGRESSION_TOLERANCE
) -> list[Comparison]:
    """The speed rows more than ``tolerance`` slower than their baseline."""
    return [c for c in comparisons if c.regressed(tolerance)]


def collect_floors(
    required: Iterable[tuple[str, Op, float]],
    results: Mapping[str, TopicResult],
    source: str,
) -> list[tuple[str, Floor]]:
    """``(source, floor)`` pairs: the ``required`` floors first, then every topic's own.

    ``required`` holds ``(row key, op, bound)``, checked on the row of that key (a key no
    topic measured is skipped); a topic floor that repeats one of them is not listed twice.
    """
    rows = {r.key: r for res in results.values() for r in res.rows}
    first = [Floor.on(rows[k], op, b) for k, op, b in required if k in rows]
    seen = {(f.key, f.op, f.bound) for f in first}
    return [(source, f) for f in first] + [
        (name, f)
        for name, res in results.items()
        for f in res.floors
        if f.key is None or (f.key, f.op, f.bound) not in seen
    ]


def regression_summary(
    comparisons: list[Comparison], measured: Iterable[str], baseline: Mapping[str, Row]
) -> str:
    """One line: how many speed rows regressed, which, and which rows have no baseline."""
    slow = regressions(comparisons)
    n_speed = sum(c.row.kind == "speed" for c in comparisons)
    text = f"{len(slow)} of {n_speed} speed rows more than {REGRESSION_TOLERANCE:.0%} slower"
    if slow:
        text += f" ({', '.join(c.row.key for c in slow)}: re-run them to tell noise)"
    new = sorted(set(measured) - set(baseline))
    return text + (f"; no baseline for {', '.join(new)}" if new else "") + "."


def machine_line(info: Mapping[str, Any]) -> str:
    """The machine information on one line."""
    versions = ", ".join(f"{k} {v}" for k, v in info["versions"].items() if v)
    return (
        f"{info['cpu']}, {info['cores_available']} of {info['cores_total']} cores, "
        f"load {info['load_average_1_5_15']}, {info['python']}, {versions}, "
        f"BLAS threads {info['blas_threads_env']}"
    )


# ------------------------------------------------------------------------- tables


def _num(x: float) -> str:
    """A number at a readable precision (thousands separators for large ones)."""
    if x != x:
        return "nan"
    if abs(x) >= 100:
        return f"{x:,.0f}"
    if abs(x) >= 1:
        return f"{x:.2f}"
    return f"{x:.3g}"


def floors_table(floors: Iterable[tuple[str, Floor]], title: str) -> Table:
    """A rich table of ``(source, floor)`` pairs with PASS/FAIL."""
    table = Table(title=title)
    for name, justify in (("source", "left"), ("floor", "left"), ("required", "right")):
        table.add_column(name, justify=justify)  # type: ignore[arg-type]
    table.add_column("measured", justify="right")
    table.add_column("verdict", justify="center")
    for source, f in floors:
        table.add_row(
            source,
            f.name,
            f"{f.op} {_num(f.bound)} {f.unit}",
            f"{_num(f.measured)} {f.unit}",
            "[bold green]PASS[/]" if f.passed else "[bold red]FAIL[/]",
        )
    return table


def comparison_table(
    comparisons: Iterable[Comparison], title: str, tolerance: float = REGRESSION_TOLERANCE
) -> Table:
    """A rich table of every row against its baseline, regressions flagged."""
    table = Table(title=title)
    table.add_column("row")
    table.add_column("unit")
    for name in ("baseline", "now", "slowdown"):
        table.add_column(name, justify="right")
    table.add_column("", justify="center")
    for c in comparisons:
        if c.regressed(tolerance):
            flag = f"[bold red]SLOWER > {tolerance:.0%}[/]"
        elif c.row.kind == "memory":
            flag = "memory (info)"
        else:
            flag = "ok"
        table.add_row(
            c.row.key, c.row.unit, _num(c.baseline), _num(c.row.value), f"{c.slowdown:.2f}x", flag
        )
    return table
