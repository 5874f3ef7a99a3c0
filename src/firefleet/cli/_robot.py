"""``firefleet robot CONFIG.yaml [--fake | --sim ENDPOINT]``: the on-board loop on a robot's
hardware (or its fakes, or the simulator's plant over zenoh)."""

from __future__ import annotations

import argparse
import contextlib
import io
import signal
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console

from firefleet.cli._console import EXIT_CLAIM_FAILED, EXIT_OK, check_flag, progress_bar
from firefleet.outputs import json_text, run_record, staged_dir

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``robot`` to the subcommands ``sub``."""
    robot = sub.add_parser(
        "robot",
        help="run one robot's controllers on its hardware (or on fakes of it)",
    )
    robot.add_argument("config", metavar="CONFIG", help="the robot's YAML configuration")
    where = robot.add_mutually_exclusive_group()
    where.add_argument(
        "--fake",
        action="store_true",
        help="replace every device by its fake (a simulated Arduino on a pseudo-terminal, "
        "a Lepton replaying frames, a PT100 register model): runs on any machine",
    )
    where.add_argument(
        "--sim",
        metavar="ENDPOINT",
        help="hardware in the loop: the motors and encoders are the plant of "
        "`firefleet team SCENARIO --external --listen ENDPOINT`, over zenoh "
        "(ENDPOINT: tcp/127.0.0.1:PORT; the run id is the config's link.run_id)",
    )
    robot.add_argument("--out", metavar="DIR", help="folder for the log and the summary")
    robot.set_defaults(handler=cmd_robot)


@contextlib.contextmanager
def _signals(stop: threading.Event) -> Iterator[None]:
    """SIGINT and SIGTERM set ``stop`` (the loop then stops the motors and ends)."""
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s in previous:
        signal.signal(s, lambda *_: stop.set())
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def cmd_robot(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet robot CONFIG``."""
    from firefleet.robot import load_role, open_adapters, read_robot_config, run_onboard

    if args.sim is not None:
        check_flag(args.sim.startswith("tcp/127.0.0.1:"), "--sim", args.sim, "tcp/127.0.0.1:PORT")
    config, folder = read_robot_config(args.config)
    scenario = load_role(config, folder)
    dest = Path(args.out) if args.out else Path("runs") / f"robot-{config.robot}"
    stop = threading.Event()
    record = run_record(args.command_line, seed=None)
    with staged_dir(dest, record=record) as stage:
        opened = open_adapters(
            config, fake=args.fake, sim=args.sim, n_robots=scenario.n_robots,
            dt_s=scenario.dt_s,
        )  # fmt: skip
        with _signals(stop), opened as adapters:
            mode = " (fake)" if args.fake else f" (sim at {args.sim})" if args.sim else ""
            label = f"robot {config.robot} of {scenario.name}{mode}"
            with progress_bar(err, label) as progress:
                result = run_onboard(config, scenario, adapters, stop=stop, progress=progress)
            link = adapters.link_errors
        summary = {"robot": config.robot, "scenario": scenario.name, **result.summary(),
                   "motor_link": link}  # fmt: skip
        (stage / "summary.json").write_text(json_text(summary), encoding="utf-8")
        buffer = io.BytesIO()
        np.savez_compressed(
            buffer,
            t=np.asarray(result.t_s),
            counts=np.asarray(result.counts, dtype=np.int64).reshape(-1, 2),
            reference_rad_s=np.asarray(result.reference_rad_s).reshape(-1, 2),
            pose_estimate=np.asarray(result.pose).reshape(-1, 3),
            period_s=np.asarray(result.period_s),
            pt100_c=np.asarray(result.pt100_c).reshape(-1, 2),
        )
        (stage / "log.npz").write_bytes(buffer.getvalue())
    p50, p99 = summary["period_p50_s"] * 1e3, summary["period_p99_s"] * 1e3
    out.print(
        f"robot {config.robot}: {result.ticks} periods, stopped on {result.stop_reason}; "
        f"period p50 {p50:.2f} ms, p99 {p99:.2f} ms; {result.overruns} overruns; "
        f"CPU {100 * summary['cpu_share_of_one_core']:.1f} % of a core; "
        f"{summary['thermal_frames']} thermal frames, {summary['pt100_readings']} PT100 readings",
        markup=False,
        highlight=False,
    )
    team = result.team_link
    if team is not None:
        out.print(
            f"team link: {team['estops']} lost-link e-stops, {team['estopped_s']:.2f} s "
            f"stopped, {sum(team['received'].values())} teammate messages heard",
            markup=False,
            highlight=False,
        )
    out.print(f"wrote {dest}/")
    return EXIT_CLAIM_FAILED if result.stop_reason == "overruns" else EXIT_OK
