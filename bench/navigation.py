"""Benchmark of the global planner: A* on a 1,000 x 1,000 random-room map.

``run(console)`` measures, prints a rich table with PASS/FAIL for issue 14's floor
("A* on a 1,000 x 1,000 grid: < 100 ms") and returns a :class:`_harness.TopicResult`.
Run directly: ``python bench/navigation.py``.

The map: 50 m x 50 m at 5 cm, a 10 x 10 grid of 5 m rooms whose walls (10 cm) each have
a 1 m door at a random place (seeded), so a path from the lower-left room to the
upper-right one winds through doors. Robot radius + margin 0.2 m.

Rows:

1. ``astar_ms``: :func:`firefleet.control.navigation.astar` on the prepared costmap
   (best of 7 wall times; the floor), its CPU time (``time.process_time``, best of 7:
   near the wall time on an idle core, steady on a shared machine), ``costmap_ms``
   (inflation and wall cost: done once per map) and ``smooth_ms`` (shortcutting +
   corner arcs of that path).
2. Peer: scikit-image's ``graph.route_through_array`` (minimum-cost path, 8-connected,
   ``geometric=True``: the same edge cost, step length x mean of the two cells' costs)
   on the same cost grid, timed interleaved with ours, as a ratio. skimage allows the
   diagonal corner cuts ours forbids, so its cost can only be lower or equal; both
   costs are reported. (PythonRobotics' ``a_star.py`` builds its obstacle map by a
   Python loop over every cell and every obstacle point, hours on this map: not run.)
"""

from __future__ import annotations

import os

if __name__ == "__main__":
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import time
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

import _harness as h
from firefleet.control.navigation import astar, build_costmap, smooth_path
from firefleet.world import OccupancyGrid

SIZE = 1000
RESOLUTION_M = 0.05
ROOM_CELLS = 100
DOOR_CELLS = 20
INFLATION_M = 0.2
REPEATS = 7


def random_rooms(seed: int = 0) -> OccupancyGrid:
    """The benchmark map (see the module docstring)."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((SIZE, SIZE), dtype=bool)
    for k in range(0, SIZE + 1, ROOM_CELLS):
        a = min(k, SIZE - 2)
        occ[a : a + 2, :] = True
        occ[:, a : a + 2] = True
    rooms = SIZE // ROOM_CELLS
    for i in range(rooms):
        for j in range(rooms):
            r0, c0 = i * ROOM_CELLS, j * ROOM_CELLS
            if j + 1 < rooms:  # a door in the wall to the right
                d = r0 + int(rng.integers(10, ROOM_CELLS - DOOR_CELLS - 10))
                occ[d : d + DOOR_CELLS, c0 + ROOM_CELLS : c0 + ROOM_CELLS + 2] = False
            if i + 1 < rooms:  # a door in the wall below
                d = c0 + int(rng.integers(10, ROOM_CELLS - DOOR_CELLS - 10))
                occ[r0 + ROOM_CELLS : r0 + ROOM_CELLS + 2, d : d + DOOR_CELLS] = False
    return OccupancyGrid(occ, ~occ, RESOLUTION_M, name="random-rooms")


def run(console: Console) -> h.TopicResult:
    """Measure, print, return the rows and the floor."""
    grid = random_rooms()
    start = np.array([2.5, 2.5])  # the lower-left room's centre
    goal = np.array([47.5, 47.5])  # the upper-right room's
    t0 = time.perf_counter()
    costmap = build_costmap(grid, INFLATION_M)
    build_once = time.perf_counter() - t0
    build = h.best_of(lambda: build_costmap(grid, INFLATION_M), 3, warmup=0)
    result = astar(costmap, start, goal)
    if not result.found or result.xy_m is None:
        raise RuntimeError(f"the benchmark map has no path: {result.status}")
    xy = result.xy_m
    smooth = h.best_of(lambda: smooth_path(costmap, xy), 3)
    path = smooth_path(costmap, xy)

    from skimage.graph import route_through_array

    peer_cost = np.where(np.isfinite(costmap.cost), costmap.cost, -1.0)
    rc = grid.cell_of(np.stack([start, goal]))
    s_cell, g_cell = (int(rc[0, 0]), int(rc[0, 1])), (int(rc[1, 0]), int(rc[1, 1]))

    def peer() -> float:
        _, total = route_through_array(  # type: ignore[no-untyped-call]
            peer_cost, s_cell, g_cell, fully_connected=True, geometric=True
        )
        return float(total)

    peer_total = peer()
    timings = h.best_of_interleaved(
        {"ours": lambda: astar(costmap, start, goal), "skimage": peer}, REPEATS
    )
    cpu = []
    for _ in range(REPEATS):  # CPU time: what the search costs when it has a core to itself
        c0 = time.process_time()
        astar(costmap, start, goal)
        cpu.append(time.process_time() - c0)
    cpu_s = min(cpu)
    ours_s = timings["ours"].best_s
    peer_s = timings["skimage"].best_s
    rows = (
        h.Row("navigation.astar_1000x1000.ms", 1e3 * ours_s, "ms", False, label="A* 1,000 x 1,000"),
        h.Row(
            "navigation.astar_1000x1000.cpu_ms",
            1e3 * cpu_s,
            "ms",
            False,
            label="A* 1,000 x 1,000 (CPU time)",
        ),
        h.Row(
            "navigation.astar_1000x1000.speedup_vs_skimage",
            peer_s / ours_s,
            "x",
            label="A* vs skimage route_through_array",
        ),
        h.Row(
            "navigation.costmap_1000x1000.ms",
            1e3 * build.best_s,
            "ms",
            False,
            label="inflation + wall cost",
        ),
        h.Row("navigation.smooth.ms", 1e3 * smooth.best_s, "ms", False, label="smoothing"),
    )
    floors = (h.Floor.on(rows[0], "<", 100.0, "issue 14: A* on 1,000 x 1,000 < 100 ms"),)
    table = Table(title="A* on a 1,000 x 1,000 random-room map (50 m at 5 cm)")
    for col in ("what", "value", "note"):
        table.add_column(col)
    table.add_row("A* (ours, compiled)", f"{1e3 * ours_s:.1f} ms", f"cost {result.cost:.3f}")
    table.add_row("A* (ours), CPU time", f"{1e3 * cpu_s:.1f} ms", "the process's own time")
    table.add_row(
        "skimage route_through_array",
        f"{1e3 * peer_s:.1f} ms",
        f"cost {peer_total * RESOLUTION_M:.3f} (corner cuts allowed)",
    )
    table.add_row("ratio (skimage / ours)", f"{peer_s / ours_s:.1f} x", "")
    table.add_row("costmap (EDT + cost)", f"{1e3 * build.best_s:.1f} ms", "once per map")
    table.add_row(
        "smoothing", f"{1e3 * smooth.best_s:.1f} ms", f"{path.length_m:.2f} m, A* cells {len(xy)}"
    )
    for f in floors:
        table.add_row(f.name, f"{f.measured:.1f} {f.unit}", "PASS" if f.passed else "FAIL")
    console.print(table)
    details: dict[str, Any] = {
        "astar": timings["ours"].to_dict(),
        "skimage": timings["skimage"].to_dict(),
        "astar_cost": result.cost,
        "skimage_cost": peer_total * RESOLUTION_M,
        "path_cells": len(xy),
        "smoothed_length_m": path.length_m,
        "costmap_first_call_s": build_once,
    }
    return h.TopicResult(rows, floors, details)


if __name__ == "__main__":
    run(Console())
