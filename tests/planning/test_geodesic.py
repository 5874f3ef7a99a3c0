"""Travel distances against a plain Dijkstra written out here and the octile distance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.planning.geodesic import travel_distance_m
from tests._dijkstra import grid_dijkstra


def _reference(free: np.ndarray, src: tuple[int, int], h: float) -> np.ndarray:
    """Dijkstra with a heap over the 8 neighbours, no corner cutting (the definition)."""
    return grid_dijkstra(free, src, h)


@pytest.mark.parametrize("seed", range(5))
def test_distances_equal_a_plain_dijkstra_on_random_grids(seed: int) -> None:
    rng = np.random.default_rng(seed)
    free = rng.random((23, 31)) > 0.3
    sources = np.argwhere(free)[rng.choice(int(free.sum()), 3, replace=False)]
    got = travel_distance_m(free, sources, 0.05)
    for k, s in enumerate(sources):
        np.testing.assert_allclose(
            got[k], _reference(free, (int(s[0]), int(s[1])), 0.05), rtol=1e-12
        )


def test_empty_grid_gives_the_octile_distance() -> None:
    d = travel_distance_m(np.ones((40, 60), dtype=bool), [[5, 7]], 0.1)[0]
    r, c = np.mgrid[:40, :60]
    dr, dc = np.abs(r - 5), np.abs(c - 7)
    octile = 0.1 * (np.maximum(dr, dc) + (math.sqrt(2) - 1) * np.minimum(dr, dc))
    np.testing.assert_allclose(d, octile, rtol=1e-12)


def test_walls_and_unreachable_cells() -> None:
    free = np.ones((5, 9), dtype=bool)
    free[:, 4] = False  # a wall from top to bottom
    d = travel_distance_m(free, [[2, 1]], 1.0)[0]
    assert np.all(np.isinf(d[:, 4:]))
    assert np.isfinite(d[:, :4]).all()
    with pytest.raises(InputError, match=r"source cell \(row 0, col 4\) is not a free cell"):
        travel_distance_m(free, [[0, 4]], 1.0)
    with pytest.raises(InputError, match="not a free cell"):
        travel_distance_m(free, [[9, 0]], 1.0)
