"""The assignment against brute force over every way of filling the task slots."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.planning.allocation import allocate_tasks


def _brute(cost: np.ndarray, demand: np.ndarray) -> tuple[int, float]:
    """(slots served, least total cost) over every assignment of robots to slots."""
    slots = np.repeat(np.arange(cost.shape[1]), demand)
    n_robots = cost.shape[0]
    best = (0, 0.0)
    for choice in itertools.product(range(-1, slots.size), repeat=n_robots):
        used = [s for s in choice if s >= 0]
        if len(used) != len(set(used)):
            continue
        total = sum(cost[i, slots[s]] for i, s in enumerate(choice) if s >= 0)
        if not np.isfinite(total):
            continue
        key = (len(used), -total)
        if key > (best[0], -best[1]):
            best = (len(used), float(total))
    return best


@pytest.mark.parametrize("seed", range(25))
def test_allocation_is_the_best_of_all_assignments(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n_robots, n_tasks = int(rng.integers(1, 5)), int(rng.integers(1, 4))
    cost = rng.uniform(0.0, 10.0, (n_robots, n_tasks))
    cost[rng.random(cost.shape) < 0.25] = np.inf
    demand = rng.integers(0, 3, n_tasks)
    got = allocate_tasks(cost, demand=demand)
    served = [t for t in got if t >= 0]
    assert all(np.bincount(served, minlength=n_tasks) <= demand)
    total = sum(cost[i, t] for i, t in enumerate(got) if t >= 0)
    assert np.isfinite(total)
    slots, best = _brute(cost, demand)
    assert len(served) == slots  # as many slots served as any assignment can
    assert total == pytest.approx(best, abs=1e-9)  # at the least cost


def test_bad_costs_and_demands() -> None:
    with pytest.raises(InputError, match="NaN or negative"):
        allocate_tasks([[1.0, np.nan]])
    with pytest.raises(InputError, match="demand must be 2 counts"):
        allocate_tasks([[1.0, 2.0]], demand=[1])
    assert allocate_tasks(np.zeros((3, 0))).tolist() == [-1, -1, -1]
    assert allocate_tasks([[np.inf], [np.inf]]).tolist() == [-1, -1]
