"""Allocation and frontier choice against brute force."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from firefleet.control.mission import TacticsParams
from firefleet.control.mission._plan import allocate, cut_demand, fire_demand
from firefleet.planning.allocation import allocate_tasks
from firefleet.planning.exploration import assign_frontiers


def brute_force(cost: np.ndarray, demand: np.ndarray) -> tuple[int, float]:
    """(most robots placed, least total cost among those plans) over every plan."""
    r, t = cost.shape
    best = (-1, np.inf)
    for plan in itertools.product(range(-1, t), repeat=r):
        p = np.array(plan)
        if any((p == j).sum() > demand[j] for j in range(t)):
            continue
        used = p >= 0
        c = cost[np.flatnonzero(used), p[used]]
        if not np.all(np.isfinite(c)):
            continue
        key = (int(used.sum()), float(c.sum()))
        if key[0] > best[0] or (key[0] == best[0] and key[1] < best[1] - 1e-12):
            best = key
    return best


def plan_value(cost: np.ndarray, got: np.ndarray) -> tuple[int, float]:
    used = got >= 0
    return int(used.sum()), float(cost[np.flatnonzero(used), got[used]].sum())


@pytest.mark.parametrize("seed", range(12))
def test_allocation_equals_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    r, t = rng.integers(2, 6), rng.integers(1, 4)
    cost = rng.uniform(0.0, 20.0, (r, t))
    cost[rng.random((r, t)) < 0.15] = np.inf  # some robots cannot do some tasks
    demand = rng.integers(1, 3, t)
    got = allocate_tasks(cost, demand=demand)
    assert all((got == j).sum() <= demand[j] for j in range(t))
    n_bf, c_bf = brute_force(cost, demand)
    n, c = plan_value(cost, got)
    assert n == n_bf
    assert c == pytest.approx(c_bf, abs=1e-9)


def test_team_costs_are_the_stated_ones() -> None:
    """The team's cost: distance, + penalty for a low tank on fires, inf for an empty
    tank on fires and for unavailable robots, - bonus for the current task (>= 0)."""
    p = TacticsParams(tank_l=10.0, low_tank_frac=0.3, low_tank_penalty_m=7.0, keep_bonus_m=2.0)
    rng = np.random.default_rng(3)
    for _ in range(10):
        dist = rng.uniform(0.5, 15.0, (4, 3))
        is_fire = np.array([True, True, False])
        demand = np.array([2, 1, 1])
        tank = np.array([10.0, 2.0, 0.0, 6.0])  # full, low, empty, fine
        available = np.array([True, True, True, rng.random() < 0.5])
        current = np.array([1, -1, 2, 0])
        ref = dist.copy()
        ref[1, :2] += 7.0
        ref[2, :2] = np.inf
        for i, j in enumerate(current):
            if j >= 0:
                ref[i, j] = max(ref[i, j] - 2.0, 0.0)
        ref[~available] = np.inf
        got = allocate(dist, demand, is_fire, current, available, tank, p)
        assert plan_value(ref, got) == pytest.approx(brute_force(ref, demand))
        assert got[2] not in (0, 1)  # an empty tank never goes to a fire


def test_fire_demand_grows_with_extent() -> None:
    p = TacticsParams(fire_robots_min=2, fire_robots_max=5, robot_per_fire_m=1.0)
    assert fire_demand(np.array([0.0, 0.99, 1.0, 2.5, 10.0]), p).tolist() == [2, 2, 3, 4, 5]


@pytest.mark.parametrize("seed", range(8))
def test_exclusive_frontiers_are_never_shared(seed: int) -> None:
    rng = np.random.default_rng(seed)
    r, f = rng.integers(2, 8), rng.integers(1, 6)
    xy = rng.uniform(0.0, 10.0, (f, 2))
    d = rng.uniform(1.0, 20.0, (r, f))
    taken = rng.choice(f, size=rng.integers(0, f), replace=False)
    got = assign_frontiers(d, xy, sensor_range_m=3.0, beta=0.05, taken=taken, exclusive=True)
    chosen = got[got >= 0]
    assert len(set(chosen.tolist())) == len(chosen)  # no target twice
    assert not set(chosen.tolist()) & set(taken.tolist())  # nor a held one
    # every robot left without one: no target was left for it
    assert (got >= 0).sum() == min(r, f - len(taken))


@pytest.mark.parametrize("n_work", [0, 1, 2, 3, 6, 20, 50])
def test_fire_demands_leave_explorers(n_work: int) -> None:
    """Demands cut against a brute force: of every way to give the fires at most what
    they ask (at least fire_robots_min each, or one each when the team is too small, or
    none when the robots at hand are all explorers and others are out refilling), the
    largest total within n_work - ceil(0.3 n_work) - victims, most even (the largest
    demand as small as it can be)."""

    p = TacticsParams(explore_frac=0.3, fire_robots_min=2, fire_robots_max=6)
    rng = np.random.default_rng(n_work)
    for _ in range(20):
        f = int(rng.integers(1, 4))
        need = rng.integers(2, 7, f)
        victims = int(rng.integers(0, 4))
        refilling = int(rng.integers(0, 3))
        out = cut_demand(need, victims, n_work, p, refilling)
        explorers = math.ceil(0.3 * n_work)
        spare = n_work - explorers
        if f * 2 <= spare:
            low = 2
        elif spare <= 0 and refilling:
            low = 0
        else:
            low = 1
        budget = max(spare - victims, f * low)
        best = None
        for combo in itertools.product(*[range(low, int(k) + 1) for k in need]):
            c = np.array(combo)
            if c.sum() > budget:
                continue
            key = (-c.sum(), c.max())
            if best is None or key < best:
                best = key
        assert best is not None
        assert (-out.sum(), out.max()) == best, (need, victims, out)
        assert np.all(out <= need)
        if n_work >= 20:
            assert n_work - out.sum() - victims >= explorers


@pytest.mark.parametrize("refilling", [0, 2])
def test_plan_keeps_the_explorer_while_the_fighters_refill(refilling: int) -> None:
    """The plan (``_step._plan``): three robots, one fire, floor left to search, the
    third robot exploring. With both others out refilling (the school, seed 4, at
    180 s) it explores on: they come back to the fire. With both others lost, it is the
    team and it fights (the fire keeps one robot)."""
    from dataclasses import replace

    from firefleet.control.mission import tactics_init, tactics_step
    from firefleet.control.mission._knowledge import fires_of
    from firefleet.control.mission._params import EXPLORE, FIGHT, REFILL
    from firefleet.control.mission._step import _plan
    from firefleet.world import load_map
    from tests.control.mission._harness import fire_obs

    p = TacticsParams(fire_robots_min=2, fire_robots_max=2)
    pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0], [1.0, 4.2, 0.0]])
    state = tactics_init(load_map("office"), pose, p)
    fire = np.array([[4.0, 5.0], [4.5, 5.0]])
    state, _ = tactics_step(state, fire_obs(pose, fire), p, 0.01)
    ids, _, _ = fires_of(state.knowledge)
    assert len(ids) == 1
    assert state.covered_coarse.sum() < 0.5 * state.coarse.floor.sum()  # floor to search
    working = np.array([True, True, True]) if refilling else np.array([False, False, True])
    state = replace(
        state,
        mode=np.array([REFILL, REFILL, EXPLORE], dtype=state.mode.dtype),
        task_fire=np.full(3, -1),
        refill_spot=np.array([0, 1, -1]),
    )
    new = _plan(state, pose, np.array([0.5, 0.5, 20.0]), working, p)
    if refilling:
        assert new.task_fire.tolist() == [-1, -1, -1]
        assert new.mode[2] == EXPLORE
    else:
        assert new.task_fire.tolist()[2] == ids[0]
        assert new.mode[2] == FIGHT
