"""mission-large at scale: the collision count's fast path equals the brute force, and
the scenario validates (50 robots in the lobby, fires and people in rooms of floor100)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from firefleet import load_scenario
from firefleet.sim.kinds._navigate_metrics import clearance_m
from firefleet.sim.kinds.mission import _touching
from firefleet.world import load_map
from firefleet.world._floor100 import floor100_rooms

LARGE = Path(__file__).parents[2] / "examples" / "missions" / "mission-large.yaml"


@pytest.mark.parametrize("name", ["office", "floor100"])
def test_touching_equals_the_brute_force(name: str) -> None:
    """Walls by the exact clearance at every point, robots by every pair at every tick."""
    grid = load_map(name)
    rng = np.random.default_rng(3)
    radius = 0.15
    for t, n in ((300, 12), (2, 12)):
        xy = rng.uniform((0.0, 0.0), (grid.width_m, grid.height_m), size=(t, n, 2))
        xy[:, 0] = xy[:, 1] + [0.2, 0.0]  # robots 0 and 1 touch at every tick
        wall = (clearance_m(grid, xy) < radius).any(axis=0)
        d = np.linalg.norm(xy[:, :, None] - xy[:, None, :], axis=-1)
        d[:, np.arange(n), np.arange(n)] = np.inf
        mate = (d < 2 * radius).any(axis=(0, 2))
        got = _touching(grid, xy, radius)
        assert got.tolist() == (wall | mate).tolist()
        assert got[0]
        assert got[1]
    # a robot in the middle of a room touches nothing
    rooms = floor100_rooms() if name == "floor100" else None
    if rooms is not None:
        centre = rooms[0, [0, 1]].mean(), rooms[0, [2, 3]].mean()
        assert not _touching(grid, np.array([[centre]]), radius)[0]


def test_the_scenario_is_in_the_building() -> None:
    scenario = load_scenario(LARGE)
    assert scenario.n_robots == 50
    assert scenario.world is not None
    grid = scenario.world.grid()
    lobby = floor100_rooms()[-1]
    xy = scenario.initial_poses[:, :2]
    assert ((xy[:, 0] > lobby[0]) & (xy[:, 0] < lobby[1])).all()
    assert ((xy[:, 1] > lobby[2]) & (xy[:, 1] < lobby[3])).all()
    assert (clearance_m(grid, xy) > 0.3).all()
    d = np.linalg.norm(xy[:, None] - xy[None], axis=-1) + np.eye(50) * 9.0
    assert d.min() >= 0.9
    fires = np.array([[f.x_m, f.y_m] for f in scenario.world.fires])
    rooms = floor100_rooms()[:-1]
    inside = (
        (fires[:, None, 0] > rooms[None, :, 0])
        & (fires[:, None, 0] < rooms[None, :, 1])
        & (fires[:, None, 1] > rooms[None, :, 2])
        & (fires[:, None, 1] < rooms[None, :, 3])
    )
    # ten fires, each in a room or hall, no two in the same one
    which = {tuple(rooms[np.argmax(row), :4]) for row in inside}
    assert len(fires) == 10
    assert inside.any(axis=1).all()
    assert len(which) == 10


def test_the_hose_cabinets_are_at_the_corridor_crossings() -> None:
    """Twelve refill points, each in a corridor (inside no room, hall or the lobby) and
    at least 1 m from a wall."""
    scenario = load_scenario(LARGE)
    assert scenario.world is not None
    grid = scenario.world.grid()
    points = np.array(scenario.command.refill_points_m)  # type: ignore[union-attr]
    assert points.shape == (12, 2)
    rooms = floor100_rooms()
    inside = (
        (points[:, None, 0] > rooms[None, :, 0])
        & (points[:, None, 0] < rooms[None, :, 1])
        & (points[:, None, 1] > rooms[None, :, 2])
        & (points[:, None, 1] < rooms[None, :, 3])
    )
    assert not inside.any()
    assert (clearance_m(grid, points) >= 1.0).all()
