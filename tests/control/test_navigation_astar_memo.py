"""A*'s plans kept in their costmap (``Costmap._astar_memo``): the same answers as the
kernel asked anew, and never kept for a cost grid that may change."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

import firefleet.control.navigation._astar as astar_module
from firefleet.control.navigation import (
    Costmap,
    NavigationInputs,
    NavigationParams,
    astar,
    build_costmap,
    navigation_init,
    navigation_retarget,
    navigation_step,
)
from firefleet.world import OccupancyGrid


def _rooms() -> Costmap:
    occ = np.zeros((60, 90), dtype=bool)
    occ[:, 45] = True
    occ[25:35, 45] = False  # a door
    occ[30, 10:30] = True
    return build_costmap(OccupancyGrid(occ, ~occ, 0.05), inflation_m=0.12)


def _fresh(cm: Costmap) -> Costmap:
    """The same costmap as a new object (an empty memo)."""
    return Costmap(cm.grid, cm.clearance_m, cm.blocked, cm.cost, cm.inflation_m)


def _same(a: astar_module.AStarResult, b: astar_module.AStarResult) -> bool:
    if a.status != b.status or a.cost != b.cost:
        return False
    if a.cells is None or b.cells is None or a.xy_m is None or b.xy_m is None:
        return a.cells is None and b.cells is None and a.xy_m is None and b.xy_m is None
    return (
        a.cells.dtype == b.cells.dtype
        and np.array_equal(a.cells, b.cells)
        and a.xy_m.tobytes() == b.xy_m.tobytes()
    )


def _counting(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    kernel = astar_module._astar_kernel

    def counted(*args: Any) -> Any:
        calls.append(1)
        return kernel(*args)

    monkeypatch.setattr(astar_module, "_astar_kernel", counted)
    return calls


def test_a_kept_plan_equals_the_plan_made_anew(monkeypatch: pytest.MonkeyPatch) -> None:
    cm = _rooms()
    rng = np.random.default_rng(0)
    free = cm.grid.center_of(np.argwhere(~cm.blocked))
    pairs = [free[rng.choice(len(free), 2, replace=False)] for _ in range(12)]
    # the ends of the edges: the same cell twice, a goal beyond the wall, an end off the
    # map, a blocked end
    pairs += [np.array([free[0], free[0]]), np.array([free[0], free[-1]])]
    pairs += [np.array([free[5], [9.0, 9.0]]), np.array([free[5], [2.25, 1.5]])]
    calls = _counting(monkeypatch)
    first = [astar(cm, a, b) for a, b in pairs]
    made = len(calls)
    again = [astar(cm, a, b) for a, b in pairs]
    assert len(calls) == made  # every plan answered from the memo
    anew = [astar(_fresh(cm), a, b) for a, b in pairs]
    for x, y, z in zip(first, again, anew, strict=True):
        assert _same(x, y)
        assert _same(x, z)
    assert {r.status for r in first} >= {"ok", "goal_blocked"}


def test_the_same_cells_from_other_points_share_a_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    cm = _rooms()
    calls = _counting(monkeypatch)
    a = astar(cm, [0.52, 0.52], [4.02, 2.52])
    b = astar(cm, [0.53, 0.54], [4.03, 2.51])  # the same two cells
    assert len(calls) == 1
    assert a.cells is not None
    assert b.cells is not None
    assert b.xy_m is not None
    assert np.array_equal(a.cells, b.cells)
    assert b.xy_m[0].tolist() == [0.53, 0.54]  # the exact ends are the points asked
    assert b.xy_m[-1].tolist() == [4.03, 2.51]


def test_returned_cells_are_copies(monkeypatch: pytest.MonkeyPatch) -> None:
    cm = _rooms()
    a = astar(cm, [0.5, 0.5], [4.0, 2.5])
    assert a.cells is not None
    kept = a.cells.copy()
    a.cells[:] = -7  # a caller writing into its result does not spoil the memo
    b = astar(cm, [0.5, 0.5], [4.0, 2.5])
    assert b.cells is not None
    assert np.array_equal(b.cells, kept)


def test_a_cost_grid_that_may_change_is_not_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    cm = _rooms()
    writable = np.array(cm.cost)  # writable
    read_only_view = writable.view()
    read_only_view.setflags(write=False)  # read-only, but its data may still change
    for cost in (writable, read_only_view):
        live = Costmap(cm.grid, cm.clearance_m, cm.blocked, cost, cm.inflation_m)
        calls = _counting(monkeypatch)
        a = astar(live, [0.5, 0.5], [4.0, 2.5])
        writable[:, 60:] += 5.0  # the far room dearer: the plan must see it
        b = astar(live, [0.5, 0.5], [4.0, 2.5])
        assert len(calls) == 2
        assert live._astar_memo == {}
        assert b.cost > a.cost
        dearer = Costmap(cm.grid, cm.clearance_m, cm.blocked, writable.copy(), cm.inflation_m)
        assert _same(b, astar(dearer, [0.5, 0.5], [4.0, 2.5]))
        writable[:, 60:] -= 5.0
        monkeypatch.undo()


def test_the_memo_keeps_the_last_plans_only(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(astar_module, "_MEMO_SIZE", 3)
    cm = _rooms()
    goals = [[4.0, 0.5 + 0.25 * k] for k in range(5)]
    for goal in goals:
        astar(cm, [0.5, 0.5], goal)
    assert len(cm._astar_memo) == 3
    calls = _counting(monkeypatch)
    astar(cm, [0.5, 0.5], goals[-1])  # kept
    astar(cm, [0.5, 0.5], goals[0])  # dropped: made anew
    assert len(calls) == 1


def test_a_replaced_costmap_starts_empty() -> None:
    cm = _rooms()
    astar(cm, [0.5, 0.5], [4.0, 2.5])
    assert len(cm._astar_memo) == 1
    assert replace(cm, inflation_m=cm.inflation_m)._astar_memo == {}


def test_plans_pass_to_an_equal_costmap_only(monkeypatch: pytest.MonkeyPatch) -> None:
    cm = _rooms()
    pairs = [([0.5, 0.5], [4.0, 2.5]), ([1.0, 2.5], [3.5, 0.5])]
    first = [astar(cm, a, b) for a, b in pairs]
    calls = _counting(monkeypatch)
    same = _fresh(cm)  # a new object with the same (frozen) cost grid
    astar_module.adopt_plans(same, cm)
    assert [_same(astar(same, a, b), r) for (a, b), r in zip(pairs, first, strict=True)] == [
        True,
        True,
    ]
    assert calls == []
    # an equal grid in another array is adopted too
    copied = np.array(cm.cost)
    copied.setflags(write=False)
    twin = Costmap(cm.grid, cm.clearance_m, cm.blocked, copied, cm.inflation_m)
    astar_module.adopt_plans(twin, cm)
    assert len(twin._astar_memo) == 2
    # not: another price, a cost grid that may change, a costmap with plans of its own
    dearer = np.array(cm.cost)
    dearer[:, 60:] += 1.0
    dearer.setflags(write=False)
    for cost in (dearer, np.array(cm.cost)):
        other = Costmap(cm.grid, cm.clearance_m, cm.blocked, cost, cm.inflation_m)
        astar_module.adopt_plans(other, cm)
        assert other._astar_memo == {}
    own = _fresh(cm)
    astar(own, [2.0, 0.5], [2.0, 2.5])
    astar_module.adopt_plans(own, cm)
    assert len(own._astar_memo) == 1
    assert calls == [1]
    # another resolution: the same numbers are another map
    coarse = OccupancyGrid(~cm.grid.free, cm.grid.free, 0.1)
    scaled = Costmap(coarse, cm.clearance_m, cm.blocked, cm.cost, cm.inflation_m)
    astar_module.adopt_plans(scaled, cm)
    assert scaled._astar_memo == {}


def test_navigation_adopts_the_plans_of_its_last_costmap(monkeypatch: pytest.MonkeyPatch) -> None:
    """A caller swapping the navigation's costmap for an equal one (the mission prices
    the fires anew at every plan) plans nothing again: the step's outputs are those of
    the step on the old costmap."""
    cm = _rooms()
    params = NavigationParams()
    pose = np.array([[0.6, 0.6, 0.0], [0.6, 2.4, 0.0]])
    goals = np.array([[4.0, 2.5], [4.0, 0.6]])
    state = navigation_init(cm.grid, pose, goals, params)
    inputs = NavigationInputs(pose, {}, pose[:, :2], 0.0)
    state, _, _ = navigation_step(state, inputs, params, 0.1)
    assert state.planned_on is state.costmap
    again = navigation_retarget(state, goals, [True, True])
    calls = _counting(monkeypatch)
    ref, v_ref, w_ref = navigation_step(again, inputs, params, 0.1)
    made = len(calls)
    swapped = replace(again, costmap=_fresh(again.costmap))
    new, v, w = navigation_step(swapped, inputs, params, 0.1)
    assert len(calls) == made
    assert new.planned_on is swapped.costmap
    assert v.tobytes() == v_ref.tobytes()
    assert w.tobytes() == w_ref.tobytes()
    for a, b in zip(new.samples, ref.samples, strict=True):
        assert a.tobytes() == b.tobytes()
