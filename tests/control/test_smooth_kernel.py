"""The compiled line-of-sight shortcutting keeps the vertices the NumPy one kept (the
reference below is the implementation it replaced), on A* paths through random maps."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.control.navigation import astar, build_costmap
from firefleet.control.navigation._costmap import Costmap
from firefleet.control.navigation._smooth import clearance_along, shortcut
from firefleet.world import OccupancyGrid


def _shortcut_reference(costmap: Costmap, xy_m: np.ndarray) -> np.ndarray:
    xy = np.asarray(xy_m, dtype=float)
    if len(xy) <= 2:
        return xy.copy()
    step = costmap.grid.resolution_m / 4.0
    own = clearance_along(costmap, xy)
    floor = costmap.inflation_m
    kept = [0]
    i = 0
    while i < len(xy) - 1:
        j = i + 1
        lowest = min(own[i], own[j])
        while j + 1 < len(xy):
            lowest_next = min(lowest, own[j + 1])
            need = max(lowest_next, floor)
            a, b = xy[i], xy[j + 1]
            n = max(int(np.ceil(np.hypot(*(b - a)) / step)), 1)
            samples = a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a)
            clear = clearance_along(costmap, samples)
            if np.all(clear[1:-1] >= need - 1e-9) and np.all(clear > floor):
                j += 1
                lowest = lowest_next
            else:
                break
        kept.append(j)
        i = j
    return np.asarray(xy[kept])


@pytest.mark.parametrize("seed", range(6))
def test_shortcut_equals_the_numpy_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    occ = rng.random((60, 80)) < 0.06
    occ[[0, -1], :] = occ[:, [0, -1]] = True
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1, origin_m=(-1.0, 0.5))
    cm = build_costmap(grid, inflation_m=0.15)
    free = np.argwhere(~cm.blocked)
    done = 0
    for _ in range(20):
        a, b = free[rng.integers(len(free), size=2)]
        res = astar(cm, grid.center_of(a), grid.center_of(b))
        if not res.found or res.xy_m is None or len(res.xy_m) < 3:
            continue
        np.testing.assert_array_equal(shortcut(cm, res.xy_m), _shortcut_reference(cm, res.xy_m))
        done += 1
    assert done >= 5


def test_give_way_conflict_equals_numpy() -> None:
    from firefleet.control.navigation._step import _conflict

    rng = np.random.default_rng(1)
    for _ in range(300):
        mine = rng.uniform(0.0, 3.0, (int(rng.integers(1, 12)), 2))
        theirs = rng.uniform(0.0, 3.0, (int(rng.integers(1, 12)), 2))
        me = rng.uniform(0.0, 3.0, 2)
        gap = float(rng.uniform(0.1, 0.8))
        d = np.hypot(mine[:, None, 0] - theirs[None, :, 0], mine[:, None, 1] - theirs[None, :, 1])
        want = (bool(d.min() < gap), bool(np.hypot(*(theirs - me).T).min() < gap))
        assert _conflict(mine, theirs, me, gap) == want


def test_give_way_conflict_skips_only_pairs_hypot_would_reject() -> None:
    """The box test before each hypot (|dx| or |dy| at least the gap): the kernel before
    it (a hypot for every pair, in Python here) on pairs at the gap's edge, axis-aligned
    and not, and with NaN and infinite coordinates."""
    import math

    from firefleet.control.navigation._step import _conflict

    def before(
        mine_a: np.ndarray, theirs_a: np.ndarray, me_a: np.ndarray, gap: float
    ) -> tuple[bool, bool]:
        mine, theirs, me = mine_a.tolist(), theirs_a.tolist(), me_a.tolist()  # floats
        in_way = any(math.hypot(t[0] - me[0], t[1] - me[1]) < gap for t in theirs)
        meets = any(math.hypot(m[0] - t[0], m[1] - t[1]) < gap for m in mine for t in theirs)
        return meets, in_way

    rng = np.random.default_rng(7)
    gap = 0.5
    edge = np.array([np.nextafter(gap, 0.0), gap, np.nextafter(gap, 1.0)])
    checked = set()
    for _ in range(3000):
        mine = rng.uniform(0.0, 1.0, (int(rng.integers(1, 5)), 2))
        theirs = mine[rng.integers(0, len(mine), int(rng.integers(1, 5)))].copy()
        # offsets at the gap's edge along an axis, or a hair off it
        off = rng.choice(edge, (len(theirs), 1)) * rng.choice([-1.0, 1.0], (len(theirs), 2))
        off[:, int(rng.integers(0, 2))] *= rng.choice([0.0, 1e-9, 0.3, 1.0])
        theirs = theirs + off
        if rng.random() < 0.05:
            theirs[int(rng.integers(0, len(theirs))), int(rng.integers(0, 2))] = rng.choice(
                [np.nan, np.inf]
            )
        me = theirs[int(rng.integers(0, len(theirs)))] + rng.choice(edge) * np.array([1.0, 0.0])
        want = before(mine, theirs, me, gap)
        assert _conflict(mine, theirs, me, gap) == want
        checked.add(want)
    assert checked == {(False, False), (False, True), (True, False), (True, True)}


def test_aside_clearance_filter_equals_numpy() -> None:
    from firefleet.control.navigation._makeway import clear_of as _clear_of

    rng = np.random.default_rng(2)
    for _ in range(50):
        xy = rng.uniform(0.0, 6.0, (int(rng.integers(1, 400)), 2))
        pts = rng.uniform(0.0, 6.0, (int(rng.integers(1, 150)), 2))
        limit = float(rng.uniform(0.2, 1.5))
        d = np.hypot(xy[:, None, 0] - pts[None, :, 0], xy[:, None, 1] - pts[None, :, 1])
        np.testing.assert_array_equal(_clear_of(xy, pts, limit), d.min(axis=1) > limit)
