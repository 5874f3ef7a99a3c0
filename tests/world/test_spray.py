"""The spray against its definition: water conserved, walls shadow, the analytic time to
put a cell out, soaked fuel does not ignite, the water's heat balance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.world import (
    BURNING,
    BURNT,
    UNBURNT,
    FireParams,
    FireState,
    OccupancyGrid,
    SprayParams,
    coarsen,
    fire_init,
    fire_step,
    spray_step,
)
from firefleet.world._spray import WATER_HEAT_J_KG

RES = 0.25


def _open(h: int = 20, w: int = 40) -> OccupancyGrid:
    walls = np.zeros((h, w), dtype=bool)
    return OccupancyGrid(walls, ~walls, resolution_m=RES)


def _fire_at(grid: OccupancyGrid, xy: tuple[float, float]) -> tuple[FireState, tuple[int, int]]:
    ignite = np.zeros(grid.shape, dtype=bool)
    r, c = (int(v) for v in grid.cell_of(np.array(xy)))
    ignite[r, c] = True
    return fire_init(np.where(grid.occupied, 0.0, 1.0), ignite, FireParams()), (r, c)


def test_water_is_conserved_and_a_cell_goes_out_at_the_analytic_time() -> None:
    grid = _open()
    fire, (r, c) = _fire_at(grid, (3.125, 2.625))
    params = SprayParams(flow_l_s=0.2, range_m=2.5, half_angle_rad=math.radians(20.0))
    temp, wet = np.full(grid.shape, 20.0), np.zeros(grid.shape)
    nozzle = np.array([[1.125, 2.625, 0.0]])
    # the cone's cells: counted once by the definition (centre within range and angle)
    centres = grid.center_of(np.argwhere(~grid.occupied))
    d = centres - nozzle[0, :2]
    dist = np.hypot(d[:, 0], d[:, 1])
    ahead = np.abs(np.arctan2(d[:, 1], d[:, 0])) <= math.radians(20.0)
    k = int(np.sum((dist <= 2.5) & (dist > 0) & ahead))  # not the nozzle's own cell
    per_step = 0.2 * 0.1 / k / RES**2  # L/m^2 a cell gets per 0.1 s step
    steps_to_out = math.ceil(params.critical_l_m2 / per_step - 1e-9)
    delivered = 0.0
    for _ in range(steps_to_out):
        assert fire.state[r, c] == BURNING  # not out before the analytic step
        fire, temp, wet, used = spray_step(fire, temp, wet, nozzle, [True], grid, params, 0.1)
        delivered += float(used[0])
    assert fire.state[r, c] == BURNT
    assert np.count_nonzero(wet) == k
    assert wet.sum() * RES**2 == pytest.approx(delivered, rel=1e-12)
    assert delivered == pytest.approx(0.2 * 0.1 * steps_to_out, rel=1e-12)


def test_a_wall_shadows_the_cone_and_out_of_reach_stays_burning() -> None:
    walls = np.zeros((20, 40), dtype=bool)
    walls[:, 10] = True  # a wall at x = 2.5-2.75 m
    grid = OccupancyGrid(walls, ~walls, resolution_m=RES)
    fire, (r, c) = _fire_at(grid, (3.125, 2.625))
    temp, wet = np.full(grid.shape, 20.0), np.zeros(grid.shape)
    params = SprayParams(flow_l_s=1.0, range_m=3.0)
    for _ in range(50):
        fire, temp, wet, _used = spray_step(
            fire, temp, wet, [[1.125, 2.625, 0.0]], [True], grid, params, 0.1
        )
    assert fire.state[r, c] == BURNING
    assert not wet[:, 11:].any()  # nothing behind the wall
    far = _open()
    fire, (r, c) = _fire_at(far, (8.125, 2.625))  # 7 m away, reach 3 m
    temp, wet = np.full(far.shape, 20.0), np.zeros(far.shape)
    for _ in range(50):
        fire, temp, wet, _used = spray_step(
            fire, temp, wet, [[1.125, 2.625, 0.0]], [True], far, params, 0.1
        )
    assert fire.state[r, c] == BURNING


def test_soaked_fuel_does_not_ignite_and_the_water_cools_by_its_heat() -> None:
    grid = _open(5, 9)
    fire, _ = _fire_at(grid, (1.125, 0.625))
    params = SprayParams(flow_l_s=10.0, range_m=1.2, half_angle_rad=math.radians(30.0))
    temp, wet = np.full(grid.shape, 500.0), np.zeros(grid.shape)
    nozzle = np.array([[0.125, 0.625, 0.0]])
    fire, temp2, wet, used = spray_step(fire, temp, wet, nozzle, [True], grid, params, 0.1)
    hit = wet > 0
    per_cell_kg = float(used[0]) / np.count_nonzero(hit)
    expected = 500.0 - per_cell_kg * WATER_HEAT_J_KG / (params.heat_capacity_j_k_m2 * RES**2)
    assert temp2[hit] == pytest.approx(np.maximum(expected, params.ambient_c))
    assert (temp2[~hit] == 500.0).all()
    soaked = (wet >= params.critical_l_m2) & (fire.state == UNBURNT)
    assert soaked.any()
    rng = np.random.default_rng(0)
    # a burning neighbour for 200 s would ignite a dry cell almost surely (rate 0.04/s)
    fire2 = fire_init(fire.fuel, np.zeros(grid.shape, bool) | (fire.state == BURNING), FireParams())
    fire2 = FireState(
        state=np.where(fire.state == BURNT, BURNING, fire2.state).astype(np.int8),
        burn_left_s=np.full(grid.shape, 1e4),
        fuel=fire.fuel,
    )
    for _ in range(400):
        fire2 = fire_step(fire2, FireParams(), 0.5, RES, rng=rng)
    assert (fire2.state[soaked] == UNBURNT).all()


def test_bad_input_is_named() -> None:
    grid = _open()
    fire, _ = _fire_at(grid, (3.0, 2.0))
    with pytest.raises(InputError, match="temperature_c"):
        spray_step(
            fire,
            np.zeros((2, 2)),
            np.zeros(grid.shape),
            [[0, 0, 0]],
            [True],
            grid,
            SprayParams(),
            0.1,
        )
    with pytest.raises(InputError, match="flow_l_s"):
        SprayParams(flow_l_s=0.0)


def test_coarsen_keeps_thin_walls_and_the_origin() -> None:
    occupied = np.zeros((10, 10), dtype=bool)
    occupied[:, 4] = True  # a one-cell wall
    fine = OccupancyGrid(occupied, ~occupied, resolution_m=0.05, origin_m=(1.0, 2.0))
    coarse = coarsen(fine, 5)
    assert coarse.shape == (2, 2)
    assert coarse.occupied[:, 0].all()
    assert not coarse.occupied[:, 1].any()
    assert coarse.center_of(np.array([[1, 0]])).tolist() == [[1.125, 2.125]]
    with pytest.raises(InputError, match="factor"):
        coarsen(fine, 0)


def _brute_cone_litres(
    grid: OccupancyGrid, pose: np.ndarray, params: SprayParams, dt_s: float
) -> np.ndarray:
    """Water [L/m^2] one nozzle puts on each cell in a step, from the model over every
    open cell of the grid (the cone, the range, the line of sight; flow shared evenly)."""
    from firefleet.world._spray import _in_sight

    rc = np.argwhere(~grid.occupied)
    xy = grid.center_of(rc)
    d = xy - pose[:2]
    dist = np.hypot(d[:, 0], d[:, 1])
    off = np.angle(np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - pose[2])))
    idx = np.flatnonzero(
        (dist <= params.range_m) & (np.abs(off) <= params.half_angle_rad) & (dist > 0)
    )
    idx = idx[_in_sight(grid, pose[:2], xy[idx])]
    out = np.zeros(grid.shape)
    if idx.size:
        out[rc[idx, 0], rc[idx, 1]] = params.flow_l_s * dt_s / idx.size / grid.resolution_m**2
    return out


def test_spray_near_the_grid_edges_wets_the_cells_of_the_whole_grid_model() -> None:
    """The step looks only at the box around a nozzle that holds its range: nozzles at
    random poses on a walled grid, by its edges and corners and off it, wet exactly the
    cells the model over every cell of the grid wets."""
    rng = np.random.default_rng(11)
    walls = rng.random((24, 36)) < 0.08
    grid = OccupancyGrid(walls, ~walls, resolution_m=RES)
    w_m, h_m = 36 * RES, 24 * RES
    params = SprayParams(range_m=2.0, half_angle_rad=math.radians(30.0))
    fire = fire_init(np.zeros(grid.shape), np.zeros(grid.shape, dtype=bool), FireParams())
    temp = np.full(grid.shape, 20.0)
    xs = np.concatenate([rng.uniform(-1.0, w_m + 1.0, 40), [0.1, w_m - 0.1, 0.1, w_m - 0.1]])
    ys = np.concatenate([rng.uniform(-1.0, h_m + 1.0, 40), [0.1, 0.1, h_m - 0.1, h_m - 0.1]])
    wetted = 0
    for x, y in zip(xs, ys, strict=True):
        pose = np.array([x, y, rng.uniform(-math.pi, math.pi)])
        _, _, wet, _ = spray_step(
            fire, temp, np.zeros(grid.shape), pose[None], [True], grid, params, 0.1
        )
        want = _brute_cone_litres(grid, pose, params, 0.1)
        assert np.array_equal(wet, want)
        wetted += int(want.any())
    assert wetted >= 20
