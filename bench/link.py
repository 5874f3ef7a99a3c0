"""Benchmark: the cost of the in-process link model (issue 16).

Per tick of a 1,000-robot team, the link stage (:class:`firefleet.sim.link.LinkModel`:
queues, the shared channel, each directed pair's loss, range and delay, what every
receiver holds) against one path-following step of the same team (the compiled kernel,
closed-loop coordination over the ideal link, every core, as ``firefleet run`` does it).

Floor (issue 16): with the deliverable's radio (``xbee``: 250 kbit/s, the team
broadcasting at 20 Hz), the link costs less than 20 % of a path-following step. The
other presets are printed beside it: the ``ideal`` preset delivers every broadcast to
all 999 others at every tick (a million pairs a tick) and ``wifi`` carries some 300
frames a tick; their cost is what a link that carries a million messages a second
costs, not a floor.

Best of several runs after an untimed warm-up (which also compiles the kernels).
``python bench/link.py`` runs it alone.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rich.console import Console
from rich.table import Table

import _harness as h
import firefleet
from firefleet.sim.link import PRESETS, LinkModel
from path_following import large_team

N_ROBOTS = 1_000
TICKS = 200
FLOOR_FRACTION = 0.20
"""The link's cost per tick, as a fraction of a path-following step, at 1,000 robots."""


def _step_s(repeats: int) -> float:
    """Best wall time of one path-following tick of the 1,000-robot team [s]."""
    team = large_team(firefleet.load_scenario("coop-different-paths"), N_ROBOTS, 20.0)
    firefleet.simulate(team, record_every=10)  # warm-up, compile
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        firefleet.simulate(team, record_every=10)
        best = min(best, time.perf_counter() - start)
    return best / (team.n_steps + 1)


def _link_s(preset: str, repeats: int, ticks: int) -> tuple[float, float]:
    """Best wall time of one link tick [s] and the frames on the air per tick."""
    rng = np.random.default_rng(0)
    pose = np.zeros((N_ROBOTS, 3))
    pose[:, :2] = rng.uniform(0.0, 30.0, (N_ROBOTS, 2))
    sent = {"zeta": rng.uniform(0, 200, N_ROBOTS), "zeta_rate": np.ones(N_ROBOTS)}
    link = LinkModel(PRESETS[preset], seed=1)
    best, frames = float("inf"), 0.0
    for rep in range(repeats + 1):
        state = link.init(N_ROBOTS, 0.01)
        link.exchange(state, {}, 0.0, pose)
        start = time.perf_counter()
        for k in range(1, ticks + 1):
            link.exchange(state, sent, k * 0.01, pose)
        if rep:  # the first is the warm-up
            best = min(best, (time.perf_counter() - start) / ticks)
        frames = link.counters(state)["frames"] / ticks
    return best, frames


def run(console: Console) -> h.TopicResult:
    """Measure, print the table, return the rows and the floor."""
    step = _step_s(repeats=3)
    costs = {
        "xbee": _link_s("xbee", 3, TICKS),
        "wifi": _link_s("wifi", 2, 20),
        "ideal": _link_s("ideal", 2, 5),
    }
    table = Table(title=f"link model per tick, {N_ROBOTS:,} robots (best of runs)")
    for col in ("stage", "frames/tick", "us/tick", "of a path-following step"):
        table.add_column(col, justify="left" if col == "stage" else "right")
    table.add_row("path-following step (compiled)", "", f"{step * 1e6:,.0f}", "100 %")
    for name, (cost, frames) in costs.items():
        table.add_row(f"link: {name}", f"{frames:.1f}", f"{cost * 1e6:,.0f}", f"{cost / step:.1%}")
    console.print(table)
    rows = [
        h.Row(
            "link.robots1000.path_following_step_us",
            step * 1e6,
            "us",
            False,
            label="path-following step, 1,000 robots",
        ),
        *(
            h.Row(
                f"link.robots1000.{name}.us_per_tick",
                cost * 1e6,
                "us",
                False,
                label=f"link model ({name}) per tick, 1,000 robots",
            )
            for name, (cost, _) in costs.items()
        ),
    ]
    fraction = costs["xbee"][0] / step
    floor = h.Floor(
        "link model (xbee) / path-following step, 1,000 robots",
        fraction * 100.0,
        FLOOR_FRACTION * 100.0,
        "%",
        "<",
    )
    return h.TopicResult(
        rows=tuple(rows),
        floors=(floor,),
        details={
            "step_s": step,
            **{f"{n}_s_per_tick": c for n, (c, _) in costs.items()},
            **{f"{n}_frames_per_tick": f for n, (_, f) in costs.items()},
        },
    )


if __name__ == "__main__":
    result = run(Console())
    sys.exit(0 if all(f.passed for f in result.floors) else 1)
