"""The formation's neighbours over the link (issue 16): views, per-receiver forces, runs."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np
import pytest

from firefleet import load_scenario
from firefleet.control.formation import FormationParams, formation_force_and_stiffness
from firefleet.scenarios._network import LinkSpec
from firefleet.sim._formation_link import outbox, predicted_views, view_forces
from firefleet.sim.registry import task_kind
from firefleet.sim.result import SimResult

KIND = task_kind("formation")


def _run(name: str, link: LinkSpec | None, **changes: Any) -> tuple[SimResult, dict[str, Any]]:
    scn = dataclasses.replace(load_scenario(name), link=link, **changes)
    rec = np.arange(0, scn.n_steps + 1, 10)
    result = KIND.run(scn, rec)
    return result, dict(KIND.metrics(result))


def test_predicted_views_match_a_loop_over_pairs() -> None:
    rng = np.random.default_rng(4)
    n, dt, step, timeout = 5, 0.01, 40, 0.15
    inbox = {key: rng.normal(size=(n, n)) for key in ("x_m", "y_m", "vx_m_s", "vy_m_s")}
    sent = rng.integers(-1, step, size=(n, n)).astype(float)
    inbox["sent_tick"] = sent
    own = rng.normal(size=(n, 2))
    pos, fresh, age = predicted_views(inbox, own, step, dt, timeout, ahead_s=0.004)
    for i in range(n):
        for j in range(n):
            if i == j:
                assert fresh[i, j]
                assert age[i, j] == 0.0
                np.testing.assert_array_equal(pos[i, j], own[i])
                continue
            a = (step - sent[i, j]) * dt if sent[i, j] >= 0 else math.inf
            assert age[i, j] == pytest.approx(a)
            assert fresh[i, j] == (a <= timeout)
            if fresh[i, j]:
                want = [
                    inbox["x_m"][i, j] + inbox["vx_m_s"][i, j] * (a + 0.004),
                    inbox["y_m"][i, j] + inbox["vy_m_s"][i, j] * (a + 0.004),
                ]
                np.testing.assert_allclose(pos[i, j], want, rtol=1e-12)


@pytest.mark.parametrize("law", ["deliverable", "regular"])
def test_true_views_give_the_team_law(law: Literal["deliverable", "regular"]) -> None:
    # every receiver holding every point as it is: the per-receiver law is the team's
    rng = np.random.default_rng(1)
    pts = rng.uniform(-4.0, 4.0, size=(6, 2))
    params = FormationParams(alpha_m=3.0, attraction_limit_n=10.0)
    active = np.array([True, True, False, True, True, True])
    team, stiff = formation_force_and_stiffness(pts, [0.2, -0.1], params, law=law, active=active)
    msg = outbox(pts, np.zeros_like(pts))
    inbox = {key: np.tile(v, (6, 1)) for key, v in msg.items()}
    inbox["sent_tick"] = np.full((6, 6), 7.0)
    views = predicted_views(inbox, pts, 7, 0.01, 1.0)

    def at(pos: np.ndarray, act: np.ndarray, row: int) -> tuple[np.ndarray, float]:
        return formation_force_and_stiffness(pos, [0.2, -0.1], params, law=law, active=act)

    force, s = view_forces(views, active, at)
    np.testing.assert_allclose(force, team, rtol=1e-12, atol=1e-12)
    assert s == pytest.approx(stiff)


def test_stale_neighbours_are_left_out() -> None:
    # nothing fresh: each robot's force is the law on itself alone (the attraction)
    pts = np.array([[3.5, 0.0], [0.0, 2.0], [-1.0, -1.0]])
    params = FormationParams(alpha_m=3.0, attraction_limit_n=10.0)
    inbox = {key: np.zeros((3, 3)) for key in ("x_m", "y_m", "vx_m_s", "vy_m_s")}
    inbox["sent_tick"] = np.full((3, 3), 0.0)
    views = predicted_views(inbox, pts, 200, 0.01, 1.0)  # 2 s old
    assert views[1].sum() == 3

    def at(pos: np.ndarray, act: np.ndarray, row: int) -> tuple[np.ndarray, float]:
        return formation_force_and_stiffness(pos, [0.0, 0.0], params, active=act)

    force, _ = view_forces(views, np.ones(3, dtype=bool), at)
    for i in range(3):
        alone, _ = formation_force_and_stiffness(pts[i : i + 1], [0.0, 0.0], params)
        np.testing.assert_allclose(force[i], alone[0], rtol=1e-12)


def test_an_ideal_link_through_the_link_stage_keeps_the_claims() -> None:
    # the ideal preset broadcasting every tick goes through LinkModel (values one tick
    # old, predicted to now): formation-regular-4 keeps its claims and ends where the
    # direct run (true points) ends, within 1 mm
    direct, m0 = _run("formation-regular-4", None)
    linked, m1 = _run("formation-regular-4", LinkSpec(period_s=0.01))
    scn = load_scenario("formation-regular-4")
    for claim in scn.claims:
        assert claim.holds(m1.get(claim.metric)), (claim.metric, m1[claim.metric])
    # the same polygon: radii within 1 mm, each robot's bearing within 1 degree (the
    # polygon may turn as a whole: every turn of it is an equilibrium)
    end = [r.pose[-1, :, :2] for r in (linked, direct)]
    np.testing.assert_allclose(np.hypot(*end[0].T), np.hypot(*end[1].T), atol=1e-3)
    bearing = [np.degrees(np.arctan2(e[:, 1], e[:, 0])) for e in end]
    assert np.abs((bearing[0] - bearing[1] + 180.0) % 360.0 - 180.0).max() < 1.0
    n = scn.n_robots
    assert m1["messages_sent"] == n * (n - 1) * scn.n_steps
    assert m1["messages_lost"] == 0.0
    assert m1["message_age_max_s"] == pytest.approx(0.01)
    assert m0["messages_sent"] == n * (n - 1) * scn.n_steps
    assert m0["message_age_max_s"] == 0.0


def test_loss_rate_and_ages_over_the_xbee_link() -> None:
    # 30 % independent loss: the share lost within 4 binomial deviations; no value
    # used older than the timeout; every robot stays in formation-3's bounds
    _, m = _run("formation-3", LinkSpec(preset="xbee", loss=0.3))
    sent = float(m["messages_sent"])
    broadcasts = math.ceil(load_scenario("formation-3").n_steps / 5)  # 20 Hz at 10 ms
    assert sent == 3 * 2 * broadcasts
    share = float(m["messages_lost"]) / sent
    assert abs(share - 0.3) < 4.0 * math.sqrt(0.3 * 0.7 / sent)
    assert 0.05 <= float(m["message_age_max_s"]) <= 1.0
    assert float(m["radius_error_max_m"]) <= 0.15


def test_latency_beyond_the_timeout_leaves_every_neighbour_stale() -> None:
    result, m = _run("formation-regular-3", LinkSpec(delay_s=1.5, period_s=0.01))
    stale = result.extra["stale_robots"]
    assert (stale == 2).all()  # nothing fresher than 1 s is ever heard
    assert math.isnan(float(m["message_age_max_s"]))


def test_a_delayed_neighbour_is_predicted_from_its_velocity() -> None:
    # 0.2 s latency on a moving formation: the age the law used is the latency plus at
    # most one broadcast period and tick (and 20 ms jitter at 4 sigma)
    _, m = _run("formation-moving", LinkSpec(preset="xbee", delay_s=0.2), duration_s=20.0)
    age = float(m["message_age_max_s"])
    assert 0.2 <= age <= 0.2 + 0.05 + 0.02 + 1e-9
