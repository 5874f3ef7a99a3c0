"""Section 2.5's formation-over-link study: its scenario, the breakdown it states, its
figure, and a small run of it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from firefleet.report import formation_link
from firefleet.report.formation_link import (
    BOUNDS,
    breakdown_delay_s,
    formation_study_png,
    study_scenario,
)
from firefleet.scenarios._network import LinkSpec
from firefleet.scenarios.schema import Formation
from firefleet.sim.formation import leader_trajectory


def _study(radius_at_delay: dict[float, float], diverged: bool = False) -> dict[str, Any]:
    points: list[dict[str, Any]] = []
    for seed in (0, 1):
        for v in formation_link.LOSSES:
            radius = radius_at_delay[0.0] if v == 0.0 else 0.03
            points.append({"axis": "loss", "value": v, "seed": seed, "radius_error_max_m": radius})
        for b in formation_link.BURSTS[1:]:
            r = math.inf if diverged and seed else 0.2
            points.append({"axis": "burst", "value": b, "seed": seed, "radius_error_max_m": r})
        for d in formation_link.DELAYS_S[1:]:
            r = radius_at_delay[d] + 0.01 * seed
            points.append({"axis": "delay", "value": d, "seed": seed, "radius_error_max_m": r})
    for p in points:
        p["spacing_error_max_deg"] = 20.0 * p["radius_error_max_m"]
    return {
        "points": points,
        "ideal": {"radius_error_max_m": 0.012, "spacing_error_max_deg": 0.3},
        "seeds": [0, 1],
    }


def test_the_breakdown_is_the_first_latency_where_a_seed_leaves_a_bound() -> None:
    radius = {0.0: 0.01, 0.1: 0.05, 0.2: 0.1, 0.3: 0.14, 0.5: 0.3}
    # at 0.2 s the spacing (20 x radius) reaches 2.2 degrees for the second seed
    assert breakdown_delay_s(_study(radius)) == 0.2
    radius = {0.0: 0.01, 0.1: 0.05, 0.2: 0.1, 0.3: 0.14, 0.5: 0.16}
    assert breakdown_delay_s(_study({**radius, 0.2: 0.05, 0.3: 0.05})) == 0.5
    assert math.isinf(breakdown_delay_s(_study(dict.fromkeys(radius, 0.01))))


def test_the_study_starts_formed() -> None:
    scn = study_scenario()
    cmd = scn.command
    assert isinstance(cmd, Formation)
    pose = scn.initial_poses
    point = pose[:, :2] + cmd.look_ahead_m * np.stack(
        [np.cos(pose[:, 2]), np.sin(pose[:, 2])], axis=1
    )
    leader, _, _ = leader_trajectory(cmd.leader, np.array([0.0, scn.duration_s]))
    np.testing.assert_allclose(np.hypot(*(point - leader[0]).T), cmd.alpha_m, rtol=1e-12)
    gaps = np.diff(np.sort(np.degrees(np.arctan2(point[:, 1], point[:, 0]))))
    np.testing.assert_allclose(gaps, 360.0 / scn.n_robots, atol=1e-9)
    # the leader turns its corner (4 m on) within the run
    assert leader[1][0] > cmd.leader.waypoints_m[1][0]
    assert leader[1][1] > 0.0


def test_the_figure_is_a_png_with_a_diverged_run() -> None:
    png = formation_study_png(_study({0.0: 0.01, 0.1: 0.05, 0.2: 0.1, 0.3: 0.2, 0.5: 0.3}, True))
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(png) > 20_000


def test_one_point_of_the_study_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    # two points, one seed: 50 % loss keeps the bounds, 0.5 s latency leaves them
    monkeypatch.setattr(
        formation_link,
        "points",
        lambda: [
            ("loss", 0.5, LinkSpec(preset="xbee", loss=0.5)),
            ("delay", 0.5, LinkSpec(preset="xbee", delay_s=0.5, jitter_s=0.02)),
        ],
    )
    seen: list[tuple[int, int]] = []
    study = formation_link.formation_link_study(
        seeds=(0,), progress=lambda d, t: seen.append((d, t))
    )
    loss, delay = study["points"]
    assert all(loss[key] <= bound for key, bound in BOUNDS.items())
    assert 0.4 <= loss["lost_share"] <= 0.6
    assert delay["spacing_error_max_deg"] > BOUNDS["spacing_error_max_deg"]
    assert 0.5 <= delay["message_age_max_s"] <= 0.5 + 0.05 + 0.1
    assert study["ideal"]["radius_error_max_m"] < loss["radius_error_max_m"]
    assert seen[-1] == (3, 3)
