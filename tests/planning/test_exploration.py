"""Frontiers of hand-made maps, and the coordinated choice of targets."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.planning.exploration import assign_frontiers, find_frontiers
from firefleet.planning.geodesic import travel_distance_m


def test_frontiers_of_a_room_explored_from_its_middle() -> None:
    # a 21 x 21 map; the robot has seen a disc of radius 5 cells around the centre,
    # and a wall across the top of the seen disc hides nothing behind it
    r, c = np.mgrid[:21, :21]
    seen = (r - 10) ** 2 + (c - 10) ** 2 <= 25
    wall = seen & (r == 5)
    free = seen & ~wall
    unknown = ~seen
    f = find_frontiers(free, unknown, min_cells=3)
    assert len(f) == 1  # one ring of frontier cells, broken only where the wall meets it
    ring = f.labels > 0
    # every frontier cell is free and touches an unknown cell across an edge
    assert np.all(free[ring])
    touches = np.zeros_like(ring)
    touches[1:] |= unknown[:-1]
    touches[:-1] |= unknown[1:]
    touches[:, 1:] |= unknown[:, :-1]
    touches[:, :-1] |= unknown[:, 1:]
    assert np.array_equal(ring, free & touches)
    assert f.size.tolist() == [int(ring.sum())]


def test_small_frontiers_are_dropped() -> None:
    free = np.zeros((6, 6), dtype=bool)
    free[2:4, 2:4] = True
    unknown = np.zeros_like(free)
    unknown[2, 4] = True  # one unknown cell beside the free block: a frontier of 1 cell
    assert len(find_frontiers(free, unknown, min_cells=1)) == 1
    assert len(find_frontiers(free, unknown, min_cells=2)) == 0
    with pytest.raises(InputError, match="min_cells"):
        find_frontiers(free, unknown, min_cells=0)


def test_coordination_spreads_robots_that_the_nearest_frontier_would_gather() -> None:
    # a corridor map: three robots at its left end, frontiers at 2 m, 12 m and 22 m
    free = np.ones((3, 240), dtype=bool)
    robots = np.array([[1, 0], [1, 1], [1, 2]])
    targets = np.array([[1, 20], [1, 120], [1, 220]])
    dist = travel_distance_m(free, robots, 0.1)[:, targets[:, 0], targets[:, 1]]
    nearest = np.argmin(dist, axis=1)
    assert nearest.tolist() == [0, 0, 0]
    xy = targets[:, ::-1] * 0.1
    chosen = assign_frontiers(dist, xy, sensor_range_m=4.0, beta=0.01)
    assert sorted(chosen.tolist()) == [0, 1, 2]


def test_unreachable_targets_are_never_chosen() -> None:
    dist = np.array([[np.inf, 5.0], [np.inf, np.inf]])
    got = assign_frontiers(dist, [[0.0, 0.0], [10.0, 0.0]], sensor_range_m=3.0)
    assert got.tolist() == [1, -1]
    assert assign_frontiers(np.zeros((2, 0)), np.zeros((0, 2)), sensor_range_m=1.0).tolist() == [
        -1,
        -1,
    ]
    with pytest.raises(InputError, match="robots, 3 targets"):
        assign_frontiers(np.zeros((2, 2)), np.zeros((3, 2)), sensor_range_m=1.0)
