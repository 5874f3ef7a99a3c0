"""The link model (issue 16): each impairment against its definition."""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np
import pytest

from firefleet import load_scenario
from firefleet.errors import InputError
from firefleet.scenarios import parse_scenario
from firefleet.scenarios._network import LinkSpec
from firefleet.scenarios.schema import PathFollowing
from firefleet.sim.kinds.path_following import path_following_metrics
from firefleet.sim.link import (
    PRESETS,
    LinkModel,
    LinkParams,
    link_params,
    message_bytes,
    packet_error_rate,
    wall_cells,
)
from firefleet.sim.loop import default_stages, run_loop
from firefleet.sim.registry import task_kind
from firefleet.world import OccupancyGrid

DT = 0.01


def _received(
    params: LinkParams,
    ticks: int,
    xy: list[tuple[float, float]],
    *,
    dt: float = DT,
    seed: int = 1,
    grid: OccupancyGrid | None = None,
) -> np.ndarray:
    """Robot 0 broadcasts its tick number every tick; returns, for each tick sent, the
    tick at which robot 1 first held it (-1: never)."""
    link = LinkModel(params, seed=seed, grid=grid)
    n = len(xy)
    pose = np.zeros((n, 3))
    pose[:, :2] = xy
    state = link.init(n, dt)
    got = np.full(ticks, -1)
    for k in range(ticks + 200):
        sent = {"x": np.full(n, float(k - 1))} if 1 <= k <= ticks else {}
        inbox, state = link.exchange(state, sent if k >= 1 else {}, k * dt, pose)
        held = inbox["x"][1, 0] if "x" in inbox else math.nan
        if np.isfinite(held) and got[int(held)] < 0 and 0 <= int(held) < ticks:
            got[int(held)] = k
    return got


def _radio(**over: Any) -> LinkParams:
    """The xbee preset's range model, every tick, without airtime, gap or delay (so that
    every frame sent at tick k - 1 is held at tick k unless lost)."""
    base = dataclasses.replace(
        PRESETS["xbee"], period_s=None, rate_bit_s=math.inf, frame_gap_s=0.0, delay_s=0.0
    )
    return dataclasses.replace(base, **over)


def test_bernoulli_loss_rate() -> None:
    n = 20_000
    got = _received(_radio(loss=0.2, range_m=math.inf), n, [(0, 0), (1, 0)])
    lost = float(np.mean(got < 0))
    assert abs(lost - 0.2) < 4 * math.sqrt(0.2 * 0.8 / n)  # 4 sigma: 0.011
    # independent: a loss after a loss as often as after a success
    seq = got < 0
    after_loss = float(np.mean(seq[1:][seq[:-1]]))
    assert abs(after_loss - 0.2) < 0.03


def test_gilbert_elliott_loss_rate_and_burst_lengths() -> None:
    n = 40_000
    got = _received(_radio(loss=0.2, burst_length=4.0, range_m=math.inf), n, [(0, 0), (1, 0)])
    seq = (got < 0).astype(int)
    assert abs(seq.mean() - 0.2) < 0.02  # bursts inflate the deviation: ~4x Bernoulli's
    edges = np.diff(np.concatenate([[0], seq, [0]]))
    bursts = np.nonzero(edges == -1)[0] - np.nonzero(edges == 1)[0]
    # geometric with mean 4: standard deviation sqrt(12), some 2,000 bursts
    assert abs(bursts.mean() - 4.0) < 4 * math.sqrt(12.0 / bursts.size)
    # P(burst = 1) = r = 1/4
    assert abs(np.mean(bursts == 1) - 0.25) < 0.04


def test_delay_distribution_without_queueing() -> None:
    dt = 0.001
    # one broadcast every 100 ticks (no frame overtakes another), 250 kbit/s
    params = LinkParams(delay_s=0.05, jitter_s=0.01, period_s=0.1, rate_bit_s=250e3)
    got = _received(params, 60_000, [(0, 0), (1, 0)], dt=dt)
    sent = np.arange(got.size)[got >= 0]
    assert sent.size == 600  # none lost
    assert np.all(sent % 100 == 0)
    airtime = 8 * message_bytes() / 250e3
    # sent at tick k (the link carries it from k + 1 on): held at the first tick at or
    # after k dt + airtime + delay + jitter
    latency = (got[sent] - sent - 1) * dt - airtime
    jitter = latency - 0.05
    # Gaussian, plus the wait for the next tick (uniform on [0, dt))
    assert abs(jitter.mean() - dt / 2) < 4 * 0.01 / math.sqrt(sent.size)
    assert abs(jitter.std() - math.sqrt(0.01**2 + dt**2 / 12)) < 4 * 0.01 / math.sqrt(2 * 600)
    inside = np.mean(np.abs(jitter - dt / 2) < 0.01)
    assert abs(inside - 0.6827) < 4 * math.sqrt(0.68 * 0.32 / 600)


