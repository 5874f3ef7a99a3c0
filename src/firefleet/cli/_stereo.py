"""``firefleet stereo`` and ``firefleet capture``: stereo pairs to depth, cameras to pairs."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from firefleet.cli._console import EXIT_OK, check_flag, progress_bar
from firefleet.errors import InputError
from firefleet.outputs import json_text, run_record, staged_dir

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``stereo`` and ``capture`` to the subcommands ``sub``."""
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
    st.set_defaults(handler=_cmd_stereo)
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
    cap.set_defaults(handler=_cmd_capture)


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
            check_flag(math.isfinite(value) and value > 0.0, flag, value, "a number > 0")
    check_flag(math.isfinite(args.doffs_px), "--doffs-px", args.doffs_px, "a finite number")
    check_flag(
        math.isfinite(args.min_depth_m) and args.min_depth_m > 0.0,
        "--min-depth-m",
        args.min_depth_m,
        "a number > 0 [m]",
    )
    check_flag(args.sectors >= 1, "--sectors", args.sectors, ">= 1")
    calib = stereo.load_calibration(args.calib) if args.calib else None
    left, right = stereo.read_image(args.left), stereo.read_image(args.right)
    if args.num_disparities is not None:
        width = left.shape[1]
        check_flag(
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
    record = run_record(args.command_line, seed=None)
    with staged_dir(dest, record=record) as stage:
        for name, content in files.items():
            (stage / name).write_bytes(content)
        written = {**summary, "provenance": record}
        (stage / "summary.json").write_text(json_text(written), encoding="utf-8")
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

    check_flag(args.frames >= 1, "--frames", args.frames, ">= 1")
    check_flag(args.offset >= 0, "--offset", args.offset, ">= 0")
    check_flag(args.every >= 1, "--every", args.every, ">= 1")
    for flag, size in (("--width", args.width), ("--height", args.height)):
        if size is not None:
            check_flag(size > 0, flag, size, "> 0 [px]")
    dest = Path(args.out)
    rows: list[dict[str, Any]] = []
    record = run_record(args.command_line, seed=None)
    with staged_dir(dest, record=record) as stage, progress_bar(err, "capture") as progress:
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
