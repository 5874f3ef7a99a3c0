"""``any_within`` against the full distance matrix, on and off the radius."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.control.mission._near import any_within


@pytest.mark.parametrize("inclusive", [True, False])
def test_any_within_equals_the_distance_matrix(inclusive: bool) -> None:
    """Random points on a 0.25 m lattice and off it (lattice points are at exactly the
    radius from each other often: 1.5 m is six cells), radii on and off the lattice: the
    same answer as ``np.hypot`` over every pair."""
    rng = np.random.default_rng(5)
    for trial in range(30):
        lattice = trial % 2 == 0
        a = np.asarray(
            rng.integers(0, 40, size=(200, 2)) * 0.25 if lattice else rng.uniform(0, 10, (200, 2)),
            dtype=np.float64,
        )
        b = np.asarray(
            rng.integers(0, 40, size=(50, 2)) * 0.25 if lattice else rng.uniform(0, 10, (50, 2)),
            dtype=np.float64,
        )
        r = float(rng.choice([0.5, 1.0, 1.5, 2.0])) if lattice else float(rng.uniform(0.2, 2.0))
        d = np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])
        want = (d <= r).any(axis=1) if inclusive else (d < r).any(axis=1)
        assert any_within(a, b, r, inclusive).tolist() == want.tolist()


def test_any_within_with_nothing_to_compare() -> None:
    a = np.array([[0.0, 0.0]])
    assert any_within(a, np.zeros((0, 2)), 1.0, True).tolist() == [False]
    assert any_within(np.zeros((0, 2)), a, 1.0, True).tolist() == []