@pytest.mark.parametrize("d_m", [10.0, 40.0, 54.0, 60.0, 70.0])
def test_range_curve(d_m: float) -> None:
    params = _radio(range_m=65.0)
    n = 6000
    got = _received(params, n, [(0, 0), (d_m, 0)])
    per = float(packet_error_rate(np.array([d_m]), 65.0, 3.0, 4.0)[0])
    assert abs(np.mean(got < 0) - per) < 4 * math.sqrt(max(per * (1 - per), 1e-4) / n)
    # the closed form: Phi(-(10 n log10(R / d)) / sigma), nothing beyond the range
    margin = 30.0 * math.log10(65.0 / d_m)
    closed = 0.5 * math.erfc(margin / (4.0 * math.sqrt(2))) if d_m <= 65.0 else 1.0
    assert per == pytest.approx(closed, abs=1e-15)


def test_walls_attenuate() -> None:
    occ = np.zeros((1, 100), dtype=bool)
    occ[0, 40:43] = True  # three cells of wall between the two robots
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.2)
    xy = [(1.0, 0.1), (19.0, 0.1)]
    assert wall_cells(grid, np.array(xy)).tolist() == [[0.0, 3.0], [3.0, 0.0]]
    got = _received(_radio(range_m=60.0), 3000, xy, grid=grid)
    per = float(packet_error_rate(np.array([18.0]), 60.0, 3.0, 4.0, walls_db=3 * 6.0)[0])
    assert 0.2 < per < 0.8
    assert abs(np.mean(got < 0) - per) < 4 * math.sqrt(per * (1 - per) / 3000)


def test_airtime_and_a_team_that_talks_too_much() -> None:
    p = PRESETS["xbee"]
    assert p.airtime_s(message_bytes()) == 8 * (81 + 17) / 250e3
    # ten robots at every 10 ms tick: 1,000 frames/s offered, the channel carries
    # 1 / (airtime + gap) = 204 a second; the rest wait and then are dropped
    params = dataclasses.replace(p, period_s=None, range_m=math.inf, delay_s=0.0)
    link = LinkModel(params, seed=3)
    n = 10
    state = link.init(n, DT)
    pose = np.zeros((n, 3))
    pose[:, 0] = np.arange(n)
    ticks = 1000
    for k in range(ticks + 1):
        sent = {"x": np.zeros(n)} if k >= 1 else {}
        _, state = link.exchange(state, sent, k * DT, pose)
    c = link.counters(state)
    rate = c["frames"] / (ticks * DT)
    assert rate == pytest.approx(1.0 / (p.airtime_s(81) + p.frame_gap_s), rel=0.01)
    assert c["queue_drops"] == pytest.approx(ticks * n - c["frames"], abs=n * p.queue_frames)
    assert c["messages_lost"] == pytest.approx(c["queue_drops"] * (n - 1))


def test_ideal_preset_equals_the_ideal_link_bit_for_bit() -> None:
    scn = load_scenario("coop-motor-fault")
    assert isinstance(scn.command, PathFollowing)
    cmd = dataclasses.replace(scn.command, trajectory_s=9.0, pieces=30)
    scn = dataclasses.replace(scn, duration_s=10.0, command=cmd, faults=())
    kind = task_kind("path-following")
    assert kind.decider is not None
    rec = np.arange(scn.n_steps + 1)
    stages = default_stages(scn, kind.decider)
    a = run_loop(scn, kind.decider, rec, stages=stages).arrays()
    b = run_loop(
        scn, kind.decider, rec, stages=dataclasses.replace(stages, link=LinkModel(PRESETS["ideal"]))
    ).arrays()
    for key, value in a.items():
        np.testing.assert_array_equal(b[key], value, err_msg=key)
    assert b["messages_sent"][-1] == 3 * 2 * scn.n_steps
    assert b["messages_lost"][-1] == 0


def test_the_scenario_key_runs_the_link_and_counts() -> None:
    scn = load_scenario("coop-motor-fault")
    assert isinstance(scn.command, PathFollowing)
    cmd = dataclasses.replace(scn.command, trajectory_s=9.0, pieces=30)
    spec = LinkSpec(
        preset="xbee", loss=0.1, burst_length=3, delay_s=0.05, jitter_s=0.01, range_m=60
    )
    scn = dataclasses.replace(scn, duration_s=10.0, command=cmd, faults=(), link=spec)
    result = task_kind("path-following").run(scn, np.arange(0, scn.n_steps + 1, 10))
    m: dict[str, Any] = dict(path_following_metrics(result))
    # 20 Hz, 3 robots, 2 receivers each, 10 s; about 10 % lost
    assert m["messages_sent"] == pytest.approx(3 * 2 * 20 * 10, abs=6)
    assert 0.05 < m["messages_lost"] / m["messages_sent"] < 0.2
    assert 0.05 + 0.05 < m["message_age_max_s"] < 1.0


def test_bad_link_keys_name_the_key() -> None:
    base = {
        "name": "x",
        "title": "x",
        "duration_s": 1.0,
        "command": {"kind": "wheel-speed-step", "speed_rad_s": 1.0},
    }
    for link, message in [
        ({"preset": "lora"}, "link.preset"),
        ({"loss": 1.5}, "link.loss"),
        ({"burst_length": 0.5}, "link.burst_length"),
        ({"delay_s": -1.0}, "link.delay_s"),
        ({"range_m": 0.0}, "link.range_m"),
    ]:
        with pytest.raises(InputError, match=re.escape(message)):
            parse_scenario({**base, "link": link})
    with pytest.raises(InputError, match=r"link\.burst_length"):
        link_params(LinkSpec(loss=0.9, burst_length=2.0))
