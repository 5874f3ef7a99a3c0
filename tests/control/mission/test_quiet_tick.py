"""The tactics' quiet-tick path: where it answers, the full step would have returned the
same state and orders (it changes nothing)."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

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
        m.setattr(step_mod, "_quiet", lambda *a: False)
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
    real = step_mod._quiet

    def spy(state: TacticsState, obs: TacticsObservation, p: TacticsParams) -> bool:
        out = real(state, obs, p)
        if out:
            quiet.append((state, obs))
        return out

    monkeypatch.setattr(step_mod, "_quiet", spy)
    world.run(8.0)
    monkeypatch.setattr(step_mod, "_quiet", real)
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
    assert step_mod._quiet(state, obs, params) == quiet
    got, orders = tactics_step(state, obs, params, 0.01)
    if full is state:
        assert got is state
        assert orders is state.orders
