"""``firefleet team SCENARIO``: the plant here, each robot's controller its own process."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console

from firefleet.cli._console import (
    EXIT_CLAIM_FAILED,
    EXIT_OK,
    all_passed,
    check_flag,
    metrics_table,
    progress_bar,
)
from firefleet.outputs import json_text, run_record, staged_dir
from firefleet.scenarios.registry import load_scenario
from firefleet.sim.metrics import compute_metrics, metrics_document

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``team`` to the subcommands ``sub``."""
    team = sub.add_parser(
        "team",
        help="run a scenario with each robot's controller in its own process, over zenoh",
    )
    team.add_argument("scenario", metavar="SCENARIO", help="built-in name or a YAML path")
    team.add_argument(
        "--transport", choices=("zenoh",), default="zenoh", help="the middleware between them"
    )
    team.add_argument("--out", metavar="DIR", help="output folder (default: runs/SCENARIO-team)")
    team.add_argument(
        "--clock",
        choices=("lockstep", "realtime"),
        default="lockstep",
        help="lockstep: each tick waits for every command (reproducible); realtime: the "
        "monotonic clock paces the ticks",
    )
    team.add_argument(
        "--timeout",
        type=float,
        default=1.0,
        metavar="S",
        help="lock-step: how long a tick waits for a command before counting a miss [s]",
    )
    team.add_argument(
        "--seed", type=int, metavar="N", help="random seed (default: the scenario's own)"
    )
    team.add_argument(
        "--compare",
        action="store_true",
        help="also run the scenario in one process and record the largest difference",
    )
    team.add_argument(
        "--external",
        action="store_true",
        help="hardware in the loop: start no robot process, wait for the scenario's robots "
        "to join (`firefleet robot CONFIG --sim ENDPOINT` on each), then run the plant",
    )
    team.add_argument(
        "--listen",
        metavar="ENDPOINT",
        help="the plant's zenoh endpoint, tcp/127.0.0.1:PORT (default: a free port; "
        "--external needs it fixed)",
    )
    team.add_argument(
        "--run-id",
        metavar="HEX",
        help="the run id, 16 hex digits (default: random; with --external "
        "0000000000000001, a robot config's default link.run_id)",
    )
    team.add_argument(
        "--wait",
        type=float,
        default=60.0,
        metavar="S",
        help="--external: how long to wait for every robot to join [s]",
    )
    team.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    team.set_defaults(handler=cmd_team)


def cmd_team(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet team SCENARIO``."""
    from firefleet.net.team import run_team
    from firefleet.sim.registry import task_kind

    scenario = load_scenario(args.scenario)
    if args.seed is not None:
        check_flag(args.seed >= 0, "--seed", args.seed, ">= 0")
        scenario = dataclasses.replace(scenario, seed=args.seed)
    check_flag(args.timeout > 0, "--timeout", args.timeout, "> 0 seconds")
    check_flag(args.wait > 0, "--wait", args.wait, "> 0 seconds")
    check_flag(
        args.listen is None or args.listen.startswith("tcp/127.0.0.1:"),
        "--listen",
        args.listen,
        "tcp/127.0.0.1:PORT",
    )
    check_flag(not args.external or args.listen is not None, "--listen", None,
               "given with --external (the endpoint the robots connect to)")  # fmt: skip
    run_id = _run_id(args.run_id, external=args.external)
    dest = Path(args.out) if args.out else Path("runs") / f"{scenario.name}-team"
    rec_steps = np.arange(scenario.n_steps + 1)
    record = run_record(args.command_line, seed=scenario.seed)
    with staged_dir(dest, record=record) as stage:
        where = ", external robots" if args.external else ""
        label = f"{scenario.name} over zenoh ({args.clock}{where})"
        with progress_bar(err, label) as progress:
            result, network = run_team(
                scenario, rec_steps, clock=args.clock, timeout_s=args.timeout,
                progress=progress, external=args.external, listen=args.listen,
                run_id=run_id, wait_s=args.wait,
            )  # fmt: skip
        metrics = compute_metrics(result)
        document = metrics_document(scenario.name, scenario.claims, metrics)
        net = network.document()
        if args.compare:
            alone = task_kind(scenario.command.kind).run(scenario, rec_steps, staged=True)
            net["in_process_max_pose_difference_m"] = float(
                np.max(np.abs(result.pose[:, :, :2] - alone.pose[:, :, :2]))
            )
        written = {
            "scenario": document["scenario"],
            "provenance": record,
            **document,
            "network": net,
        }
        (stage / "metrics.json").write_text(json_text(written), encoding="utf-8")
        (stage / "result.npz").write_bytes(result.to_npz_bytes())
        if not args.no_plots:
            from firefleet.report.plots import figures

            for name, data in figures(result, metrics).items():
                (stage / name).write_bytes(data)
    out.print(metrics_table(document))
    out.print(_summary(net), markup=False, highlight=False)
    out.print(f"wrote {dest}/")
    return EXIT_OK if all_passed(document) and not net["failed_robots"] else EXIT_CLAIM_FAILED


def _run_id(text: str | None, *, external: bool) -> int | None:
    """``--run-id`` as an int (None: random), 1 by default with ``--external``."""
    if text is None:
        return 1 if external else None
    try:
        value = int(text, 16)
    except ValueError:
        value = -1
    check_flag(len(text) == 16 and value >= 0, "--run-id", text, "16 hex digits")
    return value


def _summary(net: dict[str, Any]) -> str:
    """One line on the network: ticks per second, misses, drops, failures."""
    rate = net["ticks_per_s"]
    parts = [
        f"zenoh {net['clock']}: {net['robots']} robot processes",
        f"{net['ticks']} ticks at {rate:.0f}/s" if rate else f"{net['ticks']} ticks",
        f"misses {sum(net['misses'])}",
        f"dropped {net['dropped_total']}",
    ]
    if net["failed_robots"]:
        parts.append(f"failed robots {net['failed_robots']}")
    if "in_process_max_pose_difference_m" in net:
        parts.append(f"max |pose - in-process| {net['in_process_max_pose_difference_m']:.3g} m")
    return "; ".join(parts)
