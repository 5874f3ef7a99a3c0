"""Step-response metrics against python-control's step_info and analytic responses."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.sim.metrics import recovery_time, settling_time, step_response_info

DT_FINE = 1e-4  # fine sampling, so index-based and interpolated crossings agree


def _second_order_step(
    t: NDArray[np.float64], wn: float, zeta: float, gain: float = 1.0
) -> NDArray[np.float64]:
    """Unit-step response of gain wn^2 / (s^2 + 2 zeta wn s + wn^2), 0 < zeta < 1."""
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    phi = math.acos(zeta)
    y = 1.0 - np.exp(-zeta * wn * t) * np.sin(wd * t + phi) / math.sqrt(1.0 - zeta * zeta)
    return np.asarray(gain * y, dtype=np.float64)


@pytest.mark.parametrize(
    ("wn", "zeta", "gain"), [(10.0, 0.3, 1.0), (6.0, 0.6, 2.5), (15.0, 0.45, -0.8)]
)
def test_step_response_info_matches_python_control(wn: float, zeta: float, gain: float) -> None:
    t = np.arange(0.0, 3.0 + DT_FINE / 2, DT_FINE)
    y = _second_order_step(t, wn, zeta, gain)
    ours = step_response_info(t, y, gain)
    ref = control.step_info(y, T=t, yfinal=gain)
    # the same array, the same max: the overshoot differs only by rounding (brief: 1e-6 %)
    assert ours["overshoot_pct"] == pytest.approx(ref["Overshoot"], abs=1e-6)
    # python-control takes the first sample at/over each level, we interpolate between
    # samples: each crossing differs by less than one sample, a difference by < 2 samples
    assert ours["rise_time_s"] == pytest.approx(ref["RiseTime"], abs=2 * DT_FINE)
    # settling: python-control takes the sample after the last one outside, we interpolate
    # the exit: less than one sample apart, two allowed
    assert ours["settling_time_s"] == pytest.approx(ref["SettlingTime"], abs=2 * DT_FINE)


def test_step_response_info_matches_the_analytic_second_order_figures() -> None:
    wn, zeta = 10.0, 0.3
    t = np.arange(0.0, 3.0 + DT_FINE / 2, DT_FINE)
    info = step_response_info(t, _second_order_step(t, wn, zeta), 1.0)
    # peak overshoot exp(-pi zeta / sqrt(1 - zeta^2)) = 37.23 %; the sampled peak misses
    # the true one by at most y'' dt^2 / 8 ~ 40 * 1e-8 / 8 = 5e-8, i.e. 5e-6 %: allow 1e-5 %
    os_exact = 100.0 * math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))
    assert info["overshoot_pct"] == pytest.approx(os_exact, abs=1e-5)

    # the 10 % and 90 % crossings from the analytic response by bisection
    def cross(level: float, lo: float, hi: float) -> float:
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if _second_order_step(np.array([mid]), wn, zeta)[0] < level:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    t_peak = math.pi / (wn * math.sqrt(1.0 - zeta * zeta))
    rise_exact = cross(0.9, 0.0, t_peak) - cross(0.1, 0.0, t_peak)
    # linear interpolation between samples: error ~ y'' dt^2 / (8 y') per crossing, below
    # 1e-8 s here; 1e-7 s allowed
    assert info["rise_time_s"] == pytest.approx(rise_exact, abs=1e-7)


def test_settling_time_is_inf_if_still_outside_at_the_end() -> None:
    t = np.linspace(0.0, 1.0, 101)
    y = 1.0 - np.exp(-t)  # ends at 0.63, far outside the 2 % band of 1
    assert settling_time(t, y, 1.0) == math.inf
    assert step_response_info(t, y, 1.0)["settling_time_s"] == math.inf
    assert step_response_info(t, y, 1.0)["rise_time_s"] == math.inf  # 90 % never reached


def test_settling_time_is_zero_if_never_outside() -> None:
    t = np.linspace(0.0, 1.0, 11)
    y = 1.0 + 0.019 * np.sin(7.0 * t)  # always within 2 % of 1
    assert settling_time(t, y, 1.0) == 0.0


def test_settling_time_of_a_first_order_response() -> None:
    # y = 1 - exp(-t / tau) enters the 2 % band at tau ln 50 and never leaves
    tau = 0.3
    t = np.arange(0.0, 3.0 + 1e-6, 1e-3)
    y = 1.0 - np.exp(-t / tau)
    # linear interpolation error ~ y'' dt^2 / (8 y') = dt^2 / (8 tau) ~ 4e-7 s: allow 1e-6
    assert settling_time(t, y, 1.0) == pytest.approx(tau * math.log(50.0), abs=1e-6)
    # shifting the count's origin with t0_s subtracts it
    assert settling_time(t + 2.0, y, 1.0, t0_s=2.0) == pytest.approx(tau * math.log(50.0), abs=1e-6)
    # a 5 % band: tau ln 20
    assert settling_time(t, y, 1.0, band=0.05) == pytest.approx(tau * math.log(20.0), abs=1e-6)


def test_recovery_time_after_a_dip() -> None:
    # at the event (t = 2 s) the speed dips to 0.5 and recovers as 1 - 0.5 exp(-(t-2)/tau):
    # back inside 2 % of 1 when 0.5 exp(-T / tau) = 0.02, T = tau ln 25
    tau = 0.2
    t = np.arange(0.0, 5.0 + 1e-6, 1e-3)
    y = np.where(t < 2.0, 1.0, 1.0 - 0.5 * np.exp(-(t - 2.0) / tau))
    y[:200] = 0.0  # an unsettled start before the event must not count
    # interpolation error dt^2 / (8 tau) ~ 6e-7 s: allow 1e-6
    assert recovery_time(t, y, 1.0, 2.0) == pytest.approx(tau * math.log(25.0), abs=1e-6)
    # no dip after the event: 0
    assert recovery_time(t, np.ones_like(t), 1.0, 2.0) == 0.0
    # a dip that never recovers: inf
    assert recovery_time(t, np.where(t < 2.0, 1.0, 0.5), 1.0, 2.0) == math.inf


def test_recovery_time_needs_samples_after_the_event() -> None:
    t = np.linspace(0.0, 1.0, 11)
    with pytest.raises(InputError, match="event"):
        recovery_time(t, np.ones_like(t), 1.0, 2.0)


def test_bad_input_raises_input_error() -> None:
    t = np.linspace(0.0, 1.0, 11)
    with pytest.raises(InputError, match="target"):
        step_response_info(t, t, 0.0)
    with pytest.raises(InputError, match="y"):
        settling_time(t, np.ones(10), 1.0)
    with pytest.raises(InputError, match="sample"):
        settling_time(np.array([]), np.array([]), 1.0)
