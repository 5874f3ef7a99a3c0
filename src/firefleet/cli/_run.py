"""``firefleet list | run | validate | reproduce``: the scenarios and the report."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import os
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

from rich.console import Console
from rich.markup import escape

import firefleet
from firefleet.cli._console import (
    EXIT_BAD_INPUT,
    EXIT_CLAIM_FAILED,
    EXIT_OK,
    all_passed,
    metrics_table,
    progress_bar,
)
from firefleet.cli._serve import (
    add_run_flags,
    dashboard_screenshot,
    live_mode,
    mcap_of,
    mcap_wanted,
)
from firefleet.errors import InputError
from firefleet.outputs import json_text, run_record, staged_dir
from firefleet.scenarios.registry import builtin_names, load_scenario
from firefleet.scenarios.schema import Scenario, read_scenario_file
from firefleet.sim.engine import simulate
from firefleet.sim.metrics import compute_metrics, metrics_document
from firefleet.sim.registry import task_kind

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``list``, ``run``, ``validate`` and ``reproduce`` to the subcommands ``sub``."""
    sub.add_parser("list", help="list the built-in scenarios").set_defaults(handler=cmd_list)
    run = sub.add_parser("run", help="run a scenario and write its metrics, arrays and plots")
    run.add_argument("scenario", metavar="SCENARIO", help="built-in name or a YAML path")
    run.add_argument("--out", metavar="DIR", help="output folder (default: runs/SCENARIO)")
    run.add_argument(
        "--seed", type=int, metavar="N", help="random seed (default: the scenario's own)"
    )
    run.add_argument(
        "--no-plots", action="store_true", help="skip the PNG figures (default: draw them)"
    )
    add_run_flags(run)
    run.set_defaults(handler=cmd_run)
    validate = sub.add_parser("validate", help="check scenario files, naming each error")
    validate.add_argument("files", nargs="+", metavar="FILE")
    validate.set_defaults(handler=cmd_validate)
    reproduce = sub.add_parser("reproduce", help="run every experiment of the deliverable")
    reproduce.add_argument(
        "--out",
        metavar="DIR",
        default="firefleet-report",
        help="report folder (default firefleet-report)",
    )
    reproduce.add_argument(
        "--data",
        metavar="DIR",
        help="real data for section 2.7 (thermal/*.npy, slam/victoria_park.txt) "
        "(default: $FIREFLEET_DATA, else ../shared/data beside a checkout)",
    )
    reproduce.add_argument(
        "--seeds",
        metavar="A:B",
        help="also run every experiment with seeds A to B-1 (on Dask, as `firefleet sweep`) "
        "and report each claim's pass rate over them",
    )
    reproduce.add_argument(
        "--workers",
        type=int,
        default=1,
        metavar="N",
        help="run the experiments in N processes at once (default 1: one after another; "
        "the report is the same)",
    )
    reproduce.set_defaults(handler=cmd_reproduce)


