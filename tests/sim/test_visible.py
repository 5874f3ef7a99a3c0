"""The visible-light camera's view through smoke (Jin's law, firefleet.sim.visible) and
the stereo-only team's detector, against the analytic cases."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.sim._smoke_cast import SmokeField
from firefleet.sim.kinds._mission_smoke import SmokeAt, VisibleDetector
from firefleet.sim.visible import VisibleCameraParams, visible_view
from firefleet.world import BURNING, OccupancyGrid


def _open(h: int, w: int, res: float) -> OccupancyGrid:
    occ = np.zeros((h, w), dtype=bool)
    return OccupancyGrid(occ, ~occ, resolution_m=res)


@pytest.mark.parametrize("sigma", [0.4, 1.0, 2.5])
def test_uniform_smoke_visibility_is_k_over_sigma(sigma: float) -> None:
    """A person is seen to V = 3 / sigma, a flame to 8 / sigma (Jin)."""
    grid = _open(40, 160, 0.25)  # 40 m x 10 m
    smoke = SmokeField(grid, np.full(grid.shape, sigma))
    params = VisibleCameraParams(max_range_m=40.0)
    for k, glow in ((3.0, False), (8.0, True)):
        v = k / sigma
        d = np.array([0.97 * v, 0.999 * v, 1.001 * v, 1.03 * v])
        targets = np.c_[1.0 + d, np.full(d.size, 5.0)]
        glows = np.full(d.size, glow)
        view = visible_view(grid, [[1.0, 5.0, 0.0]], targets, glows, params, smoke=smoke)
        assert view.seen[0].tolist() == [True, True, False, False], (k, sigma)
        np.testing.assert_allclose(view.depth[0], sigma * d, rtol=1e-9)


def test_smoke_that_is_not_uniform_counts_its_optical_depth() -> None:
    """A 2 m slab of sigma between the camera and the person: seen iff 2 sigma <= 3."""
    grid = _open(20, 80, 0.25)
    for sigma, seen in ((1.45, True), (1.55, False)):
        ext = np.zeros(grid.shape)
        ext[:, 16:24] = sigma  # x from 4 to 6 m
        view = visible_view(
            grid,
            [[1.0, 2.5, 0.0]],
            [[9.0, 2.5]],
            [False],
            VisibleCameraParams(),
            smoke=SmokeField(grid, ext),
        )
        assert bool(view.seen[0, 0]) is seen


def test_field_of_view_range_walls_and_darkness() -> None:
    occ = np.zeros((40, 80), dtype=bool)
    occ[10:40, 40] = True  # a wall at x = 4 m, from y = 0 to 3 m (0.1 m cells)
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1)
    params = VisibleCameraParams(max_range_m=6.0)
    pose = [[1.0, 2.0, 0.0]]
    half = 0.5 * params.hfov_rad
    targets = np.array(
        [
            [3.0, 2.0],  # ahead, clear: seen
            [6.0, 2.0],  # behind the wall
            [1.0 + 2.0 * math.cos(half - 0.02), 2.0 + 2.0 * math.sin(half - 0.02)],  # in the edge
            [1.0 + 2.0 * math.cos(half + 0.02), 2.0 + 2.0 * math.sin(half + 0.02)],  # out
            [0.0, 2.0],  # behind the camera
            [3.9, 3.5],  # in range, above the wall's end: seen
        ]
    )
    lit = visible_view(grid, pose, targets, np.zeros(6, bool), params)
    assert lit.seen[0].tolist() == [True, False, True, False, False, True]
    far = visible_view(grid, pose, [[7.5, 3.5]], [False], params)  # 6.7 m > 6 m
    assert not far.seen[0, 0]
    near = visible_view(grid, pose, [[1.9, 2.0], [2.1, 2.0]], [False, False], params)
    assert near.seen[0].tolist() == [False, True]  # nearer than 1 m: the frame cuts them
    dark = visible_view(
        grid, pose, targets[:1].repeat(2, 0), [False, True], VisibleCameraParams(lit=False)
    )
    assert dark.seen[0].tolist() == [False, True]  # darkness: only the flame
    with pytest.raises(InputError, match="emitting"):
        visible_view(grid, pose, targets, [False], params)
    with pytest.raises(InputError, match="max_range_m"):
        VisibleCameraParams(max_range_m=0.0)


def test_stereo_only_detector_sees_the_person_in_clear_air_not_in_dense_smoke() -> None:
    """The mission's stereo-only team: a person 2 m ahead, two burning cells 3.5 m ahead;
    clear air: both seen; lower-layer smoke of 2 1/m (V = 1.5 m for the person, 4 m for
    the flames): the flames only, one fire at the burning cells' mean."""
    grid = _open(40, 80, 0.25)
    state = np.zeros(grid.shape, dtype=np.int8)
    fire_rc = grid.cell_of(np.array([[4.3, 5.0], [4.55, 5.0]]))  # centred at y 5.125
    state[fire_rc[:, 0], fire_rc[:, 1]] = BURNING
    det = VisibleDetector(
        grid,
        SmokeAt(grid, layer=0.4),
        np.array([[3.0, 5.25]]),
        VisibleCameraParams(),
        rng=np.random.default_rng(0),
        depth_noise=0.0,
    )
    pose = np.array([[1.0, 5.25, 0.0]])
    for field, kinds in ((0.0, [0.0, 1.0]), (5.0, [0.0])):
        world = SimpleNamespace(
            fire=SimpleNamespace(state=state), smoke_per_m=np.full(grid.shape, field)
        )
        rows = det.read(world, pose, np.zeros(1, bool))
        assert sorted(rows[:, 1].tolist()) == kinds, field
        person = rows[rows[:, 1] == 1.0]
        if len(person):
            assert person[0, 3] == pytest.approx(2.0)
        fire = rows[rows[:, 1] == 0.0]
        assert np.isinf(fire[0, 4])  # flames: light-emitting, no temperature measured
        np.testing.assert_allclose(fire[0, 3], math.hypot(3.5, 0.125), rtol=1e-9)  # their mean
    damaged = det.read(world, pose, np.ones(1, bool))
    assert damaged.shape == (0, 5)
