"""``make bench``: run every topic's benchmark, check the floors, compare with the baseline.

Each ``bench/<topic>.py`` exposes ``run(console)``, prints its own tables and returns
its rows, floors and details (``_harness.TopicResult``; ``_topics`` reads the topics that
still return a dict). This driver then prints one table of floors (issue 12's five
first, then every topic's own), writes the results file (default ``bench/results.json``)
and prints every row against ``bench/baseline.json``, flagging a speed row more than
10 % slower. The exit status is 0 whatever the floors say (this is a measurement), 1
when a topic failed to run (the others still run and are written).

    python bench/run.py [--only motor,fuzzy] [--out FILE] [--baseline FILE]
                        [--write-baseline FILE]
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import time
from pathlib import Path

from rich.console import Console

import _harness as h
from _topics import topic_result

HERE = Path(__file__).resolve().parent
TOPICS = (
    "motor",
    "path_following",
    "fuzzy",
    "formation",
    "thermal",
    "ranging",
    "stereo",
    "slam",
    "sweep",
    "net",
    "link",
    "gridslam",
    "net",
    "link",
    "navigation",
    "robot",
    "mission",
)
ISSUE_12: tuple[tuple[str, h.Op, float], ...] = (
    ("motor.single.speedup_vs_python_control", ">=", 100.0),
    ("motor.team.n10000.steps_per_s", ">=", 3_000.0),
    ("path_following.coop_different_paths.x_real_time", ">=", 10_000.0),
    ("path_following.robots1000.x_real_time", ">=", 50.0),
    ("fuzzy.single.evals_per_s", ">=", 300_000.0),
)
"""The speed floors of issue 12: (row key, comparison, bound)."""


def git_commit() -> str | None:
    """The repository's short commit hash (None outside a git checkout)."""
    cmd = ["git", "-C", str(HERE), "rev-parse", "--short", "HEAD"]
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    return done.stdout.strip() or None


def main(argv: list[str] | None = None) -> int:
    """Run the topics, print the floors and the regression check, write the results."""
    h.single_threaded_blas()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=",".join(TOPICS), help="comma-separated topics")
    ap.add_argument("--out", type=Path, default=HERE / "results.json")
    ap.add_argument("--baseline", type=Path, default=HERE / "baseline.json")
    ap.add_argument("--write-baseline", type=Path, help="also write this run's rows there")
    args = ap.parse_args(argv)
    topics = [t for t in args.only.split(",") if t]
    unknown = sorted(set(topics) - set(TOPICS))
    if unknown:
        ap.error(f"--only: unknown topic(s) {unknown}; expected some of {list(TOPICS)}")

    console = Console(width=None if sys.stdout.isatty() else 130)
    start = time.perf_counter()
    machine, commit = h.machine_info(), git_commit()
    console.print(f"[bold]firefleet bench[/] at {commit}: {h.machine_line(machine)}")
    results: dict[str, h.TopicResult] = {}
    failed: dict[str, str] = {}
    for name in topics:
        console.rule(f"bench/{name}.py")
        try:  # one broken topic must not lose the others' numbers
            results[name] = topic_result(name, importlib.import_module(name).run(console))
        except Exception as exc:  # reported below and in the exit status
            failed[name] = f"{type(exc).__name__}: {exc}"
            console.print_exception()

    rows = {r.key: r for res in results.values() for r in res.rows}
    floors = h.collect_floors(ISSUE_12, results, "issue 12")
    console.rule("summary")
    console.print(h.floors_table(floors, "Floors (a measurement: the exit status is 0 either way)"))
    comparisons: list[h.Comparison] = []
    if args.baseline.exists():
        base = h.load_baseline(args.baseline)
        comparisons = h.compare(rows.values(), base)
        title = f"Rows against {args.baseline.name} (slowdown > 1: slower or bigger than then)"
        console.print(h.comparison_table(comparisons, title))
        console.print(h.regression_summary(comparisons, rows, base))
    for name, why in failed.items():
        console.print(f"[bold red]bench/{name}.py failed[/]: {why} (no rows, no floors)")
    total = time.perf_counter() - start
    document = {
        "commit": commit,
        "machine": machine,
        "load_average_at_end": h.machine_info()["load_average_1_5_15"],
        "bench_wall_time_s": total,
        "process_max_rss_mb": h.max_rss_bytes() / 1e6,
        "floors": [{"source": s, **f.to_dict()} for s, f in floors],
        "regressions": [c.row.key for c in h.regressions(comparisons)],
        "slowdown_vs_baseline": {c.row.key: c.slowdown for c in comparisons},
        "topics": {name: res.to_dict() for name, res in results.items()},
        "failed_topics": failed,
    }
    h.write_results(args.out, document)
    if args.write_baseline:
        h.write_results(args.write_baseline, h.baseline_document(rows.values(), machine, commit))
    console.print(f"wrote {args.out} (bench took {total:.1f} s)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
