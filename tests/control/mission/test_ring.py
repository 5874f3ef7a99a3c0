"""The fighters' slots: a shot at a burning spot from a reachable, open place."""

from __future__ import annotations

import numpy as np

from firefleet.control.mission._coverage import coarse_map
from firefleet.control.mission._ring import has_shot, ring_slots
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid
from tests.control.mission._harness import sight


def two_rooms() -> OccupancyGrid:
    """12 m x 8 m, a wall at x = 6 m (cells 120-121) with a 1 m door at y in [3.5, 4.5]."""
    res = 0.05
    occ = np.zeros((160, 240), bool)
    occ[:2] = occ[-2:] = True
    occ[:, :2] = occ[:, -2:] = True
    occ[:, 120:122] = True
    occ[70:90, 120:122] = False  # rows 70-89: y from 8 - 4.5 to 8 - 3.5
    return OccupancyGrid(occ, ~occ, res, name="two-rooms")


def test_has_shot_is_distance_and_sight() -> None:
    """Against brute force: a spot at a distance in [near, reach] with a clear segment
    (the harness's fine-cell line of sight)."""
    grid = two_rooms()
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    rng = np.random.default_rng(3)
    pts = rng.uniform([0.6, 0.6], [11.4, 7.4], (300, 2))
    pts = pts[np.abs(pts[:, 0] - 6.05) > 0.6]  # no end within a cell of the wall
    spots = np.array([[8.0, 4.0], [9.5, 2.0]])
    near, reach = 1.0, 3.0
    got = has_shot(cm, pts, spots, near, reach)
    want = np.zeros(len(pts), bool)
    for s in spots:
        d = np.hypot(*(pts - s).T)
        ok = (d >= near) & (d <= reach)
        ok[ok] &= sight(grid, pts[ok], np.broadcast_to(s, (int(ok.sum()), 2)))
        want |= ok
    assert want.sum() > 20
    assert (~want).sum() > 20
    assert np.mean(got == want) >= 0.97, np.mean(got == want)  # coarse vs fine cells


def test_slots_of_a_fire_behind_a_door_are_reachable_and_have_a_shot() -> None:
    """A fire in the east room; the robots in the west room, the east room unreachable
    (as when burning spots block its door): every slot lies in the west room, open,
    within reach of a spot in sight, and the slots are at least gap_m apart."""
    grid = two_rooms()
    costmap = build_costmap(grid, 0.2)
    cm = coarse_map(costmap, 0.25)
    reachable = ~np.asarray(costmap.blocked).copy()
    reachable[:, 118:] = False  # x >= 5.9 m
    spots = np.array([[7.0, 4.0], [7.5, 4.3], [7.2, 3.6]])
    centre = spots.mean(axis=0)
    robots = np.array([[2.0, 2.0], [2.0, 4.0], [2.0, 6.0]])
    slots = ring_slots(
        cm,
        costmap,
        centre,
        0.5 + 2.0,
        robots,
        spots_xy_m=spots,
        reachable=reachable,
        near_m=1.0,
        shot_m=3.0,
        gap_m=0.5,
    )
    assert slots.shape == (3, 2)
    assert np.all(slots[:, 0] < 5.9), slots
    rc = grid.cell_of(slots)
    assert not np.asarray(costmap.blocked)[rc[:, 0], rc[:, 1]].any()
    for s in slots:
        d = np.hypot(*(spots - s).T)
        ok = (d >= 1.0) & (d <= 3.0)
        assert ok.any(), s
        assert sight(grid, np.repeat(s[None], ok.sum(), 0), spots[ok]).any(), s
    gaps = np.hypot(*(slots[:, None] - slots[None]).transpose(2, 0, 1))
    assert gaps[np.triu_indices(3, 1)].min() >= 0.5 - 1e-9, gaps
