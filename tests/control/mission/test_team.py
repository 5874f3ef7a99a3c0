"""The team in the small kinematic world of ``_harness`` (robots obey v, omega exactly;
detections are the truth within range, in the cone, in line of sight)."""

from __future__ import annotations

import numpy as np

from firefleet.control.mission import MODES, TacticsParams
from firefleet.control.navigation import DwaParams, NavigationParams
from firefleet.world import OccupancyGrid, load_map
from tests.control.mission._harness import World, sight

FAST_NAV = NavigationParams(dwa=DwaParams(n_v=5, n_omega=9, n_steps=8))
"""A coarser dynamic window than the default: the same controller, five times cheaper."""

FIGHT, REFILL, DAMAGED, EXPLORE = (
    MODES.index(m) for m in ("fight", "refill", "damaged", "explore")
)


def room(width_m: float = 12.0, height_m: float = 10.0, res: float = 0.05) -> OccupancyGrid:
    h, w = round(height_m / res), round(width_m / res)
    occ = np.zeros((h, w), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    return OccupancyGrid(occ, ~occ, res, name="room")


def independent_coverage(world: World, every: int = 5) -> float:
    """Free points every 0.25 m that some logged pose's cone saw (the harness's own line
    of sight on the map's fine cells), over all free points."""
    grid, p = world.grid, world.params
    ys, xs = np.mgrid[0.125 : grid.height_m : 0.25, 0.125 : grid.width_m : 0.25]
    pts = np.stack([xs.ravel(), ys.ravel()], 1)
    pts = pts[~grid.occupied_at(pts)]
    seen_any = np.zeros(len(pts), bool)
    for entry in world.log[::every]:
        for q in entry["pose"]:
            dx, dy = pts[:, 0] - q[0], pts[:, 1] - q[1]
            off = np.abs((np.arctan2(dy, dx) - q[2] + np.pi) % (2 * np.pi) - np.pi)
            cand = np.flatnonzero(
                ~seen_any & (np.hypot(dx, dy) <= p.sensing_range_m) & (off <= p.hfov_rad / 2)
            )
            if len(cand):
                ok = sight(grid, np.broadcast_to(q[:2], (len(cand), 2)), pts[cand])
                seen_any[cand[ok]] = True
    return float(seen_any.mean())


def test_three_robots_cover_the_office() -> None:
    """3 robots from the west end of the corridor cover >= 95 % of the office's floor in
    150 s, and no two explorers ever head for the same frontier."""
    world = World(
        load_map("office"),
        TacticsParams(nav=FAST_NAV),
        np.array([[1.0, 4.6, 0.0], [1.0, 5.0, 0.0], [1.0, 5.4, 0.0]]),
    )
    shared = 0
    for _ in range(1500):
        world.step()
        s = world.state
        ex = np.flatnonzero((s.mode == EXPLORE) & (s.explore_cell[:, 0] >= 0))
        cells = {tuple(c) for c in s.explore_cell[ex].tolist()}
        shared += len(cells) != len(ex)
        if s.explored_frac >= 0.96:
            break
    assert shared == 0
    assert world.state.explored_frac >= 0.95, world.state.explored_frac
    assert world.t_s <= 150.0
    # the cells the team believes covered, checked against the harness's own cones
    assert independent_coverage(world) >= 0.93
    # robots never inside a wall
    poses = np.array([e["pose"] for e in world.log]).reshape(-1, 3)
    assert not world.grid.occupied_at(poses[:, :2]).any()
