"""Incremental encoder: counts, M-method speed, quantisation, ideal sensor, window."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams, encoder_init, encoder_step, encoder_step_one


def test_counts_are_floor_of_angle_times_cpr_over_2pi() -> None:
    cpr = 2048
    params = EncoderParams(counts_per_rev=cpr, window_steps=2)
    rng = np.random.default_rng(6)
    dphi = rng.uniform(-0.4, 0.4, (400, 3))  # random walks through both signs of angle
    start = np.array([0.0, 1.234, -5.0])
    state = encoder_init(start, params)
    angle = start.copy()
    negatives = 0
    for k in range(dphi.shape[0]):
        state, counts, _ = encoder_step(state, dphi[k], params, 0.01)
        angle = angle + dphi[k]  # same additions in the same order: bit for bit
        frac = angle * cpr / (2.0 * math.pi)
        # skip angles within rounding of a count edge, where either floor is right
        away = np.abs(frac - np.round(frac)) > 1e-9
        np.testing.assert_array_equal(counts[away], np.floor(frac[away]))
        np.testing.assert_array_equal(state.angle_rad, angle)
        negatives += int(np.count_nonzero(angle[away] < 0))
    assert negatives > 100  # negative angles were checked too (floor, not truncation)


def test_resolution_is_one_count_over_the_window() -> None:
    # 2 pi / (2048 * 2 * 0.01 s) = 0.1534 rad/s, "a 0.15 rad/s quantum at 10 ms"
    q = EncoderParams().resolution_rad_s(0.01)
    assert q == pytest.approx(2.0 * math.pi / (2048 * 2 * 0.01), rel=1e-15)
    assert q == pytest.approx(0.15, abs=0.005)
    assert EncoderParams(counts_per_rev=0).resolution_rad_s(0.01) == 0.0


@pytest.mark.parametrize(
    ("cpr", "window", "speed"), [(2048, 2, 10.0), (500, 1, -3.3), (64, 5, 7.7)]
)
def test_constant_speed_is_measured_on_average_in_whole_quanta(
    cpr: int, window: int, speed: float
) -> None:
    dt, n = 0.01, 2000
    params = EncoderParams(counts_per_rev=cpr, window_steps=window)
    q = 2.0 * math.pi / (cpr * window * dt)  # the quantum, by hand
    state = encoder_init(np.array([0.37 * 2.0 * math.pi / cpr]), params)  # mid-count phase
    measured = []
    for _ in range(n):
        state, _, s = encoder_step(state, np.array([speed * dt]), params, dt)
        measured.append(float(s[0]))
    m = np.array(measured[window:])  # once the window holds only moving samples
    # every sample is a whole number of quanta (the count difference times q; rounding of
    # a few operations on numbers < 1000: 1e-9 quanta)
    np.testing.assert_allclose(m / q, np.round(m / q), rtol=0, atol=1e-9)
    # and is floor or ceil of the true count difference: within one quantum of the truth
    assert np.all(np.abs(m - speed) < q)
    # the mean telescopes to (last W counts - first W counts) / (W dt K): its error is
    # below 2 pi / (cpr dt K) <= 0.005 rad/s here, 1e-3 relative of these speeds
    assert m.mean() == pytest.approx(speed, rel=1e-3)


def test_ideal_sensor_measures_the_exact_average_speed_over_the_window() -> None:
    dt, window = 0.01, 3
    params = EncoderParams(counts_per_rev=0, window_steps=window)
    rng = np.random.default_rng(7)
    dphi = rng.uniform(-0.2, 0.4, (50, 2, 2))  # a (N, 2) team of wheels
    state = encoder_init(np.zeros((2, 2)), params)
    angles = [np.zeros((2, 2))]
    for k in range(dphi.shape[0]):
        state, counts, speed = encoder_step(state, dphi[k], params, dt)
        angles.append(angles[-1] + dphi[k])
        np.testing.assert_array_equal(counts, angles[-1])  # the angle itself, bit for bit
        old = angles[max(0, len(angles) - 1 - window)]
        # (phi_k - phi_{k-W}) / (W dt): a subtraction and a division, 1e-12 rad/s
        np.testing.assert_allclose(speed, (angles[-1] - old) / (window * dt), rtol=0, atol=1e-12)
    assert state.history.shape == (window + 1, 2, 2)


def test_window_semantics_by_hand() -> None:
    # ideal sensor, W = 3, from rest: the history starts as W + 1 copies of the first
    # reading, so sample k measures (phi_k - phi_max(0, k-3)) / (3 dt)
    dt = 0.1
    params = EncoderParams(counts_per_rev=0, window_steps=3)
    state = encoder_init(0.0, params)
    d = [0.3, 0.6, 0.9, 1.2, 0.0, 0.0, 0.0]
    expected = [
        0.3 / 0.3,  # d1 / (3 dt)
        0.9 / 0.3,  # (d1 + d2) / (3 dt)
        1.8 / 0.3,  # (d1 + d2 + d3)
        2.7 / 0.3,  # (d2 + d3 + d4)
        2.1 / 0.3,  # (d3 + d4 + 0)
        1.2 / 0.3,  # (d4 + 0 + 0)
        0.0,
    ]
    got = []
    for dk in d:
        state, _, s = encoder_step(state, dk, params, dt)
        got.append(float(s))
    # sums of a few decimals: rounding ~1e-15, 1e-12 rad/s
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_window_of_one_is_the_count_difference_of_one_period() -> None:
    cpr, dt = 100, 0.01
    params = EncoderParams(counts_per_rev=cpr, window_steps=1)
    state = encoder_init(0.0, params)
    step = 2.0 * math.pi / cpr
    # turn 3.5, then 1.2, then 0.4 counts: count readings 3, 4, 5 (floor of 3.5, 4.7, 5.1)
    got = []
    for turns in (3.5, 1.2, 0.4):
        state, counts, s = encoder_step(state, turns * step, params, dt)
        got.append((float(counts), float(s)))
    q = step / dt
    expected = [(3.0, 3 * q), (4.0, 1 * q), (5.0, 1 * q)]
    # counts are exact integers; speeds are count differences times q (1e-9 rad/s)
    for (c, sp), (ce, se) in zip(got, expected, strict=True):
        assert c == ce
        assert sp == pytest.approx(se, abs=1e-9)


def test_encoder_at_rest_measures_zero() -> None:
    params = EncoderParams()
    state = encoder_init(np.full(4, 0.001), params)
    for _ in range(5):
        state, _, s = encoder_step(state, np.zeros(4), params, 0.01)
        assert np.all(s == 0.0)  # no count change: exactly zero


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [("counts_per_rev", {"counts_per_rev": -1}), ("window_steps", {"window_steps": 0})],
)
def test_invalid_params_raise_input_error(field: str, kwargs: dict[str, int]) -> None:
    with pytest.raises(InputError, match=field):
        EncoderParams(**kwargs)


@settings(max_examples=200, deadline=None)
@given(
    st.sampled_from([0, 1, 360, 2048, 100_000]),
    st.integers(1, 4),
    st.sampled_from([0.001, 0.01, 0.05]),
    st.floats(-1e3, 1e3, allow_nan=False),
    st.lists(st.floats(-0.5, 0.5, allow_nan=False), min_size=1, max_size=12),
)
def test_compiled_encoder_step_equals_numpy_bit_for_bit(
    cpr: int, window: int, dt: float, start: float, turns: list[float]
) -> None:
    # the caller of encoder_step_one keeps the history (here a list, oldest first); the
    # counts, angles and speeds are the same doubles as encoder_step's
    params = EncoderParams(counts_per_rev=cpr, window_steps=window)
    state = encoder_init(np.array([start]), params)
    history = [float(h) for h in state.history[:, 0]]
    angle = start
    per_rad, per_count = params.counts_per_rad, params.speed_per_count(dt)
    for dphi in turns:
        state, counts, speed = encoder_step(state, np.array([dphi]), params, dt)
        angle, count, measured = encoder_step_one(angle, dphi, history[1], per_rad, per_count)
        history = [*history[1:], count]
        assert (angle, count, measured) == (
            float(state.angle_rad[0]),
            float(counts[0]),
            float(speed[0]),
        )
