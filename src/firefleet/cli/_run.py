"""``firefleet list | run | validate | reproduce``: the scenarios and the report."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

import firefleet
from firefleet.cli._console import (
    EXIT_BAD_INPUT,
    EXIT_CLAIM_FAILED,
    EXIT_OK,
    all_passed,
    claims_table,
    progress_bar,
)
from firefleet.errors import InputError
from firefleet.outputs import json_text, staged_dir
from firefleet.scenarios.registry import builtin_names, load_scenario
from firefleet.scenarios.schema import Scenario, read_scenario_file
from firefleet.sim.engine import simulate
from firefleet.sim.metrics import compute_metrics, metrics_document

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``list``, ``run``, ``validate`` and ``reproduce`` to the subcommands ``sub``."""
    sub.add_parser("list", help="list the built-in scenarios").set_defaults(handler=cmd_list)
    run = sub.add_parser("run", help="run a scenario and write its metrics, arrays and plots")
    run.add_argument("scenario", metavar="SCENARIO", help="built-in name or a YAML path")
    run.add_argument("--out", metavar="DIR", help="output folder (default: runs/SCENARIO)")
    run.add_argument("--seed", type=int, metavar="N", help="override the scenario's seed")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    run.set_defaults(handler=cmd_run)
    validate = sub.add_parser("validate", help="check scenario files, naming each error")
    validate.add_argument("files", nargs="+", metavar="FILE")
    validate.set_defaults(handler=cmd_validate)
    reproduce = sub.add_parser("reproduce", help="run every experiment of the deliverable")
    reproduce.add_argument("--out", metavar="DIR", default="firefleet-report", help="report folder")
    reproduce.set_defaults(handler=cmd_reproduce)


def run_into(
    scenario: Scenario, folder: Path, *, plots: bool, err: Console
) -> tuple[dict[str, Any], tuple[str, ...]]:
    """Run a scenario and write its outputs into ``folder``; returns (metrics doc, figures)."""
    with progress_bar(err, scenario.name) as progress:
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


def metrics_table(document: dict[str, Any]) -> Table:
    """The claims table of a ``metrics.json`` document."""
    values = [(k, v) for k, v in document.items() if k not in ("scenario", "claims")]
    return claims_table(f"{document['scenario']}: metrics and claims", values, document["claims"])


def cmd_list(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet list``."""
    table = Table(title="built-in scenarios")
    table.add_column("name")
    table.add_column("reproduces")
    table.add_column("title")
    for name in builtin_names():
        scn = load_scenario(name)
        table.add_row(name, scn.reproduces or "-", scn.title)
    out.print(table)
    return EXIT_OK


def cmd_run(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet run SCENARIO``."""
    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        if args.seed < 0:
            raise InputError(f"--seed must be >= 0, got {args.seed}")
        scenario = dataclasses.replace(scenario, seed=args.seed)
    dest = Path(args.out) if args.out else Path("runs") / scenario.name
    with staged_dir(dest) as stage:
        document, _ = run_into(scenario, stage, plots=not args.no_plots, err=err)
    out.print(metrics_table(document))
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

    scenarios = [s for s in (load_scenario(n) for n in builtin_names()) if s.reproduces]
    scenarios.sort(key=lambda s: _figure_number(s.reproduces))
    dest = Path(args.out)
    entries: list[ReportEntry] = []
    with staged_dir(dest) as stage:
        for scn in scenarios:
            document, figs = run_into(scn, stage / scn.name, plots=True, err=err)
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
        index = render_index(entries, version=firefleet.__version__)
        (stage / "index.html").write_text(index, encoding="utf-8")
    total = sum(len(e.document["claims"]) for e in entries)
    passed = sum(c["passed"] for e in entries for c in e.document["claims"])
    out.print(f"{passed} of {total} claims passed")
    out.print(f"report: {(dest / 'index.html').resolve()}", markup=False, highlight=False)
    return EXIT_OK if passed == total else EXIT_CLAIM_FAILED


def _figure_number(label: str) -> tuple[int, str]:
    digits = "".join(c if c.isdigit() else " " for c in label).split()
    return (int(digits[0]) if digits else 10**6, label)
