"""The fire step's passes over every cell, compiled (:func:`firefleet.world.fire_step`).

Two passes replace the step's array expressions, element by element the same: the
cells that can ignite with their weighted count of burning neighbours (the stencil of
:func:`firefleet.world._stencil.neighbour_sum`, summed in its order), and the states
and burn times after the step. The ignition law itself (``expm1`` on the candidates)
stays NumPy's. tests/world/test_fire_kernel.py checks both against the array form.
"""

from __future__ import annotations

import numba
import numpy as np

_UNBURNT = 0
_BURNING = 1
_BURNT = 2


@numba.njit(cache=True)
def candidates(
    state: np.ndarray, fuel: np.ndarray, diagonal_weight: float
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The cells that can ignite (unburnt, fuel > 0, a burning neighbour), as flat
    indices in C order (K,), and their neighbour sums (K,): the four edge neighbours
    ``((up + down) + left) + right`` plus ``diagonal_weight`` times the four diagonal
    ones ``((up-left + up-right) + down-left) + down-right`` (0 off the grid), as
    ``neighbour_sum`` of the burning mask adds them."""
    h, w = state.shape
    cand = np.empty(h * w, dtype=np.int64)
    near = np.empty(h * w)
    k = 0
    for r in range(h):
        up, down = r > 0, r < h - 1
        for c in range(w):
            if state[r, c] != _UNBURNT or not fuel[r, c] > 0.0:
                continue
            left, right = c > 0, c < w - 1
            # each neighbour 1.0 if it burns, else 0.0 (also off the grid)
            n_up = 1.0 if up and state[r - 1, c] == _BURNING else 0.0
            n_down = 1.0 if down and state[r + 1, c] == _BURNING else 0.0
            n_left = 1.0 if left and state[r, c - 1] == _BURNING else 0.0
            n_right = 1.0 if right and state[r, c + 1] == _BURNING else 0.0
            s = ((n_up + n_down) + n_left) + n_right
            if diagonal_weight != 0.0:
                n_ul = 1.0 if up and left and state[r - 1, c - 1] == _BURNING else 0.0
                n_ur = 1.0 if up and right and state[r - 1, c + 1] == _BURNING else 0.0
                n_dl = 1.0 if down and left and state[r + 1, c - 1] == _BURNING else 0.0
                n_dr = 1.0 if down and right and state[r + 1, c + 1] == _BURNING else 0.0
                s = s + diagonal_weight * (((n_ul + n_ur) + n_dl) + n_dr)
            if s > 0.0:
                cand[k] = r * w + c
                near[k] = s
                k += 1
    return cand[:k].copy(), near[:k].copy()


@numba.njit(cache=True)
def advance(
    state: np.ndarray,
    burn_left_s: np.ndarray,
    fuel: np.ndarray,
    ignites: np.ndarray,
    dt_s: float,
    burn_s_per_fuel: float,
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The states and burn times [s] after the step: burning cells lose ``dt_s`` (the
    others 0.0) and burn out at <= 1e-9 s left (burnt, 0 s); the cells ``ignites``
    (flat indices) burn for ``burn_s_per_fuel * fuel``."""
    h, w = state.shape
    out = state.copy()
    left = np.empty((h, w))
    for r in range(h):
        for c in range(w):
            burning = state[r, c] == _BURNING
            b = burn_left_s[r, c] - (dt_s if burning else 0.0)
            if burning and b <= 1e-9:
                out[r, c] = _BURNT
                b = 0.0
            left[r, c] = b
    for q in range(ignites.size):
        r, c = ignites[q] // w, ignites[q] % w
        out[r, c] = _BURNING
        left[r, c] = burn_s_per_fuel * fuel[r, c]
    return out, left
