"""``firefleet slam``: FastSLAM on a log (Victoria Park / GTSAM text, firefleet's own)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rich.console import Console

from firefleet.cli._console import (
    EXIT_CLAIM_FAILED,
    EXIT_OK,
    all_passed,
    claims_table,
    progress_bar,
)
from firefleet.errors import InputError
from firefleet.outputs import json_text, run_record, staged_dir

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``slam`` to the subcommands ``sub``."""
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
        help="factor on the log's odometry standard deviations (Victoria Park: 2)",
    )
    slam.add_argument(
        "--heading-drift-sigma",
        type=float,
        default=0.0,
        metavar="RAD_PER_M",
        help="estimate a heading drift per metre with this prior sigma (Victoria Park: 0.003)",
    )
    slam.add_argument(
        "--turn-scale-sigma",
        type=float,
        default=0.0,
        metavar="S",
        help="estimate a turn scale error with this prior sigma (Victoria Park: 0.05)",
    )
    slam.add_argument("--no-plots", action="store_true", help="skip slam.png and slam.gif")
    slam.set_defaults(handler=_cmd_slam)


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
        heading_drift_sigma=args.heading_drift_sigma,
        turn_scale_sigma=args.turn_scale_sigma,
    )
    log = load_or_simulate_log(args.log, seed=args.seed)
    dest = Path(args.out) if args.out else Path("runs") / f"slam-{Path(args.log).stem}"
    with progress_bar(err, f"FastSLAM {args.version}.0 over {log.n_poses} poses") as progress:
        result = run_fastslam(
            log,
            np.random.default_rng(args.seed),
            params=params,
            n_snapshots=0 if args.no_plots else 60,
            progress=progress,
        )
    summary = slam_summary(log, result)
    record = run_record(args.command_line, seed=args.seed)
    with staged_dir(dest, record=record) as stage:
        (stage / "trajectory.csv").write_text(trajectory_csv(log, result), encoding="utf-8")
        (stage / "landmarks.csv").write_text(landmarks_csv(result), encoding="utf-8")
        written = {**summary, "provenance": record}
        (stage / "summary.json").write_text(json_text(written), encoding="utf-8")
        if args.log == SIM_LOOP:
            (stage / "log.txt").write_text(format_log(log), encoding="utf-8")
        if not args.no_plots:
            from firefleet.report.slam import slam_animation_gif, slam_figure_png

            (stage / "slam.png").write_bytes(slam_figure_png(log, result))
            (stage / "slam.gif").write_bytes(slam_animation_gif(log, result))
    rows: list[tuple[str, Any]] = []
    for key, value in summary.items():
        if isinstance(value, dict):  # odometry_calibration: one row per estimate
            rows += list(value.items())
        elif key != "claims":
            rows.append((key, value))
    table = claims_table(
        f"FastSLAM {args.version}.0 on {log.name}",
        rows,
        summary["claims"],
        columns=("quantity", "value"),
    )
    out.print(table)
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    return EXIT_OK if all_passed(summary) else EXIT_CLAIM_FAILED
