"""The ``firefleet`` command line (the contract of DESIGN.md): parser and entry point.

::

    firefleet list
    firefleet run SCENARIO [--out DIR] [--seed N] [--no-plots]
    firefleet validate FILE...
    firefleet reproduce [--out DIR]
    firefleet stereo LEFT RIGHT [--calib FILE | --uncalibrated | --rectified] [--out DIR]
    firefleet capture LEFT RIGHT --out DIR [--frames N] [--offset K] [--every K]
    firefleet fis FILE [--out DIR] [--fix NAME=VALUE ...]
    firefleet fis FILE --eval IN.csv --out OUT.csv
    firefleet thermal FRAME... [--out DIR] [--counts CAL] [--hfov-deg DEG] [--fire-width-m W]
    firefleet team SCENARIO [--transport zenoh] [--clock lockstep|realtime] [--out DIR] [--seed N]
    firefleet slam LOG [--particles P] [--seed N] [--out DIR] [--fastslam {1,2}]
                   [--association {known,unknown}] [--odometry-noise-scale S]
                   [--heading-drift-sigma RAD_PER_M] [--turn-scale-sigma S] [--no-plots]

Bad input (an unknown scenario, a malformed file, a bad value) is one line per problem
on stderr and exit status 2, with nothing written. A run whose claims do not all hold
exits 1.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from rich.console import Console

import firefleet
from firefleet.cli import _fis, _run, _slam, _stereo, _team, _thermal
from firefleet.cli._console import EXIT_BAD_INPUT, EXIT_OK
from firefleet.errors import InputError

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """argparse, with a bad command line as one line on stderr (no usage block)."""

    def error(self, message: str) -> NoReturn:
        self.exit(
            EXIT_BAD_INPUT,
            f"{self.prog}: error: {message} (see {self.prog} --help)\n",
        )


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="firefleet",
        description="Teams of intelligent mobile robots for firefighting: simulate, "
        "check, and reproduce the deliverable's experiments.",
    )
    parser.add_argument("--version", action="version", version=f"firefleet {firefleet.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for group in (_run, _stereo, _fis, _thermal, _slam, _team):  # the order of the help
        group.add_parsers(sub)
    for command in sub.choices.values():
        _say_defaults(command)
    return parser


def _say_defaults(parser: argparse.ArgumentParser) -> None:
    """Make every option's help say its default (or that it is required)."""
    for action in parser._actions:  # argparse has no public list of a parser's options
        if not action.option_strings or isinstance(action, argparse._HelpAction):
            continue
        text = action.help or ""
        if "default" in text or "required" in text:
            continue
        if action.required:
            said = "required"
        elif isinstance(action, argparse._StoreTrueAction):
            said = "default: off"
        elif action.default is None or action.default == []:
            said = "default: none"
        else:
            said = f"default {action.default}"
        action.help = f"{text} ({said})" if text else said


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``firefleet`` command; returns the exit status."""
    typed = list(sys.argv[1:] if argv is None else argv)
    parser = _parser()
    if not typed:  # bare ``firefleet``: the help, not an error
        parser.print_help()
        return EXIT_OK
    args = parser.parse_args(typed)
    args.command_line = ["firefleet", *typed]
    out = Console(soft_wrap=True)
    err = Console(stderr=True, soft_wrap=True)
    try:
        status: int = args.handler(args, out, err)
    except InputError as exc:
        for line in str(exc).splitlines():
            err.print(f"firefleet: error: {line}", markup=False, highlight=False)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        err.print("firefleet: interrupted; nothing written")
        return 130
    return status
