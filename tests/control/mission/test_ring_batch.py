"""The ring's turns tested in one pass (``_ring._valid`` with blocks, ``lines_of_sight``)
give the answers of the calls made one turn at a time before, bit for bit."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import (
    CoarseMap,
    coarse_map,
    line_of_sight,
    lines_of_sight,
)
from firefleet.control.mission._ring import _fix, _valid, regular_ring, ring_slots
from firefleet.control.navigation import Costmap, build_costmap
from firefleet.planning.allocation import allocate_tasks
from firefleet.world import load_map
from tests.control.mission.test_ring import two_rooms


def test_lines_of_sight_of_groups_equal_one_call_per_group() -> None:
    """Groups of segments of very different lengths (each group's sample count is its
    own longest line's), in any order of the groups, empty groups among them."""
    grid = load_map("office")
    cm = coarse_map(build_costmap(grid, 0.2), 0.25)
    rng = np.random.default_rng(9)
    x0, x1, y0, y1 = grid.extent_m
    m = 900
    a = np.c_[rng.uniform(x0, x1, m), rng.uniform(y0, y1, m)]
    group = rng.integers(0, 40, m)
    scale = rng.choice([0.2, 1.0, 4.0, 12.0], 40)  # each group's lengths
    b = a + rng.normal(0.0, 1.0, (m, 2)) * scale[group][:, None]
    got = lines_of_sight(cm, a, b, group, 41)  # group 40 has no pair
    want = np.empty(m, dtype=bool)
    for g in range(41):
        sel = group == g
        want[sel] = line_of_sight(cm, a[sel], b[sel])
    np.testing.assert_array_equal(got, want)
    assert 0.1 < want.mean() < 0.9
    # one group: line_of_sight itself
    np.testing.assert_array_equal(
        lines_of_sight(cm, a, b, np.zeros(m, np.int64), 1), line_of_sight(cm, a, b)
    )
    assert lines_of_sight(cm, a[:0], b[:0], group[:0], 3).shape == (0,)


def _ring_slots_before(
    cm: CoarseMap,
    costmap: Costmap,
    c: np.ndarray,
    radius_m: float,
    robots: np.ndarray,
    spots: np.ndarray,
    reach: np.ndarray,
    near_m: float,
    shot_m: float,
    gap_m: float,
    avoid: np.ndarray,
    avoid_m: float,
    clear: np.ndarray,
) -> np.ndarray:
    """ring_slots as it was: one call of _valid per turn of the polygon (the reference)."""

    def valid(pts: np.ndarray) -> np.ndarray:
        return _valid(cm, costmap, reach, spots, near_m, shot_m, pts, avoid, avoid_m, clear)

    m = len(robots)
    ring = regular_ring(c, radius_m, robots)
    d = ring - c
    base = np.arctan2(d[:, 1], d[:, 0])
    best, best_score = ring, -1.0
    step = math.radians(5.0)
    period = 2 * math.pi / m
    for k in range(max(1, round(period / step))):
        delta = k * step
        delta = delta if delta <= period / 2 else delta - period
        ang = base + delta
        pts = c + radius_m * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        score = valid(pts).sum() - abs(delta) * 1e-3
        if score > best_score:
            best, best_score = pts, score
    slots = best.copy()
    bad = ~valid(slots)
    lo = costmap.inflation_m + 0.2
    _fix(slots, bad, c, radius_m, lo, valid, cm, spots, near_m, shot_m, gap_m)
    if bad.any() and len(avoid):

        def valid_near_hot(pts: np.ndarray) -> np.ndarray:
            return _valid(cm, costmap, reach, spots, near_m, shot_m, pts, avoid[:0], 0.0, clear)

        _fix(slots, bad, c, radius_m, lo, valid_near_hot, cm, spots, near_m, shot_m, gap_m)
    cost = np.hypot(robots[:, None, 0] - slots[None, :, 0], robots[:, None, 1] - slots[None, :, 1])
    out: np.ndarray = slots[allocate_tasks(cost)]
    return out


def test_ring_slots_equal_the_turn_by_turn_form() -> None:
    """Fires in the office and behind a door, 1-4 robots, with hot places and soaked
    flames to keep clear of: the same slots to the last bit."""
    rng = np.random.default_rng(21)
    cases = 0
    for grid in (load_map("office"), two_rooms()):
        costmap = build_costmap(grid, 0.2)
        cm = coarse_map(costmap, 0.25)
        reach = ~np.asarray(costmap.blocked)
        x0, x1, y0, y1 = grid.extent_m
        for _ in range(12):
            centre = rng.uniform([x0 + 1, y0 + 1], [x1 - 1, y1 - 1])
            spots = centre + rng.normal(0.0, 0.4, (int(rng.integers(1, 5)), 2))
            robots = rng.uniform(
                [x0 + 0.5, y0 + 0.5], [x1 - 0.5, y1 - 0.5], (int(rng.integers(1, 5)), 2)
            )
            avoid = centre + rng.normal(0.0, 1.5, (int(rng.integers(0, 3)), 2))
            clear = centre + rng.normal(0.0, 0.5, (int(rng.integers(0, 2)), 2))
            radius = float(rng.uniform(1.0, 2.5))
            near, shot, gap, avoid_m = 0.6, radius + 0.5, 0.5, 0.8
            got = ring_slots(
                cm, costmap, spots.mean(axis=0), radius, robots, spots_xy_m=spots,
                reachable=reach, near_m=near, shot_m=shot, gap_m=gap, avoid_xy_m=avoid,
                avoid_m=avoid_m, clear_xy_m=clear,
            )  # fmt: skip
            want = _ring_slots_before(
                cm, costmap, spots.mean(axis=0), radius, robots, spots, reach, near, shot,
                gap, avoid, avoid_m, clear,
            )  # fmt: skip
            assert got.tobytes() == want.tobytes()
            cases += 1
    assert cases == 24
