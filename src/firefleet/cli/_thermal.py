"""``firefleet thermal``: fires and people in thermal frames."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from firefleet.cli._console import EXIT_OK, check_flag, progress_bar
from firefleet.outputs import json_text, run_record, staged_dir

__all__ = ["add_parsers"]


def add_parsers(sub: Any) -> None:
    """Add ``thermal`` to the subcommands ``sub``."""
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
    thermal.set_defaults(handler=_cmd_thermal)


def _cmd_thermal(args: argparse.Namespace, out: Console, err: Console) -> int:
    from firefleet.perception import thermal as th  # scipy.ndimage only when needed
    from firefleet.report.thermal import detection_png, figure_names

    check_flag(0.0 < args.hfov_deg < 180.0, "--hfov-deg", args.hfov_deg, "in (0, 180) degrees")
    if args.fire_width_m is not None:
        check_flag(args.fire_width_m > 0.0, "--fire-width-m", args.fire_width_m, "> 0 [m]")
    calibration = th.LinearCalibration.parse(args.counts) if args.counts else None
    params = th.DetectionParams(fire_width_m=args.fire_width_m)
    paths = th.frame_paths(args.frames)
    pictures = figure_names(paths)
    dest = Path(args.out)
    documents: list[dict[str, Any]] = []
    record = run_record(args.command_line, seed=None)
    with staged_dir(dest, record=record) as stage, progress_bar(err, "thermal frames") as progress:
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
