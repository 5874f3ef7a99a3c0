"""The fire step's compiled passes (world/_fire_kernel.py) equal their array form."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.world import BURNING, BURNT, UNBURNT
from firefleet.world._fire import _DIAGONAL
from firefleet.world._fire_kernel import advance, candidates
from firefleet.world._stencil import neighbour_sum


def _states(seed: int, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    state = rng.choice(
        np.array([UNBURNT, BURNING, BURNT], dtype=np.int8), shape, p=[0.6, 0.25, 0.15]
    )
    fuel = rng.uniform(0.0, 2.0, shape)
    fuel[rng.random(shape) < 0.2] = 0.0
    burn_left = np.where(state == BURNING, rng.uniform(0.0, 0.3, shape), 0.0)
    return state, fuel, burn_left


@pytest.mark.parametrize(("seed", "shape"), [(0, (1, 1)), (1, (1, 7)), (2, (9, 1)), (3, (23, 31))])
@pytest.mark.parametrize("weight", [0.0, _DIAGONAL])
def test_candidates_equal_the_stencil(seed: int, shape: tuple[int, int], weight: float) -> None:
    state, fuel, _ = _states(seed, shape)
    near = neighbour_sum((state == BURNING).astype(float), weight)
    ref = np.flatnonzero(((state == UNBURNT) & (fuel > 0.0) & (near > 0.0)).ravel())
    cand, sums = candidates(state, fuel, weight)
    np.testing.assert_array_equal(cand, ref)
    np.testing.assert_array_equal(sums.view(np.int64), near.ravel()[ref].view(np.int64))


@pytest.mark.parametrize("seed", range(4))
def test_advance_equals_the_array_form(seed: int) -> None:
    state, fuel, burn_left = _states(seed, (17, 26))
    rng = np.random.default_rng(100 + seed)
    cand, _ = candidates(state, fuel, _DIAGONAL)
    ignites = cand[rng.random(cand.size) < 0.5]
    dt_s, per_fuel = 0.1, 300.0
    burning = state == BURNING
    left = burn_left - np.where(burning, dt_s, 0.0)
    out = burning & (left <= 1e-9)
    ign = np.zeros(state.shape, dtype=bool)
    ign.ravel()[ignites] = True
    ref_state = state.copy()
    ref_state[out] = BURNT
    ref_state[ign] = BURNING
    ref_left = np.where(ign, per_fuel * fuel, np.where(out, 0.0, left))
    got_state, got_left = advance(state, burn_left, fuel, ignites, dt_s, per_fuel)
    assert out.any()  # cells burn out in the case
    assert ign.any()
    np.testing.assert_array_equal(got_state, ref_state)
    assert got_state.dtype == state.dtype
    np.testing.assert_array_equal(got_left.view(np.int64), ref_left.view(np.int64))
