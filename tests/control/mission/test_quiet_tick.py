"""The tactics' quiet-tick path: where it answers, the full step would have returned the
same state and orders (it changes nothing)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import firefleet.control.mission._quiet as quiet_mod
import firefleet.control.mission._step as step_mod
from firefleet.control.mission import (
    TacticsObservation,
    TacticsParams,
    TacticsState,
    tactics_init,
    tactics_step,
)
from firefleet.world import load_map

from ._harness import World


def _full(
    monkeypatch: pytest.MonkeyPatch,
    state: TacticsState,
    obs: TacticsObservation,
    params: TacticsParams,
    dt_s: float,
) -> tuple[TacticsState, Any]:
    """The step without the quiet path (the reference)."""
    with monkeypatch.context() as m:
        m.setattr(step_mod, "is_quiet", lambda *a: False)
        return tactics_step(state, obs, params, dt_s)


def test_quiet_ticks_of_a_run_change_nothing_in_the_full_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A fire and a person seen, a tank that runs dry and refills: at every tick the
    quiet path took, the full step returns the state it was given."""
    params = TacticsParams(tank_l=2.0, flow_l_s=0.5)
    world = World(
        load_map("office"),
        params,
        np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0]]),
        fire_xy=np.array([[6.0, 5.0]]),
        people_xy=np.array([[4.0, 4.0]]),
        dt_s=0.01,
    )
    quiet: list[tuple[TacticsState, TacticsObservation]] = []
    real = quiet_mod.is_quiet

    def spy(state: TacticsState, obs: TacticsObservation, p: TacticsParams) -> bool:
        out = real(state, obs, p)
        if out:
            quiet.append((state, obs))
        return out

    monkeypatch.setattr(step_mod, "is_quiet", spy)
    world.run(8.0)
    monkeypatch.setattr(step_mod, "is_quiet", real)
    # the harness looks with every camera at every tick: once a fire is known, no tick is
    # quiet; before, nine in ten
    assert 100 < len(quiet) < 800
    for state, obs in quiet:
        new, orders = _full(monkeypatch, state, obs, params, 0.01)
        assert new is state
        assert orders is state.orders


@pytest.mark.parametrize(
    ("change", "quiet"),
    [
        ({}, True),
        ({"t_s": 0.1}, False),  # navigation due
        ({"fire_xy_m": np.array([[6.0, 5.0]]), "fire_robot": np.array([0])}, False),
        ({"person_xy_m": np.array([[4.0, 4.0]]), "person_robot": np.array([1])}, False),
        ({"damaged": np.array([False, True])}, False),
        ({"tank_l": np.array([0.0, 20.0])}, False),
        ({"air_c": np.array([20.0, 500.0])}, False),
        ({"air_c": np.array([20.0, 30.0])}, True),
        ({"looked": np.array([True, False])}, True),  # no fire known: nothing to update
    ],
)
def test_quiet_exactly_when_the_full_step_changes_nothing(
    monkeypatch: pytest.MonkeyPatch, change: dict[str, Any], quiet: bool
) -> None:
    params = TacticsParams()
    pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0]])
    state = tactics_init(load_map("office"), pose, params)
    obs = TacticsObservation(
        t_s=0.0,
        pose_m=pose,
        fire_xy_m=np.zeros((0, 2)),
        fire_robot=np.zeros(0, int),
        person_xy_m=np.zeros((0, 2)),
        person_robot=np.zeros(0, int),
        ranges={},
        tank_l=np.full(2, 20.0),
        damaged=np.zeros(2, bool),
        alive=np.ones(2, bool),
    )
    state, _ = tactics_step(state, obs, params, 0.01)  # the first plan and orders
    obs = dataclasses.replace(obs, **{"t_s": 0.05, **change})
    full, _ = _full(monkeypatch, state, obs, params, 0.01)
    assert (full is state) == quiet
    assert quiet_mod.is_quiet(state, obs, params) == quiet
    got, orders = tactics_step(state, obs, params, 0.01)
    if full is state:
        assert got is state
        assert orders is state.orders


def test_compiled_robot_tests_equal_the_array_form() -> None:
    """``robots_quiet`` against the full step's array expressions (lost robots, looks at
    a known fire, ``tank_flags``, ``_upkeep.too_hot``) on random teams."""
    from firefleet.control.mission._params import EXPLORE, IDLE, REFILL
    from firefleet.control.mission._plan import _empty_l

    rng = np.random.default_rng(11)
    params = TacticsParams()
    empty_l = _empty_l(params)
    low_l = params.low_tank_frac * params.tank_l
    full_l = 0.98 * params.tank_l
    quiet = 0
    for _ in range(3000):
        n = int(rng.integers(1, 6))
        mode = rng.integers(0, 6, n).astype(np.int8)
        tank = rng.choice([0.0, empty_l, 0.5 * low_l, low_l, 0.5 * params.tank_l, full_l], n)
        alive = rng.random(n) > 0.05
        damaged = rng.random(n) < 0.05
        known = ~(alive & ~damaged) & (rng.random(n) < 0.9)
        looked = rng.random(n) < 0.2
        air = rng.choice([20.0, params.retreat_c, params.retreat_c + 1.0], n, p=[0.9, 0.05, 0.05])
        has_air = bool(rng.random() < 0.5)
        spots = bool(rng.random() < 0.5)
        working = alive & ~damaged
        idle = (mode == EXPLORE) | (mode == IDLE)
        empty = working & (tank <= empty_l) & (mode != REFILL)
        if spots:
            empty |= working & idle & (tank < low_l)
        full = (mode == REFILL) & (tank >= full_l)
        want = not (
            (~working & ~known).any()
            or (spots and (working & looked).any())
            or empty.any()
            or full.any()
            or (has_air and (working & (air >= params.retreat_c)).any())
        )
        got = quiet_mod.robots_quiet(
            mode, tank, alive, damaged, known, looked, air, has_air, spots, empty_l, low_l,
            full_l, params.retreat_c,
        )  # fmt: skip
        assert got == want
        quiet += want
    assert 100 < quiet < 2900
