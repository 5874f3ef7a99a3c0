"""Benchmark of the firefighting mission (issue 15): simulated seconds per wall second.

1. **mission-office** (3 robots, thermal frames at 9 Hz per robot, the loop at 100 Hz):
   the built-in scenario run through ``firefleet.simulate`` for ``OFFICE_S`` simulated
   seconds (the first minutes: exploration, the first detections, the approach to the
   fire). Floor of issue 15: >= 60x real time.
2. The time split of that run: the world stage (fire, heat, smoke, victims, spray on the
   field grid), the range sensors, the thermal rendering, the thermal detector
   (``perception.thermal.detect``), the tactics (planning: knowledge, allocation,
   frontiers) with the navigation controller (A*, DWA) inside it, and the wheel stack
   (control: PID, motors, kinematics, encoders). Each is timed by wrapping the function
   the loop calls (wall clock, ``time.perf_counter``); the rest is the loop's own work.
   Each scenario also gets a row of x real time on the process's CPU time
   (``time.process_time``; informative, no floor): on a shared machine the wall clock
   counts the other processes' work too.

3. **mission-large** (50 robots on floor100, 100 m x 100 m, 10 fires; kept in examples/
   until its claims pass, while mission-office is built in): ``LARGE_S`` simulated
   seconds (the start: 50 first plans out of the lobby, exploration), the same split.
   Floor of issue 15: >= 5x real time.

4. **Memory of mission-large** (``MEMORY_S`` simulated seconds, in runs of their own
   under ``tracemalloc``, not timed): the size of ``result.npz`` and the peak of the
   traced allocations (the run, its metrics and the npz's bytes), with the robots'
   series recorded at 10 Hz (``sim.kinds.mission.ROBOT_RECORD_S``) and, side by side in
   the same run, at every tick as before it (the collisions then measured on the
   recorded poses, as the metric did): the ratios before / after.

Run directly: ``python bench/mission.py``.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # single-threaded BLAS, as bench/run.py sets it
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import contextlib
import dataclasses
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from _harness import Floor, Row, TopicResult

_REPO = Path(__file__).resolve().parent.parent
OFFICE = _REPO / "src" / "firefleet" / "scenarios" / "builtin" / "mission-office.yaml"
"""mission-office, built in."""
OFFICE_S = 60.0
"""Simulated seconds of mission-office per timed run."""
FLOOR_OFFICE_X = 60.0
LARGE = _REPO / "examples" / "missions" / "mission-large.yaml"
"""mission-large, kept in examples/ until its claims pass for seeds 0-4."""
LARGE_S = 30.0
"""Simulated seconds of mission-large per timed run."""
FLOOR_LARGE_X = 5.0
MEMORY_S = 10.0
"""Simulated seconds of mission-large per memory run (result.npz and peak memory)."""
PARTS = (
    ("world", "fire, heat, smoke, victims, spray (world stage)"),
    ("ranging", "range sensors"),
    ("render", "thermal rendering"),
    ("detect", "thermal detection"),
    ("navigation", "navigation (A*, DWA) inside the tactics"),
    ("tactics", "tactics without navigation (planning)"),
    ("drive", "wheel stack (control; in quiet stretches with the odometry)"),
)


@contextlib.contextmanager
def _timed(spent: dict[str, float]) -> Iterator[None]:
    """Wrap the functions the mission's loop calls; their wall time adds up in ``spent``."""
    import firefleet.control.mission as cm
    import firefleet.control.mission._step as cstep
    import firefleet.sim.loop as loop
    import firefleet.sim.sensors as sensors
    from firefleet.sim import _quiet_stretch as stretch
    from firefleet.sim.kinds import _mission_world as mw
    from firefleet.sim.ranging import RangeSensors

    def wrap(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def inner(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[name] = spent.get(name, 0.0) + time.perf_counter() - t0

        return inner

    patches: list[tuple[Any, str, Any]] = [
        (mw.MissionWorld, "step", mw.MissionWorld.step),
        (RangeSensors, "read", RangeSensors.read),
        (sensors, "render_thermal_grid_depth", sensors.render_thermal_grid_depth),
        (mw, "detect", vars(mw)["detect"]),
        (cstep, "navigation_step", vars(cstep)["navigation_step"]),
        (cm, "tactics_step", cm.tactics_step),
        (loop, "drive_step", vars(loop)["drive_step"]),
        (stretch, "stretch_drive", stretch.stretch_drive),  # the loop's quiet stretches
        (stretch, "drive_tick", stretch.drive_tick),  # and its other ticks' wheel steps
    ]
    names = (
        "world",
        "ranging",
        "render",
        "detect",
        "navigation",
        "tactics_all",
        "drive",
        "drive",
        "drive",
    )
    try:
        for (owner, attr, fn), name in zip(patches, names, strict=True):
            setattr(owner, attr, wrap(name, fn))
        yield
    finally:
        for owner, attr, fn in patches:
            setattr(owner, attr, fn)


def measure(name: str | Path, duration_s: float) -> tuple[float, dict[str, float]]:
    """Wall seconds of ``duration_s`` simulated seconds of the built-in ``name``, and the
    split by part (seconds)."""
    import firefleet

    scenario = dataclasses.replace(firefleet.load_scenario(name), duration_s=duration_s)
    spent: dict[str, float] = {}
    with _timed(spent):
        t0, c0 = time.perf_counter(), time.process_time()
        firefleet.simulate(scenario)
        wall_s, cpu_s = time.perf_counter() - t0, time.process_time() - c0
    spent["tactics"] = spent.pop("tactics_all", 0.0) - spent.get("navigation", 0.0)
    spent["loop"] = wall_s - sum(spent.values())
    spent["cpu"] = cpu_s  # this process's CPU time: what a machine of its own would take
    return wall_s, spent


def run(console: Console) -> TopicResult:
    """The rows, the floor and the split table."""
    measure(OFFICE, 2.0)  # compiled kernels loaded, caches warm
    wall_s, spent = measure(OFFICE, OFFICE_S)
    x_real = OFFICE_S / wall_s
    row = Row(
        "mission.office.x_real_time", x_real, "x real time", label="mission-office (3 robots)"
    )
    rows = [row]
    table = Table(title=f"mission-office, {OFFICE_S:g} s simulated in {wall_s:.1f} s")
    for col in ("part", "wall s", "share"):
        table.add_column(col)
    for key, label in (*PARTS, ("loop", "the loop's own work, metrics")):
        t = spent.get(key, 0.0)
        table.add_row(label, f"{t:.2f}", f"{100 * t / wall_s:.0f} %")
        rows.append(Row(f"mission.office.split.{key}_s", t, "s", False, label=label))
    table.add_row("x real time", f"{x_real:.1f}", f">= {FLOOR_OFFICE_X:g} required")
    rows.append(_cpu_row("office", OFFICE_S, spent, "mission-office (3 robots), CPU time"))
    table.add_row("x real time on CPU time", f"{rows[-1].value:.1f}", "(this process's)")
    console.print(table)
    large_rows, large_floor, large_wall_s, large_spent = _large(console)
    memory_rows = _memory_table(console)
    floors = (Floor.on(row, ">=", FLOOR_OFFICE_X), large_floor)
    return TopicResult(
        tuple(rows + large_rows + memory_rows),
        floors,
        {
            "office_wall_s": wall_s,
            "split_s": spent,
            "large_wall_s": large_wall_s,
            "large_split_s": large_spent,
        },
    )


def _cpu_row(case: str, simulated_s: float, spent: dict[str, float], label: str) -> Row:
    """Simulated seconds per second of this process's CPU time: the figure a machine of
    its own would give (the wall clock of a shared machine counts the others' work)."""
    return Row(
        f"mission.{case}.x_real_time_cpu", simulated_s / spent["cpu"], "x real time", label=label
    )


def _large(console: Console) -> tuple[list[Row], Floor, float, dict[str, float]]:
    """mission-large's row, its floor and its split table."""
    wall_s, spent = measure(LARGE, LARGE_S)
    x_real = LARGE_S / wall_s
    row = Row("mission.large.x_real_time", x_real, "x real time", label="mission-large (50 robots)")
    rows = [row]
    table = Table(title=f"mission-large, {LARGE_S:g} s simulated in {wall_s:.1f} s")
    for col in ("part", "wall s", "share"):
        table.add_column(col)
    for key, label in (*PARTS, ("loop", "the loop's own work, start-up")):
        t = spent.get(key, 0.0)
        table.add_row(label, f"{t:.2f}", f"{100 * t / wall_s:.0f} %")
        rows.append(Row(f"mission.large.split.{key}_s", t, "s", False, label=label))
    table.add_row("x real time", f"{x_real:.2f}", f">= {FLOOR_LARGE_X:g} required")
    rows.append(_cpu_row("large", LARGE_S, spent, "mission-large (50 robots), CPU time"))
    table.add_row("x real time on CPU time", f"{rows[-1].value:.2f}", "(this process's)")
    console.print(table)
    return rows, Floor.on(row, ">=", FLOOR_LARGE_X), wall_s, spent


def memory(name: str | Path, duration_s: float, every_tick: bool) -> tuple[int, int, int]:
    """Bytes of ``result.npz``, the peak of the traced allocations [bytes] of
    ``duration_s`` simulated seconds of ``name``, its metrics and its npz, and the bytes
    of the robots' recorded series (the arrays with one row per recorded tick);
    ``every_tick``: the robots recorded at every tick and the collisions measured on
    those poses (as before ``ROBOT_RECORD_S``)."""
    import tracemalloc

    import firefleet
    from firefleet.sim.kinds.mission import _command, _grid, _touching
    from firefleet.sim.registry import TaskKind, task_kind

    scenario = dataclasses.replace(firefleet.load_scenario(name), duration_s=duration_s)
    kind = task_kind("mission")
    every = np.arange(scenario.n_steps + 1)
    tracemalloc.start()
    try:
        if every_tick:  # the kind's base run: no thinning of the recorded ticks
            result = TaskKind.run(kind, scenario, every)
            radius = _command(scenario).robot_radius_m
            _touching(_grid(scenario), result.pose[:, :, :2], radius)
        else:
            result = kind.run(scenario, every)
        kind.metrics(result)
        size = len(result.to_npz_bytes())
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    ticks = len(result.t)
    robots = sum(
        np.asarray(a).nbytes for a in result.arrays().values() if np.shape(a)[:1] == (ticks,)
    )
    return size, peak, robots


def _memory_table(console: Console) -> list[Row]:
    """mission-large's result.npz and peak memory, every tick vs 10 Hz, in one run."""
    mb = 1e-6
    memory(LARGE, 1.0, every_tick=False)  # maps, caches, kernels loaded: not in a peak
    before = memory(LARGE, MEMORY_S, every_tick=True)
    after = memory(LARGE, MEMORY_S, every_tick=False)
    per_min = 60.0 / MEMORY_S
    table = Table(title=f"mission-large memory, {MEMORY_S:g} s simulated")
    for col in ("", "robots every tick", "robots at 10 Hz", "before / after"):
        table.add_column(col)
    rows: list[Row] = []
    for i, (key, label) in enumerate((("npz", "result.npz"), ("peak", "peak memory"))):
        table.add_row(
            f"{label}, MB",
            f"{before[i] * mb:.1f}",
            f"{after[i] * mb:.1f}",
            f"{before[i] / after[i]:.1f}",
        )
        if key == "npz":  # the file grows with the run; the peak has a fixed part
            table.add_row(
                f"{label}, MB per simulated minute",
                f"{before[i] * mb * per_min:.0f}",
                f"{after[i] * mb * per_min:.0f}",
                "",
            )
    # what grows with the run in memory: the recorded robot series (held by the loop's
    # recorder, the result and the npz's buffers while it is written)
    table.add_row(
        "robots' series in memory, MB per simulated minute",
        f"{before[2] * mb * per_min:.0f}",
        f"{after[2] * mb * per_min:.1f}",
        f"{before[2] / after[2]:.1f}",
    )
    for case, value in (("every_tick", before[2]), ("ten_hz", after[2])):
        rows.append(
            Row(
                f"mission.large.robot_series_mb_per_min.{case}",
                value * mb * per_min,
                "MB",
                False,
                kind="memory",
                label=f"mission-large, robots' series per simulated minute, robots {case}",
            )
        )
        for case, value in (("every_tick", before[i]), ("ten_hz", after[i])):
            rows.append(
                Row(
                    f"mission.large.{key}_mb.{case}",
                    value * mb,
                    "MB",
                    False,
                    kind="memory",
                    label=f"mission-large {MEMORY_S:g} s, {label}, robots {case}",
                )
            )
    console.print(table)
    return rows


if __name__ == "__main__":
    run(Console())
