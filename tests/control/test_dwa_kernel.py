"""The dynamic window's pruned obstacle search gives the brute-force search's commands
and clearances exactly (tests/control/_dwa_reference.py: every arc against every
obstacle), on random teams among random walls, range returns and teammates."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from firefleet.control.navigation._dwa import DwaParams, _dwa_batch

from ._dwa_reference import _dwa_batch as _dwa_batch_reference

MISSION_WINDOW = DwaParams(robot_radius_m=0.2, n_v=5, n_omega=9, n_steps=8)
"""The mission's dynamic window (the robot's 0.15 m radius plus the 0.05 m margin)."""


def _args(params: DwaParams, dt_s: float) -> tuple[Any, ...]:
    return (
        dt_s,
        params.wheel_speed_max_m_s,
        params.wheel_accel_m_s2,
        params.axle_length_m,
        params.robot_radius_m,
        params.horizon_s,
        params.n_v,
        params.n_omega,
        params.n_steps,
        params.clearance_cap_m,
        params.clearance_weight,
    )


@pytest.mark.parametrize("seed", range(8))
def test_pruned_search_equals_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, m = 6, int(rng.integers(1, 300))
    pose = np.c_[rng.uniform(0.0, 4.0, (n, 2)), rng.uniform(-np.pi, np.pi, n)]
    last = np.c_[rng.uniform(0.0, 0.7, n), rng.uniform(-2.0, 2.0, n)]
    ref = np.c_[rng.uniform(0.0, 0.7, n), rng.uniform(-3.0, 3.0, n)]
    obs = rng.uniform(-1.0, 5.0, (n, m, 2))
    obs[rng.random((n, m)) < 0.2] = 1e9  # padding
    rad = np.where(rng.random((n, m)) < 0.3, 0.15, rng.uniform(0.0, 0.18, (n, m)))
    params = DwaParams(n_v=5, n_omega=9, n_steps=8) if seed % 2 else DwaParams()
    turn = rng.random(n) < 0.5  # robots flagged stuck: the asked turn in place tried too
    args = (*_args(params, 0.1), turn)
    got = _dwa_batch(pose, last, ref, obs, rad, *args)
    want = _dwa_batch_reference(pose, last, ref, obs, rad, *args)
    np.testing.assert_array_equal(got, want)
    assert np.isfinite(got[:, 2]).all()


def test_stuck_with_no_speed_admissible_it_turns_as_asked_in_place() -> None:
    """A robot by a door's jamb, as traced (apartment seed 3 at 720 s): the jambs' wall
    cells, two range returns and a teammate behind it; the path follower asks 0.28 m/s
    and 0.29 rad/s. No speed is admissible (its disc touches the jamb), so the window
    keeps v = 0. Not flagged stuck, it keeps the grid's turn rate nearest its last,
    -0.02 rad/s (the grid's rates lie 0.625 rad/s apart: -0.02 and 0.605 score within a
    hair of each other; it held it for 240 s); flagged stuck, it turns at the asked
    rate."""
    from firefleet.control.navigation._dwa import dwa_command

    p = MISSION_WINDOW
    pose = np.array([[4.74037788067119, 9.67678761473593, 2.907046991122833]])
    # the door's two jambs: the wall cells' centres (discs of half a cell's diagonal)
    south = [[x, y] for y in np.round(np.arange(8.475, 9.48, 0.05), 3) for x in (4.525, 4.625)]
    north = [[x, y] for y in np.round(np.arange(10.425, 10.88, 0.05), 3) for x in (4.525, 4.625)]
    wall = np.array(south + north + [[4.575, 9.475], [4.575, 10.425]])
    returns = [[4.4926431323246785, 9.524609415437977], [5.313752365268165, 10.028999394358037]]
    mate = [[5.4930040205840305, 9.917284161038616]]  # a teammate behind it (0.2 m disc)
    pts = np.vstack([returns, mate, wall])[None]
    radii = np.r_[0.0, 0.0, 0.2, np.full(len(wall), 0.025 * np.sqrt(2.0))][None]
    ref = [[0.2769064330158617, 0.29133618810211004]]
    v, w, c = dwa_command(pose, [[0.0, -0.02]], ref, pts, radii, p, 0.1)
    assert (v[0], w[0]) == (0.0, pytest.approx(-0.02))
    assert c[0] < 0.0  # touching
    v, w, _ = dwa_command(pose, [[0.0, -0.02]], ref, pts, radii, p, 0.1, [True])
    assert v[0] == 0.0
    assert w[0] == pytest.approx(ref[0][1])


def test_a_stuck_robots_turn_stays_in_the_window_and_a_bad_flag_is_refused() -> None:
    """Still rolling (0.1 m/s, below one tick's braking) and flagged stuck, against a
    wall it touches: the turn in place it is given lies in the dynamic window (at v = 0
    the turn rates reach (a dt - v0) / (L / 2) from the last, not a dt / (L / 2)); a
    flag of the wrong shape is one clear error naming it."""
    from firefleet.control.navigation._dwa import dwa_command, in_window
    from firefleet.errors import InputError

    p = MISSION_WINDOW
    pose = np.array([[0.0, 0.0, 0.0]])
    wall = np.array([[[0.22, y] for y in np.arange(-0.5, 0.55, 0.05)]])  # touching, ahead
    radii = np.full(wall.shape[:2], 0.025 * np.sqrt(2.0))
    last = np.array([[0.1, 0.0]])
    ref = np.array([[0.3, 3.0]])  # asks a hard left turn
    v, w, _ = dwa_command(pose, last, ref, wall, radii, p, 0.1, [True])
    assert v[0] == 0.0
    limit = (p.wheel_accel_m_s2 * 0.1 - 0.1) / (p.axle_length_m / 2.0)
    assert w[0] == pytest.approx(limit)
    assert in_window(np.c_[v, w], last, p, 0.1).all()
    with pytest.raises(InputError, match="stuck"):
        dwa_command(pose, last, ref, wall, radii, p, 0.1, [True, False])
