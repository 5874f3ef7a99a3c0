"""``firefleet fis``: show, plot or evaluate a MATLAB .fis (Sugeno) controller."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.table import Table

from firefleet.cli._console import EXIT_OK, progress_bar
from firefleet.errors import InputError
from firefleet.outputs import run_record, staged_dir, write_text_atomic

if TYPE_CHECKING:
    from firefleet.control.fuzzy import (
        FuzzyInput,
        FuzzyOutput,
        MembershipFunction,
        SugenoOutputMf,
        SugenoSystem,
    )

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``fis`` to the subcommands ``sub``."""
    fis = sub.add_parser(
        "fis", help="show a MATLAB .fis (Sugeno) controller and plot it, or evaluate it on a CSV"
    )
    fis.add_argument("file", metavar="FILE", help="a MATLAB Fuzzy Logic Toolbox .fis file")
    fis.add_argument(
        "--out", metavar="DIR", help="figure folder (default runs/FILE-stem); with --eval, OUT.csv"
    )
    fis.add_argument("--eval", metavar="IN.csv", help="evaluate on a CSV, one column per input")
    fis.add_argument(
        "--fix",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="hold an input at VALUE on the surfaces (default: mid-range); repeatable",
    )
    fis.set_defaults(handler=_cmd_fis)


def _fis_fixed(pairs: Sequence[str]) -> dict[str, float]:
    fixed: dict[str, float] = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        try:
            fixed[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if not sep or not name.strip():
            raise InputError(f"--fix {pair}: expected NAME=VALUE with a number")
    return fixed


def _read_csv_text(path: str) -> str:
    """The text of ``--eval`` (a BOM from a spreadsheet dropped); InputError otherwise."""
    src = Path(path)
    try:
        return src.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"--eval {src}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"--eval {src}: is a folder, not a CSV file") from None
    except UnicodeDecodeError:
        raise InputError(f"--eval {src}: not UTF-8 text (a CSV file is expected)") from None
    except OSError as exc:
        raise InputError(f"--eval {src}: cannot read: {exc.strerror}") from None


def _cmd_fis(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.control import fuzzy  # scipy.special only when needed

    system = fuzzy.read_fis(args.file)
    fixed = _fis_fixed(args.fix)
    if args.eval is not None:
        if args.out is None:
            raise InputError("--eval IN.csv needs --out OUT.csv")
        if fixed:
            raise InputError("--fix applies to the plots, not to --eval")
        dest_csv = Path(args.out)
        if dest_csv.is_dir():
            raise InputError(f"--out {dest_csv}: is a folder; --eval writes one CSV file there")
        table = fuzzy.evaluate_csv(system, _read_csv_text(args.eval), origin=args.eval)
        write_text_atomic(dest_csv, table)
        rows = table.count("\n") - 1
        out.print(f"wrote {args.out} ({rows} rows)", markup=False, highlight=False)
        return EXIT_OK
    from firefleet.report.fuzzy import figures

    with progress_bar(err, "plots") as progress:
        progress(0, 1)
        pngs = figures(system, fixed=fixed)
        progress(1, 1)
    dest = Path(args.out) if args.out else Path("runs") / Path(args.file).stem
    with staged_dir(dest, record=run_record(args.command_line, seed=None)) as stage:
        for name, data in pngs.items():
            (stage / name).write_bytes(data)
    for shown in _fis_tables(system):
        out.print(shown)
    out.print(f"wrote {len(pngs)} figures to {dest}/", markup=False, highlight=False)
    return EXIT_OK


def _fis_tables(system: SugenoSystem) -> list[Table]:
    summary = Table(
        title=f"{system.name}: Sugeno, AND {system.and_method}, "
        f"OR {system.or_method}, {system.defuzz}"
    )
    for col in ("variable", "range", "membership functions"):
        summary.add_column(col)
    variables: list[tuple[str, FuzzyInput | FuzzyOutput]] = [
        *(("input", v) for v in system.inputs),
        *(("output", v) for v in system.outputs),
    ]
    for kind, var in variables:
        mfs: Sequence[MembershipFunction | SugenoOutputMf] = var.mfs
        shown = ", ".join(
            f"{k}:{m.name} {m.kind}[{' '.join(f'{p:g}' for p in m.params)}]"
            for k, m in enumerate(mfs, start=1)
        )
        summary.add_row(f"{kind} {var.name}", f"[{var.range[0]:g}, {var.range[1]:g}]", shown)
    rules = Table(title=f"{len(system.rules)} rules")
    rules.add_column("#", justify="right")
    rules.add_column("if")
    rules.add_column("then")
    rules.add_column("weight", justify="right")
    for k, r in enumerate(system.rules, start=1):
        terms = [
            f"{v.name} is {'not ' if a < 0 else ''}{v.mfs[abs(a) - 1].name}"
            for a, v in zip(r.antecedent, system.inputs, strict=True)
            if a
        ]
        then = [
            f"{o.name} is {o.mfs[c - 1].name}"
            for c, o in zip(r.consequent, system.outputs, strict=True)
            if c
        ]
        rules.add_row(str(k), f" {r.connective} ".join(terms), ", ".join(then), f"{r.weight:g}")
    return [summary, rules]
