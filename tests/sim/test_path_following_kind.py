"""The path-following kind: the whole hierarchy on the world loop, compiled."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from firefleet import compute_metrics, load_scenario, simulate
from firefleet.errors import InputError
from firefleet.scenarios import parse_scenario
from firefleet.scenarios.schema import PathFollowing


def test_team_run_equals_robots_run_one_by_one() -> None:
    # robots interact only through the common schedule: with ideal encoders (no random
    # phase to draw) each robot of the team moves exactly as it does alone
    team = load_scenario("coop-different-paths")
    cmd = team.command
    assert isinstance(cmd, PathFollowing)
    ideal = dataclasses.replace(
        team, encoder=dataclasses.replace(team.encoder, counts_per_rev=0, window_steps=1)
    )
    together = simulate(ideal)
    for i in range(3):
        alone = dataclasses.replace(
            ideal,
            poses=(ideal.poses[i],),
            command=dataclasses.replace(cmd, paths=(cmd.paths[i],)),
            claims=(),  # the team's claims name robots 2 and 3
        )
        single = simulate(alone)
        np.testing.assert_array_equal(single.pose[:, 0], together.pose[:, i])
        for key in ("y_err_m", "v_ref_m_s", "omega_ref_rad_s"):
            np.testing.assert_array_equal(single.extra[key][:, 0], together.extra[key][:, i])


def test_same_seed_same_run() -> None:
    scn = load_scenario("coop-same-path")
    a, b = simulate(scn).arrays(), simulate(scn).arrays()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    c = simulate(scn, seed=1).arrays()
    assert not np.array_equal(a["wheel_speed_measured_rad_s"], c["wheel_speed_measured_rad_s"])


def test_robot_on_a_straight_path_stays_on_it_and_stops_at_its_end() -> None:
    # ideal encoders: both wheels identical, so the robot cannot leave the x axis
    scn = parse_scenario(
        {
            "name": "line",
            "title": "line",
            "duration_s": 30.0,
            "poses": [[0.0, 0.0, 0.0]],
            "encoder": {"counts_per_rev": 0, "window_steps": 1},
            "command": {
                "kind": "path-following",
                "paths": [{"coefficients": [0.0, 0.0], "x_start_m": 0.0, "x_end_m": 5.0}],
                "trajectory_s": 20.0,
                "pieces": 50,
            },
        }
    )
    r = simulate(scn)
    np.testing.assert_array_equal(r.pose[:, 0, 1:], 0.0)
    # it stops once past its end, within the braking distance of the wheel loop
    assert 5.0 <= r.pose[-1, 0, 0] <= 5.03
    # never backwards, but for the wheel loop's settling when it stops (< 1 mm)
    assert float(np.min(np.diff(r.pose[:, 0, 0]))) > -1e-3
    # odometry with an ideal encoder is the truth
    np.testing.assert_allclose(r.extra["odometry_pose"], r.pose, atol=1e-12)


def test_path_count_must_match_the_team() -> None:
    data = {
        "name": "x",
        "title": "x",
        "duration_s": 5.0,
        "poses": [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
        "command": {
            "kind": "path-following",
            "paths": [{"coefficients": [0.0], "x_start_m": 0.0, "x_end_m": 1.0}],
            "trajectory_s": 4.0,
        },
    }
    with pytest.raises(InputError, match="one path per robot, got 1 paths for 2 poses"):
        parse_scenario(data)
    data["poses"] = [[0.0, 0.0, 0.0]]
    data["command"]["trajectory_s"] = 9.0  # type: ignore[index]
    with pytest.raises(InputError, match="longer than duration_s"):
        parse_scenario(data)


def test_parallel_kernel_equals_serial(monkeypatch: pytest.MonkeyPatch) -> None:
    from firefleet.sim import _kernels
    from firefleet.sim.kinds import path_following

    base = load_scenario("coop-different-paths")
    cmd = base.command
    assert isinstance(cmd, PathFollowing)
    big = dataclasses.replace(
        base,
        poses=base.poses * 22,
        command=dataclasses.replace(cmd, paths=cmd.paths * 22, trajectory_s=10.0),
        duration_s=10.0,
    )
    assert big.n_robots >= _kernels.PARALLEL_MIN_ROBOTS_ONE_PIECE
    parallel = simulate(big).arrays()
    monkeypatch.setattr(path_following, "PARALLEL_MIN_ROBOTS", 10**9)
    monkeypatch.setattr(path_following, "PARALLEL_MIN_ROBOTS_ONE_PIECE", 10**9)
    serial = simulate(big).arrays()
    for key in parallel:
        np.testing.assert_array_equal(parallel[key], serial[key], err_msg=key)


def test_robot_turned_away_from_its_path_waits_then_is_not_stranded() -> None:
    # robot 1 of experiment 2 starts below its path facing down (heading -pi/2): along its
    # heading (eq. 10) its point is behind it for good; along the path it is ahead of its
    # point only until the schedule passes it, then it turns back and catches the path
    scn = load_scenario("coop-same-path")
    m = compute_metrics(simulate(scn))
    wait, capture = m["wait_time_s"], m["capture_time_s"]
    assert isinstance(wait, list)
    assert isinstance(capture, list)
    assert wait[0] > 0
    assert math.isfinite(capture[0])
    assert capture[0] > wait[0]
    rms = m["cross_track_rms_after_capture_m"]
    assert isinstance(rms, list)
    assert rms[0] <= 0.03
