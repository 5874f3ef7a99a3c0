"""fire_step's law evaluated on the cells that can ignite only equals the law on every
cell (the array form before), state and burn times, step after step."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.world import BURNING, BURNT, UNBURNT, FireParams, FireState, fire_init, fire_step
from firefleet.world._fire import _DIAGONAL
from firefleet.world._stencil import neighbour_sum


def _every_cell(
    fire: FireState, params: FireParams, dt_s: float, res: float, rng: np.random.Generator
) -> FireState:
    """fire_step with the ignition law on every cell (the reference)."""
    rate0_hz = params.spread_m_s / res
    burning = fire.state == BURNING
    log_no = -rate0_hz * dt_s * neighbour_sum(burning.astype(float), _DIAGONAL)
    factor = 1.0 + np.clip(params.fuel_factor * (fire.fuel - 1.0), -0.9, 1.0)
    p_ignite = -np.expm1(log_no * factor)
    u = rng.random(fire.state.shape)
    ignites = (fire.state == UNBURNT) & (fire.fuel > 0.0) & (u < p_ignite)
    burn_left = fire.burn_left_s - np.where(burning, dt_s, 0.0)
    burns_out = burning & (burn_left <= 1e-9)
    state = fire.state.copy()
    state[burns_out] = BURNT
    state[ignites] = BURNING
    burn_left = np.where(burns_out, 0.0, burn_left)
    burn_left = np.where(ignites, params.burn_s_per_fuel * fire.fuel, burn_left)
    return FireState(state=state, burn_left_s=burn_left, fuel=fire.fuel)


@pytest.mark.parametrize("fuel_factor", [0.0, 0.7])
def test_candidates_equal_every_cell(fuel_factor: float) -> None:
    rng = np.random.default_rng(5)
    fuel = rng.uniform(0.0, 2.5, (30, 45))
    fuel[rng.random(fuel.shape) < 0.15] = 0.0  # walls
    ignite = np.zeros(fuel.shape, dtype=bool)
    ignite[15, 20] = ignite[3, 3] = True
    params = FireParams(spread_m_s=0.02, burn_s_per_fuel=20.0, fuel_factor=fuel_factor)
    a = b = fire_init(fuel, ignite, params)
    ra, rb = np.random.default_rng(9), np.random.default_rng(9)
    for _ in range(400):
        a = fire_step(a, params, 0.1, 0.25, rng=ra)
        b = _every_cell(b, params, 0.1, 0.25, rb)
        assert np.array_equal(a.state, b.state)
        assert np.array_equal(a.burn_left_s.view(np.int64), b.burn_left_s.view(np.int64))
    assert (a.state == BURNT).sum() > 50  # the fire spread and burned out
    assert ra.random() == rb.random()  # the same draws
