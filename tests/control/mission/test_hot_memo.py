"""The retreats kept in the map's cache (``_hot.retreat_point``): each answer equals the
one computed anew (``_hot._retreat``, the search itself) bit for bit, also when asked
again, after the cache dropped it, and for points that differ in the last bit."""

from __future__ import annotations

import numpy as np
import pytest

import firefleet.control.mission._hot as hot
from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid

CELL_M = 0.25


def _cm() -> CoarseMap:
    """The two rooms of test_hot's plan: a wall with a door, a pillar."""
    occ = np.zeros((12, 24), dtype=bool)
    occ[0] = occ[-1] = True
    occ[:, 0] = occ[:, -1] = True
    occ[:, 12] = True
    occ[6:8, 12] = False
    occ[3:5, 17:19] = True
    return coarse_map(build_costmap(OccupancyGrid(occ, ~occ, resolution_m=CELL_M), 0.1), CELL_M)


def _fresh(
    cm: CoarseMap, xy: np.ndarray, away: np.ndarray, clear_m: float, limit_m: float
) -> np.ndarray:
    node = int(cm.node_of(xy.reshape(1, 2))[0])
    return np.array(hot._retreat(cm, node, away.reshape(-1, 2), clear_m, limit_m))


def _cases(
    rng: np.random.Generator, cm: CoarseMap
) -> list[tuple[np.ndarray, np.ndarray, float, float]]:
    free = cm.goal_xy(np.argwhere(cm.standable))
    out = []
    for _ in range(30):
        xy = free[rng.integers(len(free))] + rng.uniform(-0.1, 0.1, 2)
        away = rng.uniform([0.0, 0.0], [6.0, 3.0], size=(int(rng.integers(0, 6)), 2))
        out.append((xy, away, float(rng.uniform(0.5, 2.0)), float(rng.choice([1.0, 8.0]))))
    # edges: nothing to avoid, every cell in reach too hot (NaN), a point on the robot
    out.append((free[3], np.zeros((0, 2)), 1.0, 8.0))
    out.append((free[3], free[3][None], 3.0, 1.0))
    return out


@pytest.mark.parametrize("kept", [16, 2])
def test_kept_retreats_equal_the_search(monkeypatch: pytest.MonkeyPatch, kept: int) -> None:
    monkeypatch.setattr(hot, "_RETREAT_KEPT", kept)
    cm = _cm()
    cases = _cases(np.random.default_rng(3), cm)
    # each case asked twice in a row, then the whole list again (with room for two,
    # most were dropped by then)
    for xy, away, clear_m, limit_m in [c for c in cases for _ in range(2)] + cases:
        got = hot.retreat_point(cm, xy, away, clear_m, limit_m)
        ref = _fresh(cm, xy, away, clear_m, limit_m)
        assert got.tobytes() == ref.tobytes()
        memo = cm.cache[("retreat",)]
        assert isinstance(memo, dict)
        assert len(memo) <= kept
    assert any(np.isnan(hot.retreat_point(cm, *c)).all() for c in cases)


def test_a_kept_retreat_is_a_copy_and_a_changed_point_is_searched_anew() -> None:
    cm = _cm()
    xy = np.array([2.875, 2.375])
    away = np.array([[x, y] for x in (1.0, 2.5) for y in (0.5, 1.5, 2.5)])
    first = hot.retreat_point(cm, xy, away, 1.0)
    kept = first.copy()
    first[:] = -1.0  # the caller's array: the cache keeps its own
    assert hot.retreat_point(cm, xy, away, 1.0).tobytes() == kept.tobytes()
    # a hot place moved by the last bit: a new key (never an old answer for new points)
    moved = away.copy()
    moved[0, 0] = np.nextafter(moved[0, 0], 10.0)
    memo = cm.cache[("retreat",)]
    assert isinstance(memo, dict)
    before = len(memo)
    got = hot.retreat_point(cm, xy, moved, 1.0)
    assert len(memo) == before + 1
    assert got.tobytes() == _fresh(cm, xy, moved, 1.0, 8.0).tobytes()
    # another clearance or limit: new keys too
    for clear_m, limit_m in ((1.5, 8.0), (1.0, 2.0)):
        got = hot.retreat_point(cm, xy, away, clear_m, limit_m)
        assert got.tobytes() == _fresh(cm, xy, away, clear_m, limit_m).tobytes()
    assert len(memo) == before + 3
