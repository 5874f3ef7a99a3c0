"""Cost of one tactics_step per tick, the team's brain alone (by hand; not one of
``bench/run.py``'s topics: ``bench/mission.py`` times the whole mission).

``PYTHONPATH=src python bench/mission_step.py ROBOTS MAP [--light] [--nav-s S]
[--plan-cell M] [--res R] [--seconds T]``: MAP is ``office`` (3 robots from the corridor's
west end) or ``big`` (100 m x 100 m of 10 m rooms with 1 m doors at resolution R, robots
one per room); robots obey (v, omega) exactly, no detections; thermal frames every 11th
tick of 10 ms. Prints the mean wall time of ``tactics_step`` per tick and the real-time
factor of the team's brain alone.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from firefleet.control.mission import TacticsObservation, TacticsParams, tactics_init, tactics_step
from firefleet.control.navigation import DwaParams, NavigationParams
from firefleet.models import unicycle_step
from firefleet.world import OccupancyGrid, load_map


def rooms(res: float, size_m: float = 100.0, room_m: float = 10.0) -> OccupancyGrid:
    n, k, door = round(size_m / res), round(room_m / res), round(1.0 / res)
    occ = np.zeros((n, n), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    for i in range(k, n - 1, k):
        occ[i : i + 2, :] = True
        occ[:, i : i + 2] = True
    for i in range(k, n - 1, k):
        for j in range(0, n - 1, k):
            occ[i : i + 2, j + k // 2 - door // 2 : j + k // 2 + door // 2] = False
            occ[j + k // 2 - door // 2 : j + k // 2 + door // 2, i : i + 2] = False
    return OccupancyGrid(occ, ~occ, res, name="rooms")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("robots", type=int)
    ap.add_argument("map", choices=["office", "big"])
    ap.add_argument("--light", action="store_true", help="DwaParams(n_v=5, n_omega=9, n_steps=8)")
    ap.add_argument("--nav-s", type=float, default=0.1)
    ap.add_argument("--plan-cell", type=float, default=0.25)
    ap.add_argument("--res", type=float, default=0.1)
    ap.add_argument("--seconds", type=float, default=30.0)
    a = ap.parse_args()
    n = a.robots
    if a.map == "office":
        grid = load_map("office")
        pose = np.array([[1.0, 4.6 + 0.4 * (i % 3), 0.0] for i in range(n)])
    else:
        grid = rooms(a.res)
        idx = np.arange(n)
        pose = np.stack([5.0 + 10.0 * (idx % 10), 6.0 + 10.0 * (idx // 10), np.zeros(n)], 1)
    nav = (
        NavigationParams(dwa=DwaParams(n_v=5, n_omega=9, n_steps=8))
        if a.light
        else NavigationParams()
    )
    params = TacticsParams(nav=nav, nav_period_s=a.nav_s, plan_cell_m=a.plan_cell)
    state = tactics_init(grid, pose, params)
    none2, none = np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    ticks = round(a.seconds / 0.01)
    spent = 0.0
    for k in range(ticks):
        obs = TacticsObservation(
            k * 0.01, pose, none2, none, none2, none, {}, np.full(n, params.tank_l),
            np.zeros(n, bool), np.ones(n, bool), looked=np.full(n, k % 11 == 0),
        )  # fmt: skip
        t0 = time.perf_counter()
        state, orders = tactics_step(state, obs, params, 0.01)
        spent += time.perf_counter() - t0
        pose = unicycle_step(pose, orders.v_m_s, orders.omega_rad_s, 0.01)
    print(
        f"{a.map} N={n} light={a.light} nav {a.nav_s} s: {1e3 * spent / ticks:.3f} ms/tick, "
        f"{a.seconds / spent:.1f}x real time, explored {state.explored_frac:.2f}"
    )


if __name__ == "__main__":
    main()
