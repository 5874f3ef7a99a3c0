"""Spare robots to the fires (``_spare.spare_demand``): hand-computed cases and brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from firefleet.control.mission import TacticsParams
from firefleet.control.mission._spare import spare_demand

P = TacticsParams(fire_robots_min=2, fire_robots_max=2, robot_per_fire_m=1.0)


def test_no_spare_no_extra_held_leaves_demand() -> None:
    # two fighters on fire 3 (demand 2), the third robot explores: nothing changes
    got = spare_demand(
        np.array([2]), np.array([4.0]), np.array([3]), np.array([3, 3, -1]), np.zeros(3, bool), P
    )
    assert got.tolist() == [2]


def test_cut_demand_is_kept_while_nobody_is_spare() -> None:
    # cut_demand freed one of the two fighters (floor left to search): held 2 is not more
    # than the capped fire_demand 2, so the cut (1) stands
    got = spare_demand(
        np.array([1]), np.array([4.0]), np.array([3]), np.array([3, 3, -1]), np.zeros(3, bool), P
    )
    assert got.tolist() == [1]


def test_idle_robot_joins_a_large_fire() -> None:
    # extent 4 m: uncapped demand 2 + 4 = 6; one idle robot: 2 -> 3
    got = spare_demand(
        np.array([2]),
        np.array([4.0]),
        np.array([3]),
        np.array([3, 3, -1]),
        np.array([False, False, True]),
        P,
    )
    assert got.tolist() == [3]


def test_small_fire_takes_no_spare() -> None:
    # extent 0.5 m: uncapped demand 2 + 0 = 2, held 2: the idle robot stays idle
    got = spare_demand(
        np.array([2]),
        np.array([0.5]),
        np.array([3]),
        np.array([3, 3, -1]),
        np.array([False, False, True]),
        P,
    )
    assert got.tolist() == [2]


def test_extra_fighters_are_kept_next_plan() -> None:
    # the next plan: the spare robot fights fire 3 (held 3 > fire_demand 2): demand 3
    got = spare_demand(
        np.array([2]), np.array([4.0]), np.array([3]), np.array([3, 3, 3]), np.zeros(3, bool), P
    )
    assert got.tolist() == [3]


def test_two_fires_hand_computed() -> None:
    # fires 0 (extent 1.2 m: uncapped 3) and 1 (3.5 m: uncapped 5), demands 2 and 2,
    # three spare robots: shortfalls (1, 3) -> the larger gets one (1, 2) -> (1, 1): the
    # lower index -> (0, 1) -> fire 1: demands (3, 4)
    p = TacticsParams(fire_robots_min=2, fire_robots_max=2, robot_per_fire_m=1.0)
    got = spare_demand(
        np.array([2, 2]),
        np.array([1.2, 3.5]),
        np.array([0, 1]),
        np.array([0, 0, 1, 1, -1, -1, -1]),
        np.array([False] * 4 + [True] * 3),
        p,
    )
    assert got.tolist() == [3, 4]


def test_no_fire() -> None:
    got = spare_demand(
        np.zeros(0, np.int64),
        np.zeros(0),
        np.zeros(0, np.int64),
        np.array([-1, -1]),
        np.ones(2, bool),
        P,
    )
    assert got.tolist() == []


@pytest.mark.parametrize("seed", range(20))
def test_against_brute_force(seed: int) -> None:
    """Every robot a fire can use gets one (as many spares as the shortfalls allow), and
    the largest shortfall left is the least any allotment of that many leaves (brute
    force over every allotment)."""
    rng = np.random.default_rng(seed)
    n_f = int(rng.integers(1, 4))
    ext = rng.uniform(0.0, 4.0, n_f)
    need = rng.integers(1, 3, n_f)
    held = rng.integers(0, 3, n_f)
    task = np.concatenate([np.full(h, f) for f, h in enumerate(held)] + [np.full(3, -1)])
    spare = np.zeros(len(task), bool)
    n_spare = int(rng.integers(1, 4))
    spare[-3:][:n_spare] = True
    got = spare_demand(need, ext, np.arange(n_f), task, spare, P)
    base = np.maximum(need, held)
    uncapped = 2 + np.floor(ext).astype(int)
    short = np.maximum(uncapped - base, 0)
    assert np.all(got >= base)
    add = got - base
    assert np.all(add <= short)
    assert add.sum() == min(n_spare, short.sum())
    best = min(
        int(np.max(uncapped - base - np.array(a)))
        for a in itertools.product(*[range(s + 1) for s in short])
        if sum(a) == add.sum()
    )
    assert int(np.max(uncapped - got)) == best


@pytest.mark.parametrize("on", [False, True])
def test_plan_sends_the_idle_robot_only_when_on(on: bool) -> None:
    """The plan (``_step._plan``): two fighters on a 1.05 m fire (uncapped demand 3), the
    third robot idle, the floor searched: with ``spare_fight`` it joins the fire; without
    it, it stays idle (``fire_robots_max`` 2)."""
    from dataclasses import replace

    from firefleet.control.mission import tactics_init, tactics_step
    from firefleet.control.mission._knowledge import fires_of
    from firefleet.control.mission._params import FIGHT, IDLE
    from firefleet.control.mission._step import _plan
    from firefleet.world import load_map
    from tests.control.mission._harness import fire_obs

    p = TacticsParams(fire_robots_max=2, fire_robots_min=2, spare_fight=on)
    pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0], [1.0, 4.2, 0.0]])
    state = tactics_init(load_map("office"), pose, p)
    fire = np.array([[4.0, 5.0], [4.7, 5.0], [5.4, 5.0], [6.1, 5.0]])
    state, _ = tactics_step(state, fire_obs(pose, fire), p, 0.01)
    ids, _, ext = fires_of(state.knowledge)
    assert len(ids) == 1
    assert 1.0 <= ext[0] < 2.0
    state = replace(
        state,
        mode=np.array([FIGHT, FIGHT, IDLE], dtype=state.mode.dtype),
        task_fire=np.array([ids[0], ids[0], -1]),
        covered_coarse=np.ones_like(state.covered_coarse),
    )
    new = _plan(state, pose, np.full(3, 20.0), np.ones(3, bool), p)
    want = [ids[0]] * 3 if on else [ids[0], ids[0], -1]
    assert new.task_fire.tolist() == want
    assert (new.mode[2] == FIGHT) == on
