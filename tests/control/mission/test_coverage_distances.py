"""The coarse map's travel distances against SciPy's undirected Dijkstra on the same graph."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse.csgraph import dijkstra

from firefleet.control.mission._coverage import coarse_map
from firefleet.control.navigation import NavigationParams, build_costmap
from firefleet.world import load_map


@pytest.mark.parametrize("name", ["floor100", "office", "maze"])
def test_distances_equal_an_undirected_search(name: str) -> None:
    """``CoarseMap.distances`` searches the graph as directed (it holds every edge both
    ways): from 12 random standable cells, cut at 3 m, 8 m and not at all, the distances
    equal SciPy's undirected search exactly, and the graph is symmetric."""
    nav = NavigationParams()
    cm = coarse_map(build_costmap(load_map(name), nav.robot_radius_m + nav.margin_m), 0.25)
    g = cm.graph
    assert (abs(g - g.T) > 0).nnz == 0
    rng = np.random.default_rng(3)
    nodes = rng.choice(np.flatnonzero(cm.standable.ravel()), 12, replace=False)
    for limit in (3.0, 8.0, math.inf):
        want = dijkstra(g, directed=False, indices=nodes, limit=limit)
        got = cm.distances(nodes, limit)
        assert np.array_equal(got, want)
        reached = np.isfinite(got).sum(axis=1)
        assert (reached > 1).all()
