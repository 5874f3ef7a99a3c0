"""The ``firefleet`` command line (the contract of DESIGN.md).

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
    firefleet slam LOG [--particles P] [--seed N] [--out DIR] [--fastslam {1,2}]
                   [--association {known,unknown}] [--odometry-noise-scale S]
                   [--heading-drift-sigma RAD_PER_M] [--turn-scale-sigma S] [--no-plots]

Bad input (an unknown scenario, a malformed file, a bad value) is one line per problem
on stderr and exit status 2, with nothing written. A run whose claims do not all hold
exits 1.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

import firefleet
from firefleet.errors import InputError
from firefleet.outputs import json_text, staged_dir, write_text_atomic
from firefleet.scenarios.registry import builtin_names, load_scenario
from firefleet.scenarios.schema import Scenario, read_scenario_file
from firefleet.sim.engine import ProgressCallback, simulate
from firefleet.sim.metrics import compute_metrics, metrics_document

if TYPE_CHECKING:
    from firefleet.control.fuzzy import (
        FuzzyInput,
        FuzzyOutput,
        MembershipFunction,
        SugenoOutputMf,
        SugenoSystem,
    )

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
    for key, value in document.items():
        if key in ("scenario", "claims"):
            continue
        claims = [c for c in document["claims"] if c["name"].split("[")[0] == key]
        expected = escape(
            "; ".join(
                c["expected"] + c["name"].removeprefix(key).replace("[", " [") for c in claims
            )
        )
        verdict = " ".join("[green]passed" if c["passed"] else "[red]FAILED" for c in claims)
        table.add_row(key, _shown(value), expected, verdict)
    return table


def _shown(value: Any) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, list):
        return escape("[" + ", ".join(f"{v:.4g}" if v is not None else "n/a" for v in value) + "]")
    return f"{value:.6g}"


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
            out.print(f"{scn.name:<24} {mark}  {escape(scn.reproduces)}")
        index = render_index(entries, version=firefleet.__version__)
        (stage / "index.html").write_text(index, encoding="utf-8")
    total = sum(len(e.document["claims"]) for e in entries)
    passed = sum(c["passed"] for e in entries for c in e.document["claims"])
    out.print(f"{passed} of {total} claims passed")
    out.print(f"report: {(dest / 'index.html').resolve()}", markup=False, highlight=False)
    return EXIT_OK if passed == total else EXIT_CLAIM_FAILED


# ---------------------------------------------------------------- firefleet fis


def _add_fis_parser(sub: Any) -> None:
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

    with _progress_bar(err, "plots") as progress:
        progress(0, 1)
        pngs = figures(system, fixed=fixed)
        progress(1, 1)
    dest = Path(args.out) if args.out else Path("runs") / Path(args.file).stem
    with staged_dir(dest) as stage:
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


# ------------------------------------------------------------------ thermal (issue 5)


def _check_flag(ok: bool, flag: str, value: Any, expected: str) -> None:
    """Raise an InputError naming the flag a person typed unless ``ok``."""
    if not ok:
        raise InputError(f"{flag} must be {expected}, got {value}")


def _cmd_thermal(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.perception import thermal as th  # scipy.ndimage only when needed
    from firefleet.report.thermal import detection_png, figure_names

    _check_flag(0.0 < args.hfov_deg < 180.0, "--hfov-deg", args.hfov_deg, "in (0, 180) degrees")
    if args.fire_width_m is not None:
        _check_flag(args.fire_width_m > 0.0, "--fire-width-m", args.fire_width_m, "> 0 [m]")
    calibration = th.LinearCalibration.parse(args.counts) if args.counts else None
    params = th.DetectionParams(fire_width_m=args.fire_width_m)
    paths = th.frame_paths(args.frames)
    pictures = figure_names(paths)
    dest = Path(args.out)
    documents: list[dict[str, Any]] = []
    with staged_dir(dest) as stage, _progress_bar(err, "thermal frames") as progress:
        for i, path in enumerate(paths):
            frame = th.read_frame(path, calibration=calibration)
            camera = th.CameraModel.for_frame(frame.shape, hfov_deg=args.hfov_deg)
            result = th.detect(frame, camera=camera, params=params)
            documents.append({**th.detections_document(path.name, result), "figure": pictures[i]})
            png = detection_png(result.filtered_c, result, title=path.name)
            (stage / pictures[i]).write_bytes(png)
            progress(i + 1, len(paths))
        (stage / "detections.json").write_text(json_text(documents), encoding="utf-8")
    table = Table(title="thermal detections")
    for column in ("frame", "fire alarm", "fires", "people", "warm"):
        table.add_column(column)
    for doc in documents:
        kinds = [d["kind"] for d in doc["detections"]]
        table.add_row(
            doc["frame"],
            "[red]YES" if doc["fire_alarm"] else "no",
            *(str(kinds.count(k)) for k in ("fire", "person", "warm")),
        )
    out.print(table)
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    return EXIT_OK


def _add_thermal_parser(sub: Any) -> None:
    thermal = sub.add_parser(
        "thermal", help="find fires and people in thermal frames; PNGs and detections.json"
    )
    thermal.add_argument(
        "frames", nargs="+", metavar="FRAME", help=".npy (C) or image; or a folder"
    )
    thermal.add_argument(
        "--out", metavar="DIR", default="runs/thermal", help="output folder (default runs/thermal)"
    )
    thermal.add_argument(
        "--counts",
        metavar="CAL",
        help="frames hold counts: 'tlinear' (0.01 K), 'tlinear10' (0.1 K) or 'GAIN,OFFSET' (C)",
    )
    thermal.add_argument(
        "--hfov-deg",
        type=float,
        default=51.0,
        help="horizontal field of view [deg] (default 51, the Lepton's)",
    )
    thermal.add_argument(
        "--fire-width-m",
        type=float,
        help="size prior of a fire [m]: gives fires a range (default: none)",
    )


# ------------------------------------------------------------------ end thermal
# --- slam (issue 7): FastSLAM on a log ------------------------------------------------


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
    with _progress_bar(err, f"FastSLAM {args.fastslam}.0 over {log.n_poses} poses") as progress:
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
    with staged_dir(dest) as stage:
        (stage / "trajectory.csv").write_text(trajectory_csv(log, result), encoding="utf-8")
        (stage / "landmarks.csv").write_text(landmarks_csv(result), encoding="utf-8")
        (stage / "summary.json").write_text(json_text(document), encoding="utf-8")
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
    out.print(_claims_table(document))
    out.print(f"wrote {dest}/", markup=False, highlight=False)
    return EXIT_OK if _all_passed(document) else EXIT_CLAIM_FAILED


def _add_slam_parser(sub: Any) -> None:
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


# --- end slam ---------------------------------------------------------------------------


def _figure_number(label: str) -> tuple[int, str]:
    digits = "".join(c if c.isdigit() else " " for c in label).split()
    return (int(digits[0]) if digits else 10**6, label)


# ------------------------------------------------------------ stereo and capture


def _cmd_stereo(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.perception import stereo
    from firefleet.report.stereo import run_files

    if args.calib is None and not (args.uncalibrated or args.rectified):
        raise InputError("stereo: give --calib FILE, --uncalibrated or --rectified")
    if args.rectified and args.uncalibrated:
        raise InputError("stereo: --rectified and --uncalibrated exclude each other")
    if (args.focal_px is None) != (args.baseline_m is None):
        raise InputError("stereo: --focal-px and --baseline-m go together")
    for flag, value in (("--focal-px", args.focal_px), ("--baseline-m", args.baseline_m)):
        if value is not None:
            _check_flag(math.isfinite(value) and value > 0.0, flag, value, "a number > 0")
    _check_flag(math.isfinite(args.doffs_px), "--doffs-px", args.doffs_px, "a finite number")
    _check_flag(
        math.isfinite(args.min_depth_m) and args.min_depth_m > 0.0,
        "--min-depth-m",
        args.min_depth_m,
        "a number > 0 [m]",
    )
    _check_flag(args.sectors >= 1, "--sectors", args.sectors, ">= 1")
    calib = stereo.load_calibration(args.calib) if args.calib else None
    left, right = stereo.read_image(args.left), stereo.read_image(args.right)
    if args.num_disparities is not None:
        width = left.shape[1]
        _check_flag(
            0 < args.num_disparities < width and args.num_disparities % 16 == 0,
            "--num-disparities",
            args.num_disparities,
            f"a positive multiple of 16 below the image width {width} px",
        )
    mode = "rectified" if args.rectified else "uncalibrated" if args.uncalibrated else "calibrated"
    run = stereo.process_pair(
        left,
        right,
        calib=calib,
        mode=mode,
        focal_px=args.focal_px,
        baseline_m=args.baseline_m,
        doffs_px=args.doffs_px,
        min_disparity=args.min_disparity,
        num_disparities=args.num_disparities,
        min_depth_m=args.min_depth_m,
        n_sectors=args.sectors,
    )
    summary = {"left": str(args.left), "right": str(args.right), **run.summary}
    dest = Path(args.out)
    files = run_files(run)
    with staged_dir(dest) as stage:
        for name, content in files.items():
            (stage / name).write_bytes(content)
        (stage / "summary.json").write_text(json_text(summary), encoding="utf-8")
    names = list(files)
    table = Table(title=f"stereo ({mode})")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    for key, value in summary.items():
        if isinstance(value, bool):
            table.add_row(key, "[red]YES" if value else "no")
        elif isinstance(value, float):
            table.add_row(key, f"{value:.6g}")
        elif isinstance(value, int):
            table.add_row(key, str(value))
    out.print(table)
    if summary.get("search_saturated"):
        err.print(
            f"warning: {summary['saturated_pct']:.1f} % of the pixels matched at the end of "
            f"the disparity search ({summary['num_disparities']} px): something is nearer "
            "than it measures; nearest_obstacle_m is not reported"
            + (
                f" (nearer than {summary['obstacle_nearer_than_m']:.3g} m)"
                if summary.get("obstacle_nearer_than_m") is not None
                else ""
            )
            + "; widen --num-disparities or leave it out",
            markup=False,
            highlight=False,
        )
    out.print(f"wrote {dest}/: {', '.join([*names, 'summary.json'])}", markup=False)
    return EXIT_OK


def _cmd_capture(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.perception import capture

    _check_flag(args.frames >= 1, "--frames", args.frames, ">= 1")
    _check_flag(args.offset >= 0, "--offset", args.offset, ">= 0")
    _check_flag(args.every >= 1, "--every", args.every, ">= 1")
    for flag, size in (("--width", args.width), ("--height", args.height)):
        if size is not None:
            _check_flag(size > 0, flag, size, "> 0 [px]")
    dest = Path(args.out)
    rows: list[dict[str, Any]] = []
    with staged_dir(dest) as stage, _progress_bar(err, "capture") as progress:
        for frame in capture.stereo_capture(
            args.left,
            args.right,
            n_frames=args.frames,
            offset_frames=args.offset,
            every=args.every,
            width=args.width,
            height=args.height,
        ):
            for name, content in capture.pair_files(frame).items():
                (stage / name).write_bytes(content)
            rows.append(capture.timestamp_row(frame))
            progress(len(rows), args.frames)
        (stage / "timestamps.csv").write_text(capture.timestamps_csv(rows), encoding="utf-8")
    skew = max(abs(r["skew_s"]) for r in rows)
    out.print(
        f"wrote {len(rows)} pair(s) and timestamps.csv to {dest}/ (max skew {skew * 1e3:.1f} ms)",
        markup=False,
        highlight=False,
    )
    return EXIT_OK


def _add_stereo_parsers(sub: Any) -> None:
    st = sub.add_parser(
        "stereo", help="rectify a stereo pair; disparity, depth, point cloud and range scan"
    )
    st.add_argument("left", metavar="LEFT", help="left image file")
    st.add_argument("right", metavar="RIGHT", help="right image file")
    how = st.add_mutually_exclusive_group()
    how.add_argument("--calib", metavar="FILE", help="calibration YAML: calibrated rectification")
    how.add_argument(
        "--uncalibrated", action="store_true", help="rectify from matched interest points"
    )
    st.add_argument(
        "--rectified",
        action="store_true",
        help="the pair is already rectified (with --calib: by it)",
    )
    st.add_argument("--focal-px", type=float, help="rectified focal length [px] (with --rectified)")
    st.add_argument("--baseline-m", type=float, help="baseline [m] (with --rectified)")
    st.add_argument(
        "--doffs-px", type=float, default=0.0, help="cx_right - cx_left [px] (default 0)"
    )
    st.add_argument(
        "--min-disparity",
        type=int,
        default=0,
        metavar="PX",
        help="start of the disparity search [px] (default 0)",
    )
    st.add_argument(
        "--num-disparities",
        type=int,
        metavar="N",
        help="disparities to search, a multiple of 16 (default: found coarse to fine, "
        "down to --min-depth-m)",
    )
    st.add_argument(
        "--min-depth-m",
        type=float,
        default=0.3,
        metavar="M",
        help="nearest depth the default search range measures [m] (default 0.3)",
    )
    st.add_argument(
        "--sectors", type=int, default=32, metavar="K", help="range-scan sectors (default 32)"
    )
    st.add_argument(
        "--out", metavar="DIR", default="stereo-out", help="output folder (default stereo-out)"
    )
    cap = sub.add_parser("capture", help="frame-synchronised pairs from two cameras or videos")
    cap.add_argument("left", metavar="LEFT", help="/dev/videoN, a camera index, or a video file")
    cap.add_argument("right", metavar="RIGHT", help="/dev/videoN, a camera index, or a video file")
    cap.add_argument("--out", metavar="DIR", required=True, help="output folder")
    cap.add_argument("--frames", type=int, default=1, metavar="N", help="pairs to save (default 1)")
    cap.add_argument(
        "--offset", type=int, default=0, metavar="K", help="skip K right frames (default 0)"
    )
    cap.add_argument(
        "--every", type=int, default=1, metavar="K", help="keep every K-th pair (default 1)"
    )
    cap.add_argument("--width", type=int, help="camera width [px] (default: the camera's)")
    cap.add_argument("--height", type=int, help="camera height [px] (default: the camera's)")


# ------------------------------------------------------------------------------


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
    _add_stereo_parsers(sub)
    _add_fis_parser(sub)
    _add_thermal_parser(sub)
    _add_slam_parser(sub)
    return parser


_COMMANDS = {
    "list": _cmd_list,
    "run": _cmd_run,
    "validate": _cmd_validate,
    "reproduce": _cmd_reproduce,
    "stereo": _cmd_stereo,
    "capture": _cmd_capture,
    "fis": _cmd_fis,
    "thermal": _cmd_thermal,
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
