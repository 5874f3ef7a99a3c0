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
            d = np.hypot(dx, dy)
            # the whole person (half width + half a cell) in the frame, from the nearest
            # range on
            half = p.hfov_rad / 2 - np.arctan((p.person_half_width_m + 0.125) / np.maximum(d, 1e-9))
            cand = np.flatnonzero(
                ~seen_any & (d <= p.sensing_range_m) & (d >= p.sensing_near_m) & (off <= half)
            )
            if len(cand):
                ok = sight(grid, np.broadcast_to(q[:2], (len(cand), 2)), pts[cand])
                seen_any[cand[ok]] = True
    return float(seen_any.mean())


def test_three_robots_cover_the_office() -> None:
    """3 robots from the west end of the corridor cover >= 95 % of the office's floor in
    360 s, and no two explorers ever head for the same frontier (the coverage counts
    only where the detector would name a person: 2 m and farther, the whole person in
    the frame; with the camera's whole cone from 0 m it took 150 s)."""
    world = World(
        load_map("office"),
        TacticsParams(nav=FAST_NAV),
        np.array([[1.0, 4.6, 0.0], [1.0, 5.0, 0.0], [1.0, 5.4, 0.0]]),
    )
    shared = 0
    for _ in range(3600):
        world.step()
        s = world.state
        ex = np.flatnonzero((s.mode == EXPLORE) & (s.explore_cell[:, 0] >= 0))
        cells = {tuple(c) for c in s.explore_cell[ex].tolist()}
        shared += len(cells) != len(ex)
        if s.explored_frac >= 0.96:
            break
    assert shared == 0
    assert world.state.explored_frac >= 0.95, world.state.explored_frac
    assert world.t_s <= 360.0
    # the cells the team believes covered, checked against the harness's own cones
    assert independent_coverage(world) >= 0.93
    # robots never inside a wall
    poses = np.array([e["pose"] for e in world.log]).reshape(-1, 3)
    assert not world.grid.occupied_at(poses[:, :2]).any()


def test_explorers_keep_away_from_a_known_fire() -> None:
    """No explorer's viewpoint lies within explore_fire_m of a burning spot (its hot gas
    damages robots): looking at the floor by a fire, the viewpoint is chosen outside,
    where without the keep-out it is the nearest cell, beside the fire; in a run, no
    explorer's goal set after the fire is known lies that near it."""
    from firefleet.control.mission._coverage import viewpoints
    from firefleet.control.mission._step import _near_fire

    fire = np.array([[8.0, 5.0]])
    start = np.array([[1.5, 4.5, 0.0], [1.5, 5.5, 0.0], [1.5, 6.5, 0.0]])
    p = TacticsParams(nav=FAST_NAV, fire_robots_min=1, fire_robots_max=1, sensing_range_m=4.0)
    world = World(room(), p, start, fire_xy=fire, water_l=1e9)
    cm = world.state.coarse
    hot = _near_fire(cm, fire, 3.0)
    target = cm.cell_of(np.array([[9.0, 5.0]]))  # the floor just past the fire
    covered = np.zeros(cm.shape, bool)
    for avoid, far in ((hot, True), (None, False)):
        v = viewpoints(cm, covered, target, 0.75, 2.25, 3.0, toward=target, avoid=avoid)
        d = float(np.hypot(*(cm.goal_xy(v)[0] - fire[0])))
        assert (d > 3.0 - 0.2) == far, d
    known_s = np.inf
    for _ in range(250):
        before = world.state.goal_xy_m.copy()
        world.step()
        s = world.state
        if len(s.knowledge.spot_xy_m):
            known_s = min(known_s, world.t_s)
        new = (s.mode == EXPLORE) & np.isfinite(s.goal_xy_m[:, 0])
        new &= ~np.all(np.isclose(before, s.goal_xy_m), axis=1)
        if world.t_s > known_s and new.any() and len(s.knowledge.spot_xy_m):
            g = s.goal_xy_m[new]
            d = np.hypot(
                g[:, None, 0] - s.knowledge.spot_xy_m[None, :, 0],
                g[:, None, 1] - s.knowledge.spot_xy_m[None, :, 1],
            )
            assert d.min() > 3.0 - 0.25
    assert np.isfinite(known_s)
