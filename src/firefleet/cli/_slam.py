"""``firefleet slam``: FastSLAM on a log (Victoria Park / GTSAM text, firefleet's own)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from rich.console import Console

from firefleet.cli._console import (
    EXIT_CLAIM_FAILED,
    EXIT_OK,
    all_passed,
    metrics_table,
    progress_bar,
)
from firefleet.errors import InputError
from firefleet.outputs import json_text, run_record, staged_dir
from firefleet.sim.metrics import metrics_document

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``slam`` to the subcommands ``sub``."""
    slam = sub.add_parser(
        "slam", help="run FastSLAM on a log (Victoria Park / GTSAM text, firefleet's own)"
    )
    slam.add_argument(
        "log", metavar="LOG", help="log file, or 'sim-loop' to simulate the 100 m loop"
    )
    slam.add_argument(
        "--particles",
        type=int,
        default=None,
        metavar="P",
        help="number of particles (default 300 with known association, 100 with unknown)",
    )
    slam.add_argument("--seed", type=int, default=0, metavar="N", help="random seed (default 0)")
    slam.add_argument("--out", metavar="DIR", help="output folder (default: runs/slam-LOG)")
    slam.add_argument(
        "--fastslam", type=int, choices=(1, 2), default=2, help="FastSLAM 1.0 or 2.0 (default 2)"
    )
    slam.add_argument(
        "--association",
        choices=("known", "unknown"),
        default="known",
        help="the log's landmark ids, or maximum likelihood (default known)",
    )
    slam.add_argument(
        "--odometry-noise-scale",
        type=float,
        default=2.0,
        metavar="S",
        help="factor on the log's odometry standard deviations (default 2)",
    )
    slam.add_argument(
        "--heading-drift-sigma",
        type=float,
        default=0.003,
        metavar="RAD_PER_M",
        help="prior sigma of the odometry's heading drift per metre, 0 = off (default 0.003)",
    )
    slam.add_argument(
        "--turn-scale-sigma",
        type=float,
        default=0.05,
        metavar="S",
        help="prior sigma of the odometry's turn scale error, 0 = off (default 0.05)",
    )
    slam.add_argument("--no-plots", action="store_true", help="skip slam.png and slam.gif")
    slam.set_defaults(handler=_cmd_slam)


_SLAM_FLAGS = {
    "fastslam.n_particles": "--particles",
    "fastslam.odometry_noise_scale": "--odometry-noise-scale",
    "fastslam.heading_drift_sigma": "--heading-drift-sigma",
    "fastslam.turn_scale_sigma": "--turn-scale-sigma",
}


def _available_memory_bytes() -> int:
    """Memory available to a new allocation: MemAvailable on Linux, else physical memory."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 2**62


def _cmd_slam(args: argparse.Namespace, out: Console, err: Console) -> int:
    import numpy as np

    from firefleet.estimation.fastslam import (
        FastSlamParams,
        default_n_particles,
        fastslam_memory_bytes,
        landmarks_csv,
        run_fastslam,
        slam_claims,
        slam_summary,
        trajectory_csv,
    )
    from firefleet.estimation.logs import format_log
    from firefleet.sim.world import SIM_LOOP, load_or_simulate_log

    if args.seed < 0:
        raise InputError(f"--seed must be >= 0, got {args.seed}")
    particles = default_n_particles(args.association) if args.particles is None else args.particles
    try:
        params = FastSlamParams(
            n_particles=particles,
            version=args.fastslam,
            association=args.association,
            odometry_noise_scale=args.odometry_noise_scale,
            heading_drift_sigma=args.heading_drift_sigma,
            turn_scale_sigma=args.turn_scale_sigma,
        )
    except InputError as exc:  # name the flag a person typed, not the field
        message = str(exc)
        for field, flag in _SLAM_FLAGS.items():
            message = message.replace(field, flag)
        raise InputError(message) from None
    log = load_or_simulate_log(args.log, seed=args.seed)
    need = fastslam_memory_bytes(log, params)
    have = _available_memory_bytes()
    if need > 0.8 * have:
        raise InputError(
            f"--particles {particles} needs about {need / 2**30:.3g} GiB for {log.n_poses} "
            f"poses, more than the {have / 2**30:.3g} GiB available; use fewer particles"
        )
    dest = Path(args.out) if args.out else Path("runs") / f"slam-{Path(args.log).stem}"
    with progress_bar(err, f"FastSLAM {args.fastslam}.0 over {log.n_poses} poses") as progress:
        result = run_fastslam(
            log,
            np.random.default_rng(args.seed),
            params=params,
            n_snapshots=0 if args.no_plots else 60,
            progress=progress,
        )
    metrics = slam_summary(log, result)
    document = metrics_document(
        log.name, slam_claims(metrics, association=args.association), dict(metrics)
    )
    record = run_record(args.command_line, seed=args.seed)
    with staged_dir(dest, record=record) as stage:
        (stage / "trajectory.csv").write_text(trajectory_csv(log, result), encoding="utf-8")
        (stage / "landmarks.csv").write_text(landmarks_csv(result), encoding="utf-8")
        written = {"scenario": document["scenario"], "provenance": record, **document}
        (stage / "summary.json").write_text(json_text(written), encoding="utf-8")
        if args.log == SIM_LOOP:
            (stage / "log.txt").write_text(format_log(log), encoding="utf-8")
        if not args.no_plots:
            from firefleet.report.slam import slam_animation_gif, slam_figure_png

            (stage / "slam.png").write_bytes(slam_figure_png(log, result))
            (stage / "slam.gif").write_bytes(slam_animation_gif(log, result))
    out.print(
        f"FastSLAM {args.fastslam}.0, {args.association} association, {particles} particles",
        markup=False,
        highlight=False,
    )
    out.print(metrics_table(document))
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    return EXIT_OK if all_passed(document) else EXIT_CLAIM_FAILED
