"""``firefleet._frozen.replace`` makes what ``dataclasses.replace`` makes."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from firefleet._frozen import replace
from firefleet.control.mission import TacticsParams, tactics_init
from firefleet.control.mission._knowledge import Knowledge
from firefleet.control.mission._team import TacticsState
from firefleet.control.navigation import NavigationState
from firefleet.world import load_map


def _same(a: Any, b: Any) -> None:
    """The same class and every field the same object."""
    assert type(a) is type(b)
    for f in dataclasses.fields(a):
        assert getattr(a, f.name) is getattr(b, f.name), f.name
    assert a.__dict__.keys() == b.__dict__.keys()


def test_replace_equals_dataclasses_replace_on_the_tactics_states() -> None:
    pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0]])
    state = tactics_init(load_map("office"), pose, TacticsParams())
    assert isinstance(state, TacticsState)
    assert isinstance(state.nav, NavigationState)
    assert isinstance(state.knowledge, Knowledge)
    goals = np.zeros((2, 2))
    _same(
        replace(state, goal_xy_m=goals, pending=True),
        dataclasses.replace(state, goal_xy_m=goals, pending=True),
    )
    _same(replace(state), dataclasses.replace(state))
    cmd = np.ones((2, 2))
    _same(replace(state.nav, command=cmd), dataclasses.replace(state.nav, command=cmd))
    wet = np.zeros_like(state.knowledge.wet_l_m2)
    _same(
        replace(state.knowledge, wet_l_m2=wet), dataclasses.replace(state.knowledge, wet_l_m2=wet)
    )
    new = replace(state, pending=not state.pending)
    assert new is not state
    assert new.pending is not state.pending
    with pytest.raises(dataclasses.FrozenInstanceError):
        new.pending = False  # type: ignore[misc]


def test_replace_falls_back_where_the_constructor_does_more() -> None:
    # __post_init__ checks: TacticsParams's constructor runs, as dataclasses.replace runs it
    with pytest.raises(ValueError, match="standoff_m"):
        replace(TacticsParams(), standoff_m=-1.0)
    assert replace(TacticsParams(), standoff_m=2.0).standoff_m == 2.0

    @dataclasses.dataclass(frozen=True)
    class Init:
        x: float
        scale: dataclasses.InitVar[float] = 1.0
        y: float = dataclasses.field(init=False, default=0.0)

        def __post_init__(self, scale: float) -> None:
            object.__setattr__(self, "y", self.x * scale)

    assert replace(Init(2.0, 3.0), x=4.0).y == 4.0  # the constructor ran (scale 1)

    @dataclasses.dataclass(frozen=True)
    class Plain:
        x: float
        y: float = 0.0

    p = Plain(1.0)
    with pytest.raises(TypeError):
        replace(p, z=1.0)  # no such field: dataclasses.replace's error
    object.__setattr__(p, "extra", 1)  # more than its fields: dataclasses.replace drops it
    assert not hasattr(replace(p, y=2.0), "extra")
    assert replace(Plain(1.0), y=2.0) == Plain(1.0, 2.0)
