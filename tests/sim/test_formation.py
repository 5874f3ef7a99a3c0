"""The formation runner, its metrics and its CLI outputs."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

from firefleet import compute_metrics, load_scenario, simulate
from firefleet.cli import main
from firefleet.errors import InputError
from firefleet.models.mass_damper import MassDamperParams, mass_damper_step
from firefleet.scenarios.schema import Formation, LeaderPath, Scenario, parse_scenario
from firefleet.sim import formation as formation_module
from firefleet.sim.formation import (
    FormationDivergedError,
    formation_metrics,
    leader_trajectory,
    spacing_error_deg,
    start_positions,
    substeps,
)
from firefleet.sim.result import SimResult


def _scenario(**command: Any) -> Scenario:
    base: dict[str, Any] = {
        "name": "f",
        "title": "t",
        "duration_s": 10.0,
        "poses": [[0.0, 0.0, 0.0]] * 3,
        "command": {"kind": "formation", **command},
    }
    return parse_scenario(base)


def _shorter(scn: Scenario, duration_s: float) -> Scenario:
    """``scn`` cut to ``duration_s``, its shape metrics over the whole run."""
    assert isinstance(scn.command, Formation)
    cmd = dataclasses.replace(scn.command, formed_by_s=0.0)
    return dataclasses.replace(scn, duration_s=duration_s, command=cmd)


def test_leader_trapezoid_by_hand() -> None:
    path = LeaderPath(waypoints_m=((1.0, 2.0), (11.0, 2.0)), speed_m_s=0.5, accel_m_s2=0.25)
    t = np.array([0.0, 1.0, 2.0, 12.0, 21.0, 22.0, 30.0])
    xy, v, a = leader_trajectory(path, t)
    # accelerate 2 s over 0.5 m, cruise 9 m in 18 s, brake 2 s: at rest at x = 11 after 22 s
    # s(1) = 0.125; s(2) = 0.5; s(12) = 0.5 + 5; s(21) = 10 - 0.125; s(22) = 10
    np.testing.assert_allclose(xy[:, 0] - 1.0, [0, 0.125, 0.5, 5.5, 9.875, 10.0, 10.0], atol=1e-12)
    np.testing.assert_allclose(xy[:, 1], 2.0, atol=0)
    np.testing.assert_allclose(v[:, 0], [0, 0.25, 0.5, 0.5, 0.25, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(a[:, 0], [0, 0.25, 0.0, 0.0, -0.25, 0.0, 0.0], atol=1e-12)


def test_leader_velocity_is_the_derivative_of_its_position() -> None:
    path = LeaderPath(
        waypoints_m=((0.0, 0.0), (4.0, 0.0), (4.0, 3.0)), speed_m_s=0.4, accel_m_s2=0.2, start_s=1
    )
    t = np.linspace(0.0, 25.0, 25001)
    xy, v, _ = leader_trajectory(path, t)
    numeric = np.gradient(xy, t, axis=0)
    # central differences on a 1 ms grid: error ~ a dt = 2e-4 m/s away from the corner
    # and the speed-profile kinks, where one sample sees both sides (skip those)
    corner = np.abs(t - (1.0 + 2.0 + (4.0 - 0.4) / 0.4)) < 0.01  # reached x = 4 at 12 s
    ok = ~corner
    np.testing.assert_allclose(numeric[ok], v[ok], atol=2e-3)
    np.testing.assert_allclose(xy[-1], [4.0, 3.0], atol=1e-12)


def test_spacing_error_by_hand() -> None:
    leader = np.zeros((1, 2))
    pts = np.array([[[1.0, 0.0], [0.0, 2.0], [-3.0, 0.0]]])  # at 0, 90 and 180 degrees
    # gaps 90, 90, 180 against 120: the worst is 60 degrees
    np.testing.assert_allclose(spacing_error_deg(pts, leader), [60.0], rtol=1e-14)
    square = np.array([[[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]])
    np.testing.assert_allclose(spacing_error_deg(square, leader), [0.0], atol=1e-12)


def test_metrics_on_a_hand_built_run() -> None:
    scn = _scenario(
        alpha_m=2.0, robot_radius_m=0.15, obstacles=[{"x_m": 0, "y_m": 5, "radius_m": 1}]
    )
    t = np.array([0.0, 1.0])
    pts = np.array([[[2.1, 0.0], [-2.0, 0.0], [0.0, 3.0]], [[2.0, 0.0], [-2.0, 0.0], [0.0, 2.0]]])
    pose = np.concatenate([pts, np.zeros((2, 3, 1))], axis=2)
    empty = np.zeros((2, 3, 0))
    result = SimResult(
        scenario=scn,
        t=t,
        pose=pose,
        wheel_speed_rad_s=empty,
        wheel_speed_measured_rad_s=empty,
        wheel_speed_ref_rad_s=empty,
        current_a=empty,
        voltage_v=empty,
        load_torque_n_m=empty,
        extra={
            "leader_xy_m": np.zeros((2, 2)),
            "formation_xy_m": pts,
            "robot_active": np.ones((2, 3)),
        },
    )
    m = formation_metrics(result)
    # at t = 0: robot 3 at 3 m (error 1 m); obstacle gap 5 - 3 - 0.15 - 1 = 0.85 m
    assert m["radius_error_max_m"] == pytest.approx(1.0, abs=1e-12)
    assert m["radius_settling_time_s"] == 1.0
    assert m["final_radius_m"] == [2.0, 2.0, 2.0]
    # angles 0, 180, 90 at the end: gaps 90, 90, 180 against 120
    assert m["spacing_error_max_deg"] == pytest.approx(60.0, abs=1e-9)
    # bodies: robots 2 and 3 at t = 1 are sqrt(8) apart: clearance 2.828 - 0.3; the
    # obstacle is nearer: 0.85 m
    assert m["min_clearance_m"] == pytest.approx(0.85, abs=1e-12)


def test_seeded_starts_are_apart_in_the_square_and_reproducible() -> None:
    scn = dataclasses.replace(_scenario(scatter_m=2.0), poses=((0.0, 0.0, 0.0),) * 12)
    cmd = scn.command
    assert isinstance(cmd, Formation)
    a = start_positions(scn, np.random.default_rng(4))
    b = start_positions(scn, np.random.default_rng(4))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a[:, :2]).max() <= 2.0
    d = np.sqrt(((a[:, None, :2] - a[None, :, :2]) ** 2).sum(axis=2)) + np.eye(12) * 9
    assert d.min() >= 2 * 0.15 + 0.5  # two body radii plus the contact range
    with pytest.raises(Exception, match="cannot place 12 robots"):
        start_positions(
            dataclasses.replace(scn, command=dataclasses.replace(cmd, scatter_m=0.5)),
            np.random.default_rng(4),
        )


@pytest.mark.parametrize("name", ["formation-4", "formation-moving"])
def test_same_seed_same_run(name: str) -> None:
    scn = _shorter(load_scenario(name), 3.0)
    a, b = simulate(scn).arrays(), simulate(scn).arrays()
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    other = simulate(scn, seed=scn.seed + 1).arrays()
    assert not np.array_equal(other["pose"], a["pose"])


def test_symmetric_start_converges_to_the_analytic_radius() -> None:
    # three robots on an equilateral triangle stay symmetric; the deliverable's law
    # settles where r (r^2 - alpha^2) = k_r sum_j 1 / (4 r^2 sin(pi j / 3))
    ang = np.deg2rad([90.0, 210.0, 330.0])
    poses = tuple((2.0 * math.cos(a), 2.0 * math.sin(a), 0.0) for a in ang)
    scn = dataclasses.replace(_scenario(alpha_m=3.0), poses=poses, duration_s=25.0)
    push = sum(1.0 / (4.0 * math.sin(math.pi * j / 3)) for j in (1, 2))
    r_star = brentq(lambda r: r * (r * r - 9.0) - 10.0 * push / (r * r), 3.0, 6.0, xtol=1e-14)
    m = compute_metrics(simulate(scn))
    # the slowest mode decays as exp(-(B + k_d) t / 2M) = exp(-t): after 25 s ~1e-11 m
    np.testing.assert_allclose(m["final_radius_m"], r_star, atol=1e-8)


def test_point_masses_keep_the_circle_while_the_leader_moves() -> None:
    # robots at rest on the circle (a regular triangle: the regular law's equilibrium);
    # with the feedforward the formation is that of a fixed leader in the leader's frame
    ang = np.deg2rad([0.0, 120.0, 240.0])
    poses = tuple((3.0 * math.cos(a), 3.0 * math.sin(a), 0.0) for a in ang)
    leader = {"waypoints_m": [[0, 0], [3, 3]], "speed_m_s": 0.3, "accel_m_s2": 0.3}
    scn = dataclasses.replace(
        _scenario(law="regular", alpha_m=3.0, leader=leader), poses=poses, duration_s=25.0
    )
    r = simulate(scn)
    lead = r.extra["leader_xy_m"]
    np.testing.assert_allclose(lead[-1], [3.0, 3.0], atol=1e-12)
    dist = np.sqrt(((r.pose[:, :, :2] - lead[:, None, :]) ** 2).sum(axis=2))
    # the feedforward is held over each 10 ms step while the leader's velocity changes
    # by a dt = 3 mm/s: a force error (B + k_d) a dt = 6 mN, and the acceleration steps
    # at the ends of the ramps; against the circle's stiffness 2 alpha^2 = 18 N/m that
    # is ~3e-4 m each (measured 6e-4 m). (A polyline corner is a velocity step the
    # feedforward cannot give: point masses swing out there, so this path is straight.)
    assert np.abs(dist - 3.0).max() < 2e-3


def test_failed_robot_stops_and_leaves_the_team() -> None:
    scn = load_scenario("formation-failure")
    r = simulate(scn)
    cmd = scn.command
    assert isinstance(cmd, Formation)
    assert cmd.failure is not None
    k = cmd.failure.robot - 1
    after = r.t >= cmd.failure.time_s
    active = r.extra["robot_active"]
    assert np.all(active[~after] == 1)
    assert np.all(active[after, k] == 0)
    assert np.all(np.delete(active[after], k, axis=1) == 1)
    # a stopped point mass does not move at all
    np.testing.assert_array_equal(
        r.pose[after, k, :2], np.repeat(r.pose[after][:1, k, :2], after.sum(), 0)
    )
    m = compute_metrics(r)
    # the four left are a regular polygon: 90 degrees apart
    assert float(m["spacing_error_max_deg"]) <= 2.0  # type: ignore[arg-type]


def test_diff_drive_robots_use_the_motor_stack() -> None:
    scn = _shorter(load_scenario("formation-moving"), 2.0)
    r = simulate(scn)
    n = scn.n_robots
    assert r.wheel_speed_rad_s.shape == (r.t.size, n, 2)
    assert np.abs(r.voltage_v).max() <= scn.speed_pid.output_limit
    # the formation point is the look-ahead point, 0.1 m ahead of the axle centre
    heading = r.pose[:, :, 2]
    ahead = r.pose[:, :, :2] + 0.1 * np.stack([np.cos(heading), np.sin(heading)], axis=2)
    np.testing.assert_allclose(r.extra["formation_xy_m"], ahead, atol=1e-12)


def test_run_writes_leader_and_claims(tmp_path: Path) -> None:
    out = tmp_path / "o"
    assert main(["run", "formation-failure", "--out", str(out)]) == 0
    with np.load(out / "result.npz") as npz:
        t = npz["t"]
        assert npz["leader_xy_m"].shape == (t.size, 2)
        assert npz["pose"].shape == (t.size, 5, 3)
        assert "current_a" not in npz  # point masses have no wheels
    assert not (out / "formation.gif").exists()  # the leader stays: no animation
    assert (out / "trajectories.png").read_bytes()[:4] == b"\x89PNG"
    doc = json.loads((out / "metrics.json").read_text())
    assert len(doc["final_radius_m"]) == 5
    assert all(c["passed"] for c in doc["claims"])


def test_animation_of_a_moving_leader_is_a_gif(report_out: Path | None) -> None:
    if report_out is not None:  # the session's report drew it (tests/conftest.py)
        gif = (report_out / "formation-obstacles" / "formation.gif").read_bytes()
    else:
        from firefleet.report.formation import formation_figures

        scn = _shorter(load_scenario("formation-obstacles"), 12.0)
        gif = formation_figures(simulate(scn))["formation.gif"]
    assert gif[:6] == b"GIF89a"
    import io

    from PIL import Image

    with Image.open(io.BytesIO(gif)) as im:
        assert getattr(im, "n_frames", 1) == 40  # _GIF_FRAMES


BAD = """\
name: bad
title: t
duration_s: 5.0
poses: [[0, 0, 0], [0, 0, 0]]
command: {kind: formation, %s}
"""


@pytest.mark.parametrize(
    ("fields", "fragment"),
    [
        ("failure: {robot: 3, time_s: 1.0}", "failure.robot = 3, but the team has 2 robot(s)"),
        ("formed_by_s: 9.0", "formed_by_s = 9.0 s is after the end of the run"),
        ("alpha_m: -2.0", "alpha_m must be > 0, got -2.0"),
        ("alpha_m: .nan", "alpha_m must be a finite number"),
        ("law: circular", "law: Input should be 'deliverable' or 'regular'"),
        ("obstacles: [{x_m: 0, y_m: 0, radius_m: 0}]", "radius_m must be > 0"),
        ("leader: {waypoints_m: []}", "waypoints_m must list at least one point"),
        ("scatter_m: 0.1", "cannot place 2 robots"),
        (
            "alpha_m: 0.1",
            "alpha_m = 0.1 m is too small for 2 robots of radius 0.15 m (robot_radius_m)",
        ),
        (
            "alpha_m: 2000.0, attraction_limit_n: null, scatter_m: 5.0",
            "N/m: a 0.01 s step would need more than 10,000 sub-steps to stay stable",
        ),
    ],
)
def test_bad_formation_input_is_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fields: str, fragment: str
) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(BAD % fields)
    out = tmp_path / "never"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert fragment in err, err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
    assert not out.exists()


def _team(
    n: int, alpha_m: float, law: str = "regular", duration_s: float = 30.0, **command: Any
) -> Scenario:
    """N robots from seeded random starts onto a circle of alpha_m (the bench's recipe)."""
    cmd: dict[str, Any] = {
        "kind": "formation",
        "law": law,
        "alpha_m": alpha_m,
        "attraction_gain": 9.0 / alpha_m**2,  # 18 N/m on the circle at any radius
        "scatter_m": max(5.0, alpha_m / 2.0),
        **command,
    }
    return parse_scenario(
        {
            "name": "team",
            "title": "t",
            "duration_s": duration_s,
            "seed": 1,
            "poses": [[0.0, 0.0, 0.0]] * n,
            "command": cmd,
        }
    )


def test_held_force_step_is_stable_with_the_substeps() -> None:
    # eq. 5 with a spring -kappa x: one held-force step is linear in (x, v); its 2 x 2
    # matrix, made by stepping unit states, must have spectral radius < 1
    md = MassDamperParams()  # M = 1 kg, c = 2 N s/m: the bound is ~2 c / h = 400 N/m
    dt = 0.01

    def radius(kappa: float, n_sub: int) -> float:
        cols = []
        for unit in ([1.0, 0.0], [0.0, 1.0]):
            s = np.array([[unit[0], 0.0, unit[1], 0.0]])
            for _ in range(n_sub):
                s = mass_damper_step(s, -kappa * s[:, :2], dt / n_sub, md)
            cols.append([s[0, 0], s[0, 2]])
        return float(np.abs(np.linalg.eigvals(np.array(cols).T)).max())

    assert radius(380.0, 1) < 1.0 < radius(420.0, 1)  # the ~400 N/m edge is real
    for kappa in (10.0, 200.0, 420.0, 5e3, 1e5, 1e6):
        n = substeps(kappa, 2.0, dt)
        assert radius(kappa, n) < 1.0, (kappa, n)
    assert [substeps(k, 2.0, dt) for k in (0.0, 200.0, 200.1, 1e3)] == [1, 1, 2, 5]
    with pytest.raises(FormationDivergedError, match="more than 10,000 sub-steps"):
        substeps(math.nan, 2.0, dt)


@pytest.mark.parametrize(("n", "alpha_m"), [(3, 3.0), (20, 3.0), (200, 30.0)])
def test_regular_law_converges_for_teams(n: int, alpha_m: float) -> None:
    scn = _team(n, alpha_m, formed_by_s=25.0)
    m = compute_metrics(simulate(scn))
    # issue 13: radius error <= 1 % of alpha, spacing error <= 2 deg, no contact
    assert float(m["radius_error_max_m"]) <= 0.01 * alpha_m  # type: ignore[arg-type]
    assert float(m["spacing_error_max_deg"]) <= 2.0  # type: ignore[arg-type]
    assert float(m["min_clearance_m"]) > 0.0  # type: ignore[arg-type]


def test_issue_13_team_with_the_readme_keys_converges() -> None:
    # 100 robots on a 10 m circle with the README's keys (eq. 6 with a = 1, now capped
    # at 10 N by default; scatter 10 m): diverged to ~250 km before issue 13
    scn = parse_scenario(
        {
            "name": "readme",
            "title": "t",
            "duration_s": 30.0,
            "seed": 0,
            "poses": [[0.0, 0.0, 0.0]] * 100,
            "command": {
                "kind": "formation",
                "law": "regular",
                "alpha_m": 10.0,
                "scatter_m": 10.0,
                "formed_by_s": 25.0,
            },
        }
    )
    m = compute_metrics(simulate(scn))
    assert float(m["radius_error_max_m"]) <= 0.01 * 10.0  # type: ignore[arg-type]
    assert float(m["spacing_error_max_deg"]) <= 2.0  # type: ignore[arg-type]
    assert float(m["min_clearance_m"]) > 0.0  # type: ignore[arg-type]


def test_regular_law_converges_for_1000_robots() -> None:
    # 1,000 robots from a 80 m square onto a 150 m circle (side 0.94 m): formed by 35 s
    scn = _team(1000, 150.0, duration_s=40.0, scatter_m=40.0, formed_by_s=35.0)
    r = simulate(scn, record_every=100)
    m = compute_metrics(r)
    assert float(m["radius_error_max_m"]) <= 0.01 * 150.0  # type: ignore[arg-type]
    assert float(m["spacing_error_max_deg"]) <= 2.0  # type: ignore[arg-type]
    # (min_clearance_m sees the recorded samples only, here every second)
    assert float(m["min_clearance_m"]) > 0.0  # type: ignore[arg-type]
    # the steps were stable, mostly undivided
    assert float(np.mean(r.extra["substeps"])) < 1.5


def test_deliverable_law_at_team_scale_is_bounded_and_on_the_circle() -> None:
    # 100 robots on a 10 m circle, k_r scaled with the polygon's side squared
    # (0.63 m against the 5-gon's 3.53 m on 3 m): every robot on the circle
    side = 2.0 * 10.0 * math.sin(math.pi / 100)
    scn = _team(100, 10.0, law="deliverable", k_r=10.0 * (side / 3.53) ** 2, formed_by_s=25.0)
    m = compute_metrics(simulate(scn))
    assert float(m["radius_error_max_m"]) <= 0.05 * 10.0  # type: ignore[arg-type]
    # with the deliverable's k_r = 10 the crowded ring walls late robots out (the
    # irregular polygon, with robots off it), but the run stays bounded
    scn10 = _team(20, 3.0, law="deliverable", formed_by_s=25.0)
    final = compute_metrics(simulate(scn10))["final_radius_m"]
    assert max(final) < 2.0 * 3.0  # type: ignore[arg-type]


def test_team_that_cannot_fit_is_a_validation_error() -> None:
    # 100 bodies of 0.15 m need 0.15 / sin(pi / 100) = 4.775 m
    with pytest.raises(InputError) as info:
        _team(100, 4.7)
    msg = str(info.value)
    assert "alpha_m = 4.7 m is too small for 100 robots of radius 0.15 m" in msg
    assert "at least 4.775 m" in msg
    _team(100, 4.78)  # fits
    with pytest.raises(InputError, match=r"radius 0.25 m \(robot_radius_m \+ look_ahead_m\)"):
        _team(100, 6.0, robot_model="diff-drive")


def test_a_run_that_leaves_every_bound_stops_with_an_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the position guard: robots farther than DIVERGENCE_FACTOR x the formation's size
    monkeypatch.setattr(formation_module, "DIVERGENCE_FACTOR", 0.1)
    with pytest.raises(FormationDivergedError, match=r"diverged at t = 0.000 s: a robot is"):
        simulate(_scenario(scatter_m=5.0))


def test_diverging_run_writes_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "stiff.yaml"
    path.write_text(BAD % "alpha_m: 2000.0, attraction_limit_n: null, scatter_m: 5.0")
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "stiffness" in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()
