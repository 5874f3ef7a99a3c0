"""Speed PID: each term by hand, saturation, anti-windup, and the closed loop of Figure 25."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from firefleet.control.pid import PidParams, PidState, pid_init, pid_step, pid_step_one
from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams, encoder_init, encoder_step
from firefleet.models.motor import MotorParams, discretise_motor, motor_step
from firefleet.sim.metrics import settling_time, step_response_info

DT = 0.01  # the deliverable's fixed step (section 2.6.4)


def test_proportional_only_output_is_kp_times_weighted_error() -> None:
    params = PidParams(kp=2.0, ki=0.0, kd=0.0, setpoint_weight=0.7)
    r = np.array([[1.0, -2.0], [3.0, 0.5]])
    y = np.array([[0.2, -1.0], [2.5, 0.9]])
    state = pid_init(y)  # previous measurement = y: no derivative either way
    _, u = pid_step(state, r, y, params, DT)
    # kp (b r - y) by hand; a few operations on values < 10: 1e-14
    np.testing.assert_allclose(u, 2.0 * (0.7 * r - y), rtol=0, atol=1e-14)


def test_integral_accumulates_ki_dt_error_per_step() -> None:
    params = PidParams(kp=0.0, ki=3.0, kd=0.0)
    rng = np.random.default_rng(9)
    r = rng.uniform(-1, 1, 40)
    y = rng.uniform(-1, 1, 40)
    state = pid_init(0.0)
    total = 0.0
    for k in range(40):
        state, u = pid_step(state, r[k], y[k], params, DT)
        # the output uses the integral before this period's error is added
        assert float(u) == pytest.approx(total, abs=1e-13)
        total += 3.0 * DT * (r[k] - y[k])
        # the same running sum of ki dt e, < 1 V: 1e-13 covers the rounding of 40 additions
        assert float(state.integral) == pytest.approx(total, abs=1e-13)


def test_output_saturates_at_the_limit() -> None:
    params = PidParams(kp=100.0, ki=0.0, kd=0.0, setpoint_weight=1.0, output_limit=12.0)
    state = pid_init(np.zeros(4))
    _, u = pid_step(state, np.array([1.0, -1.0, 0.05, -0.05]), np.zeros(4), params, DT)
    # clipped values are the limit exactly; 100 * 0.05 = 5 V is inside the limit
    np.testing.assert_array_equal(u[:2], [12.0, -12.0])
    np.testing.assert_allclose(u[2:], [5.0, -5.0], rtol=1e-15)


def _motor_loop(
    params: PidParams, refs: NDArray[np.float64], encoder: EncoderParams, phase: float = 0.0
) -> tuple[NDArray[np.float64], list[PidState]]:
    """One wheel: PID -> Table 2 motor -> encoder, the order of firefleet.sim.engine.

    Returns the true speed at t = 0, dt, ..., n dt and the PID state after each period.
    """
    motor = discretise_motor(MotorParams(), DT)
    cur, spd = np.zeros(1), np.zeros(1)
    enc = encoder_init(np.full(1, phase), encoder)
    measured = np.zeros(1)
    pid = pid_init(measured)
    speeds, states = [0.0], []
    for r in refs:
        pid, volts = pid_step(pid, np.full(1, r), measured, params, DT)
        states.append(pid)
        cur, spd, dphi = motor_step(cur, spd, volts, 0.0, motor)
        enc, _, measured = encoder_step(enc, dphi, encoder, DT)
        speeds.append(float(spd[0]))
    return np.array(speeds), states


def test_anti_windup_bounds_the_integral_and_speeds_recovery() -> None:
    # 40 rad/s is out of reach (12 V gives at most 12 * 1.3955 = 16.7 rad/s): the output
    # saturates for 4 s, then the reference drops to a reachable 5 rad/s for 16 s
    ideal = EncoderParams(counts_per_rev=0)
    k_drop = 400
    refs = np.concatenate([np.full(k_drop, 40.0), np.full(1600, 5.0)])
    aw = PidParams()
    no_aw = PidParams(tracking_time_s=1e12)  # back-calculation switched off in effect
    w_aw, s_aw = _motor_loop(aw, refs, ideal)
    w_no, s_no = _motor_loop(no_aw, refs, ideal)
    i_aw_2s, i_aw_4s = float(s_aw[199].integral[0]), float(s_aw[k_drop - 1].integral[0])
    i_no_2s, i_no_4s = float(s_no[199].integral[0]), float(s_no[k_drop - 1].integral[0])
    # with anti-windup the integral converges to the fixed point of the back-calculation,
    # I = u_max + ki e T_t - kp (b r - y) - D, with e = 40 - 16.7 = 23.3 rad/s:
    # 12 + 25 * 23.3 * 0.1 - 2.5 * (20 - 16.7) = 62 V; it is bounded and flat between 2 s
    # and 4 s (2 s = 20 T_t and 11 mechanical time constants: converged to < 1e-3 V)
    w_top = 12.0 * MotorParams().speed_gain_rad_s_per_v
    i_fixed = 12.0 + 25.0 * (40.0 - w_top) * 0.1 - 2.5 * (0.5 * 40.0 - w_top)
    assert i_aw_4s == pytest.approx(i_fixed, rel=1e-3)
    assert abs(i_aw_4s - i_aw_2s) < 1e-3
    # without it the integral keeps growing by ki e over the last 2 s: 25 * 23.3 * 2 = 1165 V
    # (1e-3 relative: the speed is within exp(-11) of its top from 2 s on)
    assert i_no_4s - i_no_2s == pytest.approx(25.0 * (40.0 - w_top) * 2.0, rel=1e-3)
    assert i_no_4s > 10.0 * i_aw_4s
    # recovery into the 2 % band of 5 rad/s after the drop (t = 4 s)
    t = np.arange(refs.size + 1) * DT
    after = slice(k_drop, None)
    rec_aw = settling_time(t[after], w_aw[after], 5.0, t0_s=k_drop * DT)
    rec_no = settling_time(t[after], w_no[after], 5.0, t0_s=k_drop * DT)
    # both settle in the 16 s left, the wound-up loop far later: it stays saturated at
    # 16.7 rad/s until it has unwound ~2400 - 60 V at ki |e| = 25 * 11.7 = 292 V/s, about
    # 8 s, while the back-calculated one needs a few mechanical time constants (< 1 s)
    assert rec_aw < 1.0
    assert math.isfinite(rec_no)
    assert rec_no > 7.0
    assert rec_no > 4.0 * rec_aw


def test_reference_step_gives_no_derivative_kick() -> None:
    params = PidParams(kp=0.0, ki=0.0, kd=1.0, derivative_filter_s=0.01)
    state = pid_init(np.full(3, 2.0))
    state, u0 = pid_step(state, np.zeros(3), np.full(3, 2.0), params, DT)
    state, u1 = pid_step(state, np.array([5.0, -5.0, 100.0]), np.full(3, 2.0), params, DT)
    # the measurement did not move: the derivative term is exactly zero
    np.testing.assert_array_equal(u0, 0.0)
    np.testing.assert_array_equal(u1, 0.0)
    np.testing.assert_array_equal(state.derivative, 0.0)


def test_reference_step_kick_is_only_the_weighted_proportional_part() -> None:
    params = PidParams(kp=2.5, ki=0.0, kd=0.05, setpoint_weight=0.5)
    state = pid_init(1.0)
    state, u0 = pid_step(state, 1.0, 1.0, params, DT)
    _, u1 = pid_step(state, 3.0, 1.0, params, DT)
    # the output jumps by kp b dr = 2.5 * 0.5 * 2 = 2.5 V, nothing more (1e-14)
    assert float(u1 - u0) == pytest.approx(2.5, abs=1e-14)


def test_filtered_derivative_of_a_ramp_converges_to_minus_kd_slope() -> None:
    kd, tf, slope = 0.05, 0.01, 3.0
    params = PidParams(kp=0.0, ki=0.0, kd=kd, derivative_filter_s=tf)
    state = pid_init(0.0)
    a = tf / (tf + DT)  # pole of the backward-Euler filter
    for k in range(1, 61):
        state, u = pid_step(state, 0.0, slope * k * DT, params, DT)
        # backward Euler of D = -kd s / (1 + tf s) y on a ramp: -kd slope (1 - a^k) by hand
        assert float(u) == pytest.approx(-kd * slope * (1.0 - a**k), abs=1e-13)
    # a = 0.5, after 60 periods a^60 ~ 1e-18: the limit -kd slope (1e-13 as above)
    assert float(u) == pytest.approx(-kd * slope, abs=1e-13)


def test_batched_pid_equals_per_element() -> None:
    rng = np.random.default_rng(10)
    params = PidParams(kp=3.0, ki=40.0, kd=0.02, output_limit=5.0)  # some outputs saturate
    r = rng.uniform(-3, 3, (30, 4, 2))
    y = rng.uniform(-3, 3, (30, 4, 2))
    batch = pid_init(np.zeros((4, 2)))
    singles = [[pid_init(0.0) for _ in range(2)] for _ in range(4)]
    saturated = 0
    for k in range(30):
        batch, ub = pid_step(batch, r[k], y[k], params, DT)
        saturated += int(np.count_nonzero(np.abs(ub) == 5.0))
        for i in range(4):
            for j in range(2):
                singles[i][j], ue = pid_step(singles[i][j], r[k, i, j], y[k, i, j], params, DT)
                # the same elementwise arithmetic: bit for bit
                assert ub[i, j] == ue
                assert batch.integral[i, j] == singles[i][j].integral
    assert saturated > 0  # the anti-windup branch was exercised too


@pytest.mark.parametrize("phase_counts", [0.0, 0.25, 0.5, 0.75])
def test_closed_loop_meets_the_deliverable_bounds(phase_counts: float) -> None:
    # Figure 25: "the response time ... is less than 200 ms while the settling time is
    # less than 500 ms", default gains, Table 2 motor, 2048-count encoder, 1 rad/s step
    encoder = EncoderParams()
    phase = phase_counts * 2.0 * math.pi / encoder.counts_per_rev
    n = 300
    w, _ = _motor_loop(PidParams(), np.ones(n), encoder, phase)
    t = np.arange(n + 1) * DT
    info = step_response_info(t, w, 1.0)
    assert info["rise_time_s"] < 0.2
    assert info["settling_time_s"] < 0.5
    assert info["rise_time_s"] > 0.0  # a real rise, not a degenerate jump
    # the motor-pid scenario's overshoot claim (foundation issue): at most 5 %
    assert info["overshoot_pct"] <= 5.0
    # the integral removes the steady error: the mean of the last second is inside 2 %
    assert abs(w[-100:].mean() - 1.0) < 0.02


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("kp", -1.0),
        ("ki", math.nan),
        ("kd", -0.1),
        ("derivative_filter_s", 0.0),
        ("tracking_time_s", -1.0),
        ("output_limit", 0.0),
        ("setpoint_weight", 1.5),
    ],
)
def test_bad_params_raise_input_error(field: str, value: float) -> None:
    with pytest.raises(InputError, match=field):
        PidParams(**{field: value})


@settings(max_examples=300, deadline=None)
@given(
    st.tuples(*[st.floats(-30.0, 30.0)] * 5),
    st.floats(0.0, 10.0),
    st.floats(0.0, 50.0),
    st.floats(0.0, 0.05),
    st.floats(1e-3, 0.1),
    st.floats(0.0, 1.0),
    st.floats(1e-2, 1.0),
    st.floats(0.5, 24.0),
    st.sampled_from([0.001, 0.01, 0.02]),
)
def test_compiled_pid_step_equals_numpy_bit_for_bit(
    values: tuple[float, float, float, float, float],
    kp: float,
    ki: float,
    kd: float,
    tf: float,
    b: float,
    tt: float,
    lim: float,
    dt: float,
) -> None:
    # the same operations in the same order (the clip as two comparisons), saturated or
    # not (|u| up to some 300 V against limits of 0.5-24 V): identical doubles
    integral, derivative, last, r, y = values
    params = PidParams(
        kp=kp,
        ki=ki,
        kd=kd,
        derivative_filter_s=tf,
        setpoint_weight=b,
        tracking_time_s=tt,
        output_limit=lim,
    )
    state = PidState(
        integral=np.array(integral),
        derivative=np.array(derivative),
        last_measurement=np.array(last),
    )
    ref_state, ref_u = pid_step(state, r, y, params, dt)
    got = pid_step_one(integral, derivative, last, r, y, params.gains, dt)
    assert got == (float(ref_state.integral), float(ref_state.derivative), float(ref_u))
