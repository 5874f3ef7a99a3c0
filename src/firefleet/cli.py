"""The ``firefleet`` command line (the contract of DESIGN.md).

::

    firefleet list
    firefleet run SCENARIO [--out DIR] [--seed N] [--no-plots]
    firefleet validate FILE...
    firefleet reproduce [--out DIR]
    firefleet slam LOG [--particles P] [--seed N] [--out DIR] [--version {1,2}]
                   [--association {known,unknown}] [--odometry-noise-scale S] [--no-plots]

Bad input (an unknown scenario, a malformed file, a bad value) is one line per problem
on stderr and exit status 2, with nothing written. A run whose claims do not all hold
exits 1.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

import firefleet
from firefleet.errors import InputError
from firefleet.outputs import json_text, staged_dir
from firefleet.scenarios.registry import builtin_names, load_scenario
from firefleet.scenarios.schema import Scenario, read_scenario_file
from firefleet.sim.engine import ProgressCallback, simulate
from firefleet.sim.metrics import compute_metrics, metrics_document

__all__ = ["main"]

EXIT_OK, EXIT_CLAIM_FAILED, EXIT_BAD_INPUT = 0, 1, 2


@contextmanager
def _progress_bar(console: Console, label: str) -> Iterator[ProgressCallback]:
    columns = (TextColumn("{task.description}"), BarColumn(), TimeRemainingColumn())
    if not console.is_terminal:  # a log file gets no bar (and no blank lines from one)
        yield lambda done, total: None
        return
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        yield update


def _run_into(
    scenario: Scenario, folder: Path, *, plots: bool, err: Console
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """Run a scenario and write its outputs into ``folder``; returns (metrics doc, figures)."""
    with _progress_bar(err, scenario.name) as progress:
        result = simulate(scenario, progress=progress)
    metrics = compute_metrics(result)
    document = metrics_document(scenario.name, scenario.claims, metrics)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "metrics.json").write_text(json_text(document), encoding="utf-8")
    (folder / "result.npz").write_bytes(result.to_npz_bytes())
    names: tuple[str, ...] = ()
    if plots:
        from firefleet.report.plots import figures  # matplotlib only when plotting

        pngs = figures(result, metrics)
        for name, data in pngs.items():
            (folder / name).write_bytes(data)
        names = tuple(pngs)
    return document, names


def _claims_table(document: dict[str, Any]) -> Table:
    table = Table(title=f"{document['scenario']}: metrics and claims")
    table.add_column("metric")
    table.add_column("measured", justify="right")
    table.add_column("claim")
    table.add_column("result")
    by_name = {c["name"]: c for c in document["claims"]}
    for key, value in document.items():
        if key in ("scenario", "claims"):
            continue
        claim = by_name.get(key)
        shown = "n/a" if value is None else f"{value:.6g}"
        verdict = "" if claim is None else ("[green]passed" if claim["passed"] else "[red]FAILED")
        table.add_row(key, shown, "" if claim is None else claim["expected"], verdict)
    return table


def _all_passed(document: dict[str, Any]) -> bool:
    return all(c["passed"] for c in document["claims"])


def _cmd_list(args: argparse.Namespace, out: Console, err: Console) -> int:
    table = Table(title="built-in scenarios")
    table.add_column("name")
    table.add_column("reproduces")
    table.add_column("title")
    for name in builtin_names():
        scn = load_scenario(name)
        table.add_row(name, scn.reproduces or "-", scn.title)
    out.print(table)
    return EXIT_OK


def _cmd_run(args: argparse.Namespace, out: Console, err: Console) -> int:
    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        if args.seed < 0:
            raise InputError(f"--seed must be >= 0, got {args.seed}")
        scenario = dataclasses.replace(scenario, seed=args.seed)
    dest = Path(args.out) if args.out else Path("runs") / scenario.name
    with staged_dir(dest) as stage:
        document, _ = _run_into(scenario, stage, plots=not args.no_plots, err=err)
    out.print(_claims_table(document))
    out.print(f"wrote {dest}/")
    return EXIT_OK if _all_passed(document) else EXIT_CLAIM_FAILED


def _cmd_validate(args: argparse.Namespace, out: Console, err: Console) -> int:
    status = EXIT_OK
    for path in args.files:
        try:
            scn = read_scenario_file(path)
        except InputError as exc:
            for line in str(exc).splitlines():
                err.print(line, markup=False, highlight=False)
            status = EXIT_BAD_INPUT
        else:
            out.print(
                f"{path}: ok ({scn.name}, {scn.n_robots} robot(s), {scn.n_steps} steps)",
                markup=False,
                highlight=False,
            )
    return status


def _cmd_reproduce(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.report.html import ReportEntry, render_index

    scenarios = [s for s in (load_scenario(n) for n in builtin_names()) if s.reproduces]
    scenarios.sort(key=lambda s: _figure_number(s.reproduces))
    dest = Path(args.out)
    entries: list[ReportEntry] = []
    with staged_dir(dest) as stage:
        for scn in scenarios:
            document, figs = _run_into(scn, stage / scn.name, plots=True, err=err)
            entries.append(
                ReportEntry(
                    name=scn.name,
                    title=scn.title,
                    reproduces=scn.reproduces,
                    deliverable_says=scn.deliverable_says,
                    folder=scn.name,
                    figures=figs,
                    document=document,
                )
            )
            mark = "[green]ok" if _all_passed(document) else "[red]CLAIM FAILED"
            out.print(f"{scn.reproduces:>10}  {scn.name:<24} {mark}")
        index = render_index(entries, version=firefleet.__version__)
        (stage / "index.html").write_text(index, encoding="utf-8")
    total = sum(len(e.document["claims"]) for e in entries)
    passed = sum(c["passed"] for e in entries for c in e.document["claims"])
    out.print(f"{passed} of {total} claims passed")
    out.print(f"report: {(dest / 'index.html').resolve()}", markup=False, highlight=False)
    return EXIT_OK if passed == total else EXIT_CLAIM_FAILED


# --- slam (issue 7): FastSLAM on a log ------------------------------------------------


def _cmd_slam(args: argparse.Namespace, out: Console, err: Console) -> int:
    import numpy as np

    from firefleet.estimation.fastslam import (
        FastSlamParams,
        landmarks_csv,
        run_fastslam,
        slam_summary,
        trajectory_csv,
    )
    from firefleet.estimation.logs import format_log
    from firefleet.sim.world import SIM_LOOP, load_or_simulate_log

    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    params = FastSlamParams(
        n_particles=args.particles,
        version=args.version,
        association=args.association,
        odometry_noise_scale=args.odometry_noise_scale,
    )
    log = load_or_simulate_log(args.log, seed=args.seed)
    dest = Path(args.out) if args.out else Path("runs") / f"slam-{Path(args.log).stem}"
    with _progress_bar(err, f"FastSLAM {args.version}.0 over {log.n_poses} poses") as progress:
        result = run_fastslam(
            log,
            np.random.default_rng(args.seed),
            params=params,
            n_snapshots=0 if args.no_plots else 60,
            progress=progress,
        )
    summary = slam_summary(log, result)
    with staged_dir(dest) as stage:
        (stage / "trajectory.csv").write_text(trajectory_csv(log, result), encoding="utf-8")
        (stage / "landmarks.csv").write_text(landmarks_csv(result), encoding="utf-8")
        (stage / "summary.json").write_text(json_text(summary), encoding="utf-8")
        if args.log == SIM_LOOP:
            (stage / "log.txt").write_text(format_log(log), encoding="utf-8")
        if not args.no_plots:
            from firefleet.report.slam import slam_animation_gif, slam_figure_png

            (stage / "slam.png").write_bytes(slam_figure_png(log, result))
            (stage / "slam.gif").write_bytes(slam_animation_gif(log, result))
    table = Table(title=f"FastSLAM {args.version}.0 on {log.name}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("claim")
    table.add_column("result")
    by_name = {c["name"]: c for c in summary["claims"]}
    for key, value in summary.items():
        if key == "claims":
            continue
        claim = by_name.get(key)
        shown = f"{value:.6g}" if isinstance(value, float) else str(value)
        verdict = "" if claim is None else ("[green]passed" if claim["passed"] else "[red]FAILED")
        table.add_row(key, shown, "" if claim is None else claim["expected"], verdict)
    out.print(table)
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    return EXIT_OK if _all_passed(summary) else EXIT_CLAIM_FAILED


def _add_slam_parser(sub: Any) -> None:
    slam = sub.add_parser(
        "slam", help="run FastSLAM on a log (Victoria Park / GTSAM text, firefleet's own)"
    )
    slam.add_argument(
        "log", metavar="LOG", help="log file, or 'sim-loop' to simulate the 100 m loop"
    )
    slam.add_argument("--particles", type=int, default=100, metavar="P", help="default 100")
    slam.add_argument("--seed", type=int, default=0, metavar="N", help="random seed (default 0)")
    slam.add_argument("--out", metavar="DIR", help="output folder (default: runs/slam-LOG)")
    slam.add_argument("--version", type=int, choices=(1, 2), default=2, help="FastSLAM 1.0 or 2.0")
    slam.add_argument("--association", choices=("known", "unknown"), default="known")
    slam.add_argument(
        "--odometry-noise-scale",
        type=float,
        default=1.0,
        metavar="S",
        help="factor on the log's odometry standard deviations (Victoria Park: 4)",
    )
    slam.add_argument("--no-plots", action="store_true", help="skip slam.png and slam.gif")


# --- end slam ---------------------------------------------------------------------------


def _figure_number(label: str) -> tuple[int, str]:
    digits = "".join(c if c.isdigit() else " " for c in label).split()
    return (int(digits[0]) if digits else 10**6, label)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="firefleet",
        description="Teams of intelligent mobile robots for firefighting: simulate, "
        "check, and reproduce the deliverable's experiments.",
    )
    parser.add_argument("--version", action="version", version=f"firefleet {firefleet.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    sub.add_parser("list", help="list the built-in scenarios")
    run = sub.add_parser("run", help="run a scenario and write its metrics, arrays and plots")
    run.add_argument("scenario", metavar="SCENARIO", help="built-in name or a YAML path")
    run.add_argument("--out", metavar="DIR", help="output folder (default: runs/SCENARIO)")
    run.add_argument("--seed", type=int, metavar="N", help="override the scenario's seed")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    validate = sub.add_parser("validate", help="check scenario files, naming each error")
    validate.add_argument("files", nargs="+", metavar="FILE")
    reproduce = sub.add_parser("reproduce", help="run every experiment of the deliverable")
    reproduce.add_argument("--out", metavar="DIR", default="firefleet-report", help="report folder")
    _add_slam_parser(sub)
    return parser


_COMMANDS = {
    "list": _cmd_list,
    "run": _cmd_run,
    "validate": _cmd_validate,
    "reproduce": _cmd_reproduce,
    "slam": _cmd_slam,
}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``firefleet`` command; returns the exit status."""
    args = _parser().parse_args(argv)
    out = Console(soft_wrap=True)
    err = Console(stderr=True, soft_wrap=True)
    try:
        return _COMMANDS[args.command](args, out, err)
    except InputError as exc:
        for line in str(exc).splitlines():
            err.print(f"firefleet: error: {line}", markup=False, highlight=False)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        err.print("firefleet: interrupted; nothing written")
        return 130


if __name__ == "__main__":
    sys.exit(main())