def run_into(
    scenario: Scenario,
    folder: Path,
    *,
    plots: bool,
    err: Console,
    command_line: Sequence[str],
    mcap: bool | None = False,
    simulator: Any = None,
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """Run a scenario and write its outputs into ``folder``; returns (metrics doc, figures).

    ``metrics.json`` also names what made the run (``provenance``: firefleet's version,
    the git commit, the seed and ``command_line``); the returned document does not.
    ``mcap``: also write ``run.mcap`` (``None``: when it is small, :func:`mcap_wanted`);
    ``simulator``: runs the scenario instead of
    :func:`simulate` (``simulator(scenario, progress)``, the live mode).
    """
    with progress_bar(err, scenario.name) as progress:
        result = (simulator or simulate)(scenario, progress=progress)
    metrics = compute_metrics(result)
    document = metrics_document(scenario.name, scenario.claims, metrics)
    folder.mkdir(parents=True, exist_ok=True)
    provenance = run_record(command_line, seed=scenario.seed)
    written = {"scenario": document["scenario"], "provenance": provenance, **document}
    (folder / "metrics.json").write_text(json_text(written), encoding="utf-8")
    (folder / "result.npz").write_bytes(result.to_npz_bytes())
    if mcap_wanted(mcap, result.t.shape[0], result.pose.shape[1]):
        (folder / "run.mcap").write_bytes(mcap_of(result, written))
    names: tuple[str, ...] = ()
    if plots:
        from firefleet.report.plots import figures  # matplotlib only when plotting

        pngs = figures(result, metrics)
        for name, data in pngs.items():
            (folder / name).write_bytes(data)
        names = tuple(pngs)
    return document, names


def cmd_list(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet list``: one line per built-in scenario, cut to the console's width."""
    scenarios = [load_scenario(name) for name in builtin_names()]
    width = max(len(s.name) for s in scenarios)
    for scn in scenarios:
        line = f"{scn.name:<{width}}  {scn.reproduces or '-'}: {scn.title}"
        if len(line) > out.width:
            line = line[: out.width - 1] + "\N{HORIZONTAL ELLIPSIS}"
        out.print(line, markup=False, highlight=False, soft_wrap=True)
    return EXIT_OK


def cmd_run(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet run SCENARIO``."""
    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        if args.seed < 0:
            raise InputError(f"--seed must be >= 0, got {args.seed}")
        scenario = dataclasses.replace(scenario, seed=args.seed)
    dest = Path(args.out) if args.out else Path("runs") / scenario.name
    record = run_record(args.command_line, seed=scenario.seed)
    with live_mode(args, out) as simulator, staged_dir(dest, record=record) as stage:
        document, _ = run_into(
            scenario,
            stage,
            plots=not args.no_plots,
            err=err,
            command_line=args.command_line,
            mcap=args.mcap,
            simulator=simulator,
        )
    items = dict(task_kind(scenario.command.kind).list_items)
    out.print(metrics_table(document, items))
    out.print(f"wrote {dest}/")
    return EXIT_OK if all_passed(document) else EXIT_CLAIM_FAILED


def cmd_validate(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet validate FILE...``."""
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


def cmd_reproduce(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet reproduce``."""
    from firefleet.report.html import ReportEntry, render_index

    if args.workers < 1:
        raise InputError(f"--workers must be at least 1, got {args.workers}")
    scenarios = [s for s in (load_scenario(n) for n in builtin_names()) if s.reproduces]
    scenarios.sort(key=lambda s: _figure_number(s.reproduces))
    seeds = None
    if args.seeds is not None:
        from firefleet.sweep import parse_seeds

        seeds = parse_seeds(args.seeds)
    data = _data_dir(args)
    dest = Path(args.out)
    entries: list[ReportEntry] = []
    record = run_record(args.command_line, seed=None)
    with staged_dir(dest, record=record) as stage, _jobs(args.workers, err) as jobs:

        def submit(scn: Any) -> Callable[[], Any]:
            return jobs(_scenario_job, scn.name, stage / scn.name, tuple(args.command_line))

        # the missions and the link study take minutes each: started first
        missions = [s for s in scenarios if s.command.kind == "mission"]
        runs = {s.name: submit(s) for s in missions}
        link = jobs(_link_job)
        runs |= {s.name: submit(s) for s in scenarios if s.name not in runs}
        section_27 = jobs(_section_27_job, data)
        for scn in scenarios:
            document, figs = runs[scn.name]()
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
            mark = "[green]ok" if all_passed(document) else "[red]CLAIM FAILED"
            out.print(f"{scn.name:<24} {mark}  {escape(scn.reproduces)}")
        if seeds is not None:
            from firefleet.cli._sweep import seed_pass_rates

            entries = seed_pass_rates(entries, scenarios, seeds, args.seeds, stage, out, err)
        runs_27, missing = section_27()
        for run in runs_27:
            entries.append(_write_report_run(stage, run, out))
        entries.append(_write_report_run(stage, link(), out))
        footer = report_footer(record, {s.name: s.seed for s in scenarios})
        (stage / "dashboard.png").write_bytes(dashboard_screenshot())
        index = render_index(
            entries,
            version=firefleet.__version__,
            footer=footer,
            missing=missing,
            dashboard="dashboard.png",
        )
        (stage / "index.html").write_text(index, encoding="utf-8")
    total = sum(len(e.document["claims"]) for e in entries)
    passed = sum(c["passed"] for e in entries for c in e.document["claims"])
    out.print(f"{passed} of {total} claims passed")
    out.print(f"report: {(dest / 'index.html').resolve()}", markup=False, highlight=False)
    return EXIT_OK if passed == total else EXIT_CLAIM_FAILED


_T = TypeVar("_T")


@contextlib.contextmanager
def _jobs(workers: int, err: Console) -> Iterator[Callable[..., Callable[[], Any]]]:
    """``submit(job, *args)`` -> a function that returns ``job(err, *args)``'s value.

    One worker: the job runs when its value is asked for, here, with its progress on
    ``err``. More: jobs start at once in that many processes ("spawn": numba's OpenMP
    layer does not survive a fork), each job's progress as plain lines on stderr; a
    job's warnings are warned again here (under this process's filters) and its
    exception raised here when its value is asked for.
    """
    if workers == 1:
        yield lambda job, *args: functools.partial(job, err, *args)
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:

        def submit(job: Callable[..., Any], *args: Any) -> Callable[[], Any]:
            future = pool.submit(_in_worker, job, *args)

            def value() -> Any:
                result, caught = future.result()
                for message, category, filename, lineno in caught:
                    warnings.warn_explicit(message, category, filename, lineno)
                return result

            return value

        try:
            yield submit
        except BaseException:
            pool.shutdown(wait=True, cancel_futures=True)
            raise


def _in_worker(
    job: Callable[..., _T], *args: Any
) -> tuple[_T, list[tuple[str, type[Warning], str, int]]]:
    """``job(err, *args)`` in a worker process, and the warnings it gave (once each)."""
    err = Console(stderr=True, force_terminal=False)  # two bars would garble a terminal
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = job(err, *args)
    seen = dict.fromkeys((str(w.message), w.category, w.filename, w.lineno) for w in caught)
    return result, list(seen)


def _scenario_job(
    err: Console, name: str, folder: Path, command_line: tuple[str, ...]
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """A built-in scenario run into ``folder`` with its figures (``run_into``)."""
    return run_into(load_scenario(name), folder, plots=True, err=err, command_line=command_line)


def _section_27_job(err: Console, data: Path | None) -> tuple[list[Any], str]:
    """Section 2.7's runs and what was left out (:func:`_section_27`)."""
    return _section_27(data, err)


def _link_job(err: Console) -> Any:
    """Section 2.5's study (cooperation over an imperfect link) as a report run."""
    from firefleet.report.network import link_study_run

    with progress_bar(err, "section 2.5: the link study") as progress:
        return link_study_run(progress=progress)


def _data_dir(args: argparse.Namespace) -> Path | None:
    """Where section 2.7's real data is: ``--data``, ``$FIREFLEET_DATA``, or the shared
    data set beside a checkout (``<repo>/../shared/data``); None if none exists."""
    if args.data is not None:
        given = Path(args.data)
        if not given.is_dir():
            raise InputError(f"--data {given}: no such folder")
        return given
    env = os.environ.get("FIREFLEET_DATA")
    if env:
        return Path(env) if Path(env).is_dir() else None
    beside = Path(__file__).resolve().parents[3].parent / "shared" / "data"
    return beside if beside.is_dir() else None


def _thermal_frames(data: Path | None) -> dict[str, Any]:
    """The known-answer FLIR frames: from the data folder, else the checkout's tests/data."""
    import numpy as np

    from firefleet.report.sensing import KNOWN_FRAMES

    frames: dict[str, Any] = {}
    for name in KNOWN_FRAMES:
        npy = data / "thermal" / f"{name}.npy" if data is not None else None
        npz = Path(__file__).resolve().parents[3] / "tests" / "data" / "thermal" / f"{name}.npz"
        if npy is not None and npy.is_file():
            frames[name] = np.load(npy)
        elif npz.is_file():
            with np.load(npz) as archive:
                frames[name] = archive["celsius"]
    return frames


def _section_27(data: Path | None, err: Console) -> tuple[list[Any], str]:
    """Section 2.7's runs (thermal, stereo, SLAM) from the data folder ``data``; what was
    left out (a sentence for the report, or "")."""
    from firefleet.report.html import ReportRun
    from firefleet.report.sensing import stereo_runs, thermal_run
    from firefleet.report.slam import slam_report_runs

    frames = _thermal_frames(data)
    park = data / "slam" / "victoria_park.txt" if data is not None else None
    park = park if park is not None and park.is_file() else None
    missing = []
    if not frames:
        missing.append("the real FLIR frames (thermal/*.npy)")
    if park is None:
        missing.append("Victoria Park (slam/victoria_park.txt)")
    runs: list[ReportRun] = []
    with progress_bar(err, "section 2.7: thermal, stereo, SLAM") as progress:
        progress(0, 3)
        runs.append(thermal_run(frames))
        progress(1, 3)
        runs += stereo_runs()
        progress(2, 3)
        runs += slam_report_runs(park)
        progress(3, 3)
    if park is not None and not any(r.name == "slam-victoria-park" for r in runs):
        missing.append("Victoria Park's GTSAM reference (the gtsam package is not installed)")
    if not missing:
        return runs, ""
    return runs, (
        "Not in this report, its data not found (give --data DIR or set FIREFLEET_DATA): "
        + "; ".join(missing)
        + "."
    )


def _write_report_run(stage: Path, run: Any, out: Console) -> Any:
    """A report run's files and ``metrics.json`` into its folder; its report entry."""
    from firefleet.report.html import ReportEntry

    folder = stage / run.name
    folder.mkdir()
    for name, data_bytes in run.files.items():
        (folder / name).write_bytes(data_bytes)
    (folder / "metrics.json").write_text(json_text(run.document), encoding="utf-8")
    mark = "[green]ok" if all_passed(run.document) else "[red]CLAIM FAILED"
    out.print(f"{run.name:<24} {mark}  {escape(run.reproduces)}")
    return ReportEntry(
        name=run.name,
        title=run.title,
        reproduces=run.reproduces,
        deliverable_says=run.deliverable_says,
        folder=run.name,
        figures=run.figures,
        document=run.document,
        command=run.command,
        links=("metrics.json",),
        captions=run.captions,
    )


def report_footer(record: Mapping[str, Any], seeds: Mapping[str, int]) -> str:
    """The report footer's provenance: the git commit, the command line and the seeds."""
    parts = []
    if record.get("git_commit"):
        parts.append(f"Commit {record['git_commit']}.")
    parts.append(f"Made by: {record['command']}.")
    if seeds:
        parts.append("Seeds: " + ", ".join(f"{name} {seed}" for name, seed in seeds.items()) + ".")
    return " ".join(parts)


def _figure_number(label: str) -> tuple[int, str]:
    digits = "".join(c if c.isdigit() else " " for c in label).split()
    return (int(digits[0]) if digits else 10**6, label)
