"""Benchmark: the thermal detection pipeline against a plain OpenCV threshold-and-contours.

Frames per second of :func:`firefleet.perception.thermal.detect` (destriping, median,
local background, labelling, per-region measurement, bearing and range) on simulated
Lepton frames (80 x 60: a fire, a person, walls) and on the same scenes rendered at
640 x 512, and of the baseline on the same frames: ``cv2.threshold`` at the median +
3 K, ``cv2.findContours``, and each contour's area, bounding box and centroid
(``cv2.moments``) - a detector with no filtering, no background model, no ranging.
The ratio is baseline fps / ours (how much slower the whole pipeline is).

Floor (issue 5): the whole pipeline on one 80 x 60 frame in under a tenth of the
Lepton's frame period (1 / 9 Hz / 10 = 11.1 ms), on one core.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable
from typing import Any

if __name__ == "__main__":  # one core, before numpy loads (run.py sets it otherwise)
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import cv2
import numpy as np
from numpy.typing import NDArray
from rich.console import Console
from rich.table import Table

from firefleet.perception.thermal import CameraModel, DetectionParams, detect
from firefleet.sim.sensors import ThermalCameraParams, ThermalScene, render_thermal

FRAME_PERIOD_S = 1.0 / 9.0
FLOOR_S = FRAME_PERIOD_S / 10.0
"""Floor: one 80 x 60 frame through the pipeline in a tenth of the Lepton's frame period."""
FRAMES = 20
REPEATS = 5


def _scenes(count: int, rng: np.random.Generator) -> list[tuple[ThermalScene, NDArray[np.float64]]]:
    walls = np.array(
        [[-15, -15, 15, -15], [15, -15, 15, 15], [15, 15, -15, 15], [-15, 15, -15, -15]]
    )
    out = []
    for _ in range(count):
        pose = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-math.pi, math.pi)])
        r = rng.uniform([4.0, 4.0], [12.0, 12.0])
        b = pose[2] + np.array([rng.uniform(-0.35, -0.1), rng.uniform(0.1, 0.35)])
        xy = np.stack([pose[0] + r * np.cos(b), pose[1] + r * np.sin(b)], axis=-1)
        scene = ThermalScene(
            walls_m=walls.astype(float),
            wall_temp_c=rng.uniform(15, 30, 4),
            object_xy_m=xy,
            object_size_m=np.array([[0.8, 1.0], [0.5, 1.7]]),
            object_temp_c=np.array([rng.uniform(150, 400), rng.uniform(31, 36)]),
        )
        out.append((scene, pose))
    return out


def _opencv_baseline(
    frame: NDArray[np.float64],
) -> list[tuple[float, tuple[int, int, int, int], float, float]]:
    f32 = frame.astype(np.float32)
    _, mask = cv2.threshold(f32, float(np.median(f32)) + 3.0, 255.0, cv2.THRESH_BINARY)
    contours, _ = cv2.findContours(
        mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    found = []
    for c in contours:
        m = cv2.moments(c)
        area = m["m00"]
        if area > 0:
            x, y, w, h = cv2.boundingRect(c)
            found.append((area, (int(x), int(y), int(w), int(h)), m["m10"] / area, m["m01"] / area))
    return found


def _best_per_frame(
    fn: Callable[[NDArray[np.float64]], object], frames: NDArray[np.float64]
) -> float:
    """Best (over repeats) mean time per frame [s] over the frame set, after a warm-up."""
    for f in frames[:2]:
        fn(f)
    best = math.inf
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        for f in frames:
            fn(f)
        best = min(best, (time.perf_counter() - t0) / len(frames))
    return best


def run(console: Console) -> dict[str, Any]:
    """Measure, print the tables, return every number."""
    rng = np.random.default_rng(0)
    scenes = _scenes(FRAMES, rng)
    results: dict[str, Any] = {"frames_per_size": FRAMES, "repeats": REPEATS, "sizes": {}}
    table = Table(title="thermal detection pipeline vs OpenCV threshold + contours (one core)")
    for column in (
        "frame",
        "firefleet ms/frame",
        "firefleet fps",
        "OpenCV ms/frame",
        "OpenCV fps",
        "OpenCV fps / firefleet fps",
    ):
        table.add_column(column, justify="right")
    for width, height, hfov in ((80, 60, 51.0), (640, 512, 51.0)):
        cam = CameraModel(width_px=width, height_px=height, hfov_rad=math.radians(hfov))
        prm = ThermalCameraParams(camera=cam, supersample=2 if width > 100 else 4)
        frames = np.stack([render_thermal(s, pose[None], prm, rng=rng)[0] for s, pose in scenes])
        params = DetectionParams(fire_width_m=0.8)

        def pipeline(
            f: NDArray[np.float64], cam: CameraModel = cam, params: DetectionParams = params
        ) -> object:
            return detect(f, camera=cam, params=params)

        ours = _best_per_frame(pipeline, frames)
        peer = _best_per_frame(_opencv_baseline, frames)
        fires = sum(detect(f, camera=cam, params=params).fire_alarm for f in frames)
        key = f"{width}x{height}"
        results["sizes"][key] = {
            "ours_s_per_frame": ours,
            "ours_fps": 1.0 / ours,
            "opencv_s_per_frame": peer,
            "opencv_fps": 1.0 / peer,
            "ratio_opencv_fps_over_ours": ours / peer,
            "frames_with_fire_alarm": int(fires),
        }
        table.add_row(
            key,
            f"{ours * 1e3:.3f}",
            f"{1 / ours:,.0f}",
            f"{peer * 1e3:.3f}",
            f"{1 / peer:,.0f}",
            f"{ours / peer:.1f}x",
        )
    console.print(table)
    lepton = results["sizes"]["80x60"]["ours_s_per_frame"]
    passed = lepton < FLOOR_S
    floors = Table(title="floor")
    for column in ("floor", "required", "measured", "verdict"):
        floors.add_column(column)
    floors.add_row(
        "80 x 60 frame through the whole pipeline",
        f"< {FLOOR_S * 1e3:.1f} ms",
        f"{lepton * 1e3:.3f} ms",
        "[green]PASS" if passed else "[red]FAIL",
    )
    console.print(floors)
    results["floor"] = {"required_s": FLOOR_S, "measured_s": lepton, "pass": passed}
    return results


if __name__ == "__main__":
    import json

    doc = run(Console())
    json.dump(doc, sys.stdout, indent=2)
    sys.stdout.write("\n")
