"""The mission's per-tick contact log gives the collisions that every tick's poses give,
and the mission records its robots at 10 Hz."""

from __future__ import annotations

import dataclasses

import numpy as np

import firefleet
from firefleet.sim.kinds._mission_contacts import ContactCheck, touched_walls
from firefleet.sim.kinds.mission import _touching
from firefleet.world import load_map


def test_contact_log_equals_the_test_on_every_tick() -> None:
    """Random walks of six robots in the office, two of them driven into each other and
    one along a wall: the robots the log calls touching are the ones the metric's test
    on all the poses (T, N, 2) finds, touching or not."""
    grid = load_map("office")
    rng = np.random.default_rng(3)
    radius = 0.15
    t, n = 300, 6
    start = np.array([[1.0, 5.0], [1.6, 4.6], [4.0, 5.2], [6.0, 5.0], [3.0, 4.8], [3.8, 4.8]])
    xy = start[None] + np.cumsum(rng.normal(0.0, 0.01, (t, n, 2)), axis=0)
    xy[:, 4, 0] += np.linspace(0.0, 0.4, t)  # robot 4 drives into robot 5
    xy[:, 1, 1] = np.linspace(4.6, 1.0, t)  # robot 1 runs south, into whatever is there
    pose = np.concatenate([xy, np.zeros((t, n, 1))], axis=2)
    check = ContactCheck.of(grid, radius)
    log = check.init(n)
    for k in range(t):
        check.check(log, pose[k])
    out = check.final(log)
    got = touched_walls(grid, out["near_wall_xy_m"], n, radius) | (out["touched_robot"] > 0.5)
    want = _touching(grid, xy, radius)
    assert got.tolist() == want.tolist()
    assert want.any()
    assert not want.all()
    # the bound keeps far fewer points than every tick's
    assert len(out["near_wall_xy_m"]) < t * n
    # the ticks of a quiet stretch, checked at once: the same log, entry for entry
    batch = check.init(n)
    for k in range(0, t, 37):
        check.check_ticks(batch, pose[k : k + 37])
    assert len(batch["near_wall"]) == len(log["near_wall"])
    for a, b in zip(batch["near_wall"], log["near_wall"], strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(batch["touched_robot"], log["touched_robot"])


def test_mission_records_its_robots_at_ten_hertz() -> None:
    scenario = dataclasses.replace(firefleet.load_scenario("mission-office"), duration_s=1.05)
    result = firefleet.simulate(scenario)
    assert np.allclose(result.t, [*np.arange(0.0, 1.01, 0.1), 1.05])
    assert result.pose.shape == (12, 3, 3)
    assert result.arrays()["mode"].shape == (12, 3)
    assert np.asarray(result.extra["touched_robot"]).shape == (3,)


def test_compiled_candidates_equal_the_grids_cells() -> None:
    """The kernel's near-wall flags are the grid's cell lookup (NumPy, ``cell_of`` and
    ``contains``) on points on and off the map, on cell edges too; its pair flag holds
    whenever two points are closer than two radii."""
    from firefleet.sim.kinds._mission_contacts import _candidates

    grid = load_map("office")
    check = ContactCheck.of(grid, 0.15)
    rng = np.random.default_rng(0)
    x0, x1, y0, y1 = grid.extent_m
    pts = np.c_[rng.uniform(x0 - 1, x1 + 1, 4000), rng.uniform(y0 - 1, y1 + 1, 4000)]
    edges = grid.center_of(np.argwhere(check.near_wall)[:500]) + 0.5 * grid.resolution_m
    pts = np.vstack([pts, edges, edges - 0.5 * grid.resolution_m])
    h, w = grid.shape
    rc = grid.cell_of(pts)
    want = (
        ~grid.contains(pts)
        | check.near_wall[np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)]
    )
    got = np.empty(len(pts), dtype=bool)
    for k in range(0, len(pts), 50):  # teams of 50
        team = np.ascontiguousarray(pts[k : k + 50])
        near = np.empty(len(team), dtype=bool)
        ox, oy = (float(v) for v in grid.origin_m)
        close = _candidates(team, ox, oy, grid.resolution_m, check.near_wall, 0.15, near)
        got[k : k + 50] = near
        d = np.hypot(team[None, :, 0] - team[:, None, 0], team[None, :, 1] - team[:, None, 1])
        np.fill_diagonal(d, np.inf)
        assert close or not (d < 0.3).any()
    assert got.tolist() == want.tolist()
    assert want.any()
    assert not want.all()
