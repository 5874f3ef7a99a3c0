"""``_discs.disc_cells`` (one compiled pass) against the array form it replaced in
``_fight._disc_mask`` (kept here verbatim): the same cells on random points and radii,
on points of the cells' lattice (distances equal to the radius: ``<=`` decided alike),
off the map, not finite, with an offset origin, and with no point at all."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._discs import disc_cells
from firefleet.world import OccupancyGrid


def _reference(grid: OccupancyGrid, xy: FloatArray, radius_m: float) -> BoolArray:
    """``_fight._disc_mask`` before (array windows per point)."""
    grid_shape = grid.shape
    h, w = grid_shape
    k = math.ceil(radius_m / grid.resolution_m) + 1
    out = np.zeros(grid_shape, dtype=bool)
    for p in xy:
        r, c = (int(v) for v in grid.cell_of(p))
        r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, h), max(c - k, 0), min(c + k + 1, w)
        if r0 >= r1 or c0 >= c1:
            continue
        rr, cc = np.mgrid[r0:r1, c0:c1]
        centres = grid.center_of(np.stack([rr, cc], axis=-1))
        out[r0:r1, c0:c1] |= np.hypot(centres[..., 0] - p[0], centres[..., 1] - p[1]) <= radius_m
    return out


def _grid(h: int, w: int, res: float, origin: tuple[float, float]) -> OccupancyGrid:
    occ = np.zeros((h, w), dtype=bool)
    return OccupancyGrid(occ, ~occ, res, origin)


@pytest.mark.parametrize("seed", range(6))
def test_random_points_and_radii(seed: int) -> None:
    rng = np.random.default_rng(seed)
    res = float(rng.choice([0.05, 0.1, 0.25, 0.3]))
    h, w = int(rng.integers(5, 120)), int(rng.integers(5, 120))
    origin = (float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)))
    grid = _grid(h, w, res, origin)
    for _ in range(8):
        m = int(rng.integers(0, 30))
        # points on the map and up to a couple of metres beyond it
        lo = np.array(origin) - 2.0
        hi = np.array(origin) + np.array([w * res + 2.0, h * res + 2.0])
        xy = rng.uniform(lo, hi, size=(m, 2))
        radius = float(rng.choice([0.0, res / 2, 0.5, 1.5, rng.uniform(0.01, 3.0)]))
        got = disc_cells(grid, xy, radius)
        assert got.dtype == np.bool_
        assert np.array_equal(got, _reference(grid, xy, radius))


def test_points_on_the_lattice_decide_the_edge_alike() -> None:
    """Cell centres as points and radii that are lattice distances (1, sqrt 2, 2, sqrt 5
    cells): the distances equal the radius up to rounding, so ``<=`` must see the very
    same floats."""
    grid = _grid(40, 50, 0.05, (0.0, 0.0))
    centres = grid.center_of(np.argwhere(np.ones((40, 50), dtype=bool)))
    rng = np.random.default_rng(1)
    for radius in (0.05, 0.05 * math.sqrt(2.0), 0.1, 0.05 * math.sqrt(5.0), 1.5, 0.25):
        xy = centres[rng.integers(len(centres), size=7)]
        assert np.array_equal(disc_cells(grid, xy, radius), _reference(grid, xy, radius))
    odd = _grid(30, 30, 0.1, (-1.3, 0.7))  # an origin off the lattice of 0.1
    pts = odd.center_of(np.array([[0, 0], [29, 29], [15, 3], [3, 15]]))
    for radius in (0.1, 0.1 * math.sqrt(2.0), 0.3, 1.0):
        assert np.array_equal(disc_cells(odd, pts, radius), _reference(odd, pts, radius))


def test_edges() -> None:
    grid = _grid(20, 30, 0.1, (0.0, 0.0))
    none = np.zeros((0, 2))
    assert not disc_cells(grid, none, 1.0).any()
    assert disc_cells(grid, none, 1.0).shape == (20, 30)
    # far off the map, not finite: nothing, as the array form
    far = np.array([[1e6, 1.0], [1.0, -1e6], [-50.0, -50.0]])
    assert np.array_equal(disc_cells(grid, far, 1.0), _reference(grid, far, 1.0))
    assert not disc_cells(grid, far, 1.0).any()
    nan = np.array([[np.nan, 1.0], [1.0, np.inf], [1.05, 1.05]])
    got = disc_cells(grid, nan, 0.3)
    assert np.array_equal(got, disc_cells(grid, nan[2:], 0.3))
    assert np.array_equal(got, _reference(grid, nan[2:], 0.3))
    # just off each edge, the disc reaching onto the map
    rim = np.array([[-0.25, 1.0], [3.25, 1.0], [1.5, -0.25], [1.5, 2.25]])
    assert np.array_equal(disc_cells(grid, rim, 0.4), _reference(grid, rim, 0.4))
    assert disc_cells(grid, rim, 0.4).any()
    # a radius covering the whole map; the inclusive edge at 0
    centre = grid.center_of(np.array([[5, 5]]))
    assert disc_cells(grid, centre, 100.0).all()
    assert disc_cells(grid, centre, 0.0).sum() == 1


@pytest.mark.parametrize("seed", [0, 1])
def test_the_hot_places_keep_out_is_the_same_disc(seed: int) -> None:
    """``_keepout.near_points`` (the live hot places' price) was the same window code
    as the reference: it is the reference's cells, and none for a radius of 0 or no
    point."""
    from firefleet.control.mission._keepout import near_points

    rng = np.random.default_rng(seed)
    grid = _grid(60, 90, 0.05, (0.5, -1.0))
    xy = rng.uniform([0.0, -1.5], [5.5, 2.5], size=(7, 2))
    for radius in (0.2, 1.0, 1.37):
        assert np.array_equal(near_points(grid, xy, radius), _reference(grid, xy, radius))
    assert not near_points(grid, xy, 0.0).any()
    assert not near_points(grid, np.zeros((0, 2)), 1.0).any()
