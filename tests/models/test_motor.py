"""DC motor (deliverable Table 2) against hand formulas, python-control and solve_ivp."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from firefleet.errors import InputError
from firefleet.models.motor import MotorParams, discretise_motor, motor_step, motor_step_one

# Table 2 of the deliverable, written out here so the test does not trust the defaults
R_OHM, L_H, J_KG_M2, B_NMS, KE, KT = 3.07, 0.04, 0.0294, 0.0141, 0.65, 0.65
TABLE2 = MotorParams(
    resistance_ohm=R_OHM,
    inductance_h=L_H,
    inertia_kg_m2=J_KG_M2,
    damping_n_m_s=B_NMS,
    back_emf_v_s=KE,
    torque_n_m_a=KT,
)


def _hand_matrices() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A, B of L di/dt = V - R i - Ke w, J dw/dt = Kt i - B w - tau, written out by hand."""
    A = np.array([[-R_OHM / L_H, -KE / L_H], [KT / J_KG_M2, -B_NMS / J_KG_M2]])
    B = np.array([[1.0 / L_H, 0.0], [0.0, -1.0 / J_KG_M2]])
    return A, B


def test_defaults_are_table_2() -> None:
    assert MotorParams() == TABLE2


def test_steady_speed_for_1_volt_no_load() -> None:
    gain = TABLE2.speed_gain_rad_s_per_v
    # the deliverable's number (Figure 24 "settles to around 1.4"), printed with 4 decimals:
    # half a unit of the last printed digit
    assert abs(gain - 1.3955) < 0.5e-4
    # the formula Kt / (R B + Ke Kt) evaluated here: same few operations, 1e-12 relative
    assert gain == pytest.approx(KT / (R_OHM * B_NMS + KE * KT), rel=1e-12, abs=0)
    i_ss, w_ss = TABLE2.steady_state(1.0)
    # a 2x2 linear solve of a well-conditioned system: 1e-12 relative
    assert w_ss == pytest.approx(gain, rel=1e-12, abs=0)
    # no-load current B w / Kt from the mechanical equation
    assert i_ss == pytest.approx(B_NMS * gain / KT, rel=1e-12, abs=0)


@pytest.mark.parametrize(("volts", "load"), [(12.0, 0.5), (6.0, -0.2), (0.0, 0.3)])
def test_steady_state_with_load_solves_the_two_equations(volts: float, load: float) -> None:
    # 0 = V - R i - Ke w and 0 = Kt i - B w - tau, eliminated by hand:
    # w = (Kt V - R tau) / (R B + Ke Kt), i = (B V + Ke tau) / (R B + Ke Kt)
    den = R_OHM * B_NMS + KE * KT
    w_hand = (KT * volts - R_OHM * load) / den
    i_hand = (B_NMS * volts + KE * load) / den
    i_ss, w_ss = TABLE2.steady_state(volts, load)
    # 2x2 solve of a matrix with condition number ~ 20: 1e-12 of the largest value
    assert i_ss == pytest.approx(i_hand, rel=1e-12, abs=1e-12)
    assert w_ss == pytest.approx(w_hand, rel=1e-12, abs=1e-12)
    # and the residuals of the two equations vanish
    assert volts - R_OHM * i_ss - KE * w_ss == pytest.approx(0.0, abs=1e-12)
    assert KT * i_ss - B_NMS * w_ss - load == pytest.approx(0.0, abs=1e-12)


def test_matrices_are_the_equations() -> None:
    A, B = _hand_matrices()
    # the same quotients computed the same way: bit for bit
    np.testing.assert_array_equal(TABLE2.a_matrix, A)
    np.testing.assert_array_equal(TABLE2.b_matrix, B)


def test_time_constants_from_trace_and_determinant() -> None:
    A, _ = _hand_matrices()
    tr = A[0, 0] + A[1, 1]
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    disc = math.sqrt(tr * tr - 4.0 * det)
    lam_slow, lam_fast = (tr + disc) / 2.0, (tr - disc) / 2.0
    slow, fast = TABLE2.time_constants_s
    # eigenvalues of a 2x2 by LAPACK vs the quadratic formula: 1e-10 relative
    assert slow == pytest.approx(-1.0 / lam_slow, rel=1e-10)
    assert fast == pytest.approx(-1.0 / lam_fast, rel=1e-10)
    # the module docstring's numbers: poles -5.5 and -71.7 rad/s (printed with 1 decimal)
    assert -1.0 / slow == pytest.approx(-5.5, abs=0.05)
    assert -1.0 / fast == pytest.approx(-71.7, abs=0.05)


def test_underdamped_motor_has_no_real_time_constants() -> None:
    # L = 1 H: tr^2 = 12.6 < 4 det = 63.4, complex poles
    motor = MotorParams(inductance_h=1.0)
    with pytest.raises(InputError, match="underdamped"):
        _ = motor.time_constants_s


def _simulate(
    volts: NDArray[np.float64], load: NDArray[np.float64], dt: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Iterate motor_step from rest; returns i, w at t = 0..n dt and the dphi of each step."""
    motor = discretise_motor(TABLE2, dt)
    i, w = np.float64(0.0), np.float64(0.0)
    cur, spd, dphis = [0.0], [0.0], []
    for k in range(volts.size):
        i_next, w_next, dphi = motor_step(i, w, volts[k], load[k], motor)
        i, w = np.float64(i_next), np.float64(w_next)
        cur.append(float(i))
        spd.append(float(w))
        dphis.append(float(dphi))
    return np.array(cur), np.array(spd), np.array(dphis)


def _control_plant() -> object:
    A, B = _hand_matrices()
    return control.ss(A, B, np.eye(2), np.zeros((2, 2)))


def test_voltage_step_matches_python_control() -> None:
    dt, n = 0.01, 1000
    volts, load = np.ones(n), np.zeros(n)
    cur, spd, _ = _simulate(volts, load, dt)
    t = np.arange(n + 1) * dt
    u = np.zeros((2, n + 1))
    u[0] = 1.0  # a constant input: control's linear interpolation between samples is exact
    ref = control.forced_response(_control_plant(), t, u, initial_state=[0.0, 0.0])
    # the brief's bound; both are exact discretisations, the observed gap is rounding ~1e-14
    np.testing.assert_allclose(cur, ref.outputs[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(spd, ref.outputs[1], rtol=0, atol=1e-6)
    # and the run ends at the steady state (10 s = 55 slow time constants; 1e-12 relative)
    assert spd[-1] == pytest.approx(TABLE2.speed_gain_rad_s_per_v, rel=1e-12)


def test_load_torque_step_matches_python_control() -> None:
    dt, n, k_load = 0.01, 1000, 500
    volts, load = np.full(n, 6.0), np.zeros(n)
    load[k_load:] = 0.3  # a load step held from t = 5 s (sample 500) on
    cur, spd, _ = _simulate(volts, load, dt)
    # reference: two continuous segments with constant inputs, so python-control's
    # interpolation of the input between samples cannot smear the step
    plant = _control_plant()
    t1 = np.arange(k_load + 1) * dt
    seg1 = control.forced_response(plant, t1, np.vstack([np.full(t1.size, 6.0), np.zeros(t1.size)]))
    t2 = np.arange(n - k_load + 1) * dt
    seg2 = control.forced_response(
        plant,
        t2,
        np.vstack([np.full(t2.size, 6.0), np.full(t2.size, 0.3)]),
        initial_state=seg1.states[:, -1],
    )
    ref = np.concatenate([seg1.outputs, seg2.outputs[:, 1:]], axis=1)
    # the brief's bound (observed gap: rounding, ~1e-14)
    np.testing.assert_allclose(cur, ref[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(spd, ref[1], rtol=0, atol=1e-6)
    # the load lowers the final speed to the hand steady state (5 s = 27 slow time constants)
    _, w_ss = TABLE2.steady_state(6.0, 0.3)
    assert spd[-1] == pytest.approx(w_ss, rel=1e-9)


def test_load_torque_step_matches_python_control_zoh_c2d() -> None:
    # a second, discrete reference: control.c2d with a zero-order hold, same input samples
    dt, n, k_load = 0.01, 600, 200
    volts, load = np.full(n, 12.0), np.zeros(n)
    load[k_load:] = 0.5
    cur, spd, _ = _simulate(volts, load, dt)
    plant_d = control.c2d(_control_plant(), dt, method="zoh")
    t = np.arange(n + 1) * dt
    u = np.vstack([np.append(volts, volts[-1]), np.append(load, load[-1])])
    ref = control.forced_response(plant_d, t, u)
    # same exact discretisation computed by scipy.signal: rounding only, values < 20
    np.testing.assert_allclose(cur, ref.outputs[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(spd, ref.outputs[1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("dt", [0.01, 0.37])
def test_zoh_step_matches_solve_ivp_including_angle(dt: float) -> None:
    i0, w0, volts, load = 0.8, -2.0, 7.5, 0.12

    def rhs(_t: float, s: NDArray[np.float64]) -> list[float]:
        i, w = s[0], s[1]
        return [
            (volts - R_OHM * i - KE * w) / L_H,
            (KT * i - B_NMS * w - load) / J_KG_M2,
            w,  # dphi/dt = w
        ]

    sol = solve_ivp(rhs, (0.0, dt), [i0, w0, 0.0], method="RK45", rtol=1e-10, atol=1e-12)
    assert sol.success
    i1, w1, dphi = motor_step(i0, w0, volts, load, discretise_motor(TABLE2, dt))
    # RK45 at rtol 1e-10 over one step: error far below 1e-8 on values < 20
    assert float(i1) == pytest.approx(sol.y[0, -1], abs=1e-8)
    assert float(w1) == pytest.approx(sol.y[1, -1], abs=1e-8)
    assert float(dphi) == pytest.approx(sol.y[2, -1], abs=1e-8)


@pytest.mark.parametrize("dt", [0.01, 0.0037])
def test_two_steps_of_dt_equal_one_step_of_2dt(dt: float) -> None:
    m1 = discretise_motor(TABLE2, dt)
    m2 = discretise_motor(TABLE2, 2.0 * dt)
    i0, w0, volts, load = 0.3, 4.0, -3.0, 0.05
    ia, wa, da = motor_step(i0, w0, volts, load, m1)
    ib, wb, db = motor_step(ia, wa, volts, load, m1)
    ic, wc, dc = motor_step(i0, w0, volts, load, m2)
    # exp(A 2dt) = exp(A dt)^2 for the exact discretisation: rounding of expm only
    assert float(ib) == pytest.approx(float(ic), abs=1e-12)
    assert float(wb) == pytest.approx(float(wc), abs=1e-12)
    assert float(da + db) == pytest.approx(float(dc), abs=1e-12)


def test_batched_motor_step_equals_per_element() -> None:
    rng = np.random.default_rng(5)
    motor = discretise_motor(TABLE2, 0.01)
    i = rng.uniform(-2, 2, (6, 2))
    w = rng.uniform(-10, 10, (6, 2))
    v = rng.uniform(-12, 12, (6, 2))
    tl = rng.uniform(-0.5, 0.5, (6, 2))
    ib, wb, db = motor_step(i, w, v, tl, motor)
    for r in range(6):
        for c in range(2):
            ie, we, de = motor_step(i[r, c], w[r, c], v[r, c], tl[r, c], motor)
            # the same multiply-adds elementwise: bit for bit
            assert ib[r, c] == ie
            assert wb[r, c] == we
            assert db[r, c] == de


def test_input_broadcasts_over_the_team() -> None:
    motor = discretise_motor(TABLE2, 0.01)
    i = np.zeros((3, 2))
    w = np.linspace(0.0, 5.0, 6).reshape(3, 2)
    ib, wb, db = motor_step(i, w, 4.0, 0.1, motor)
    ie, we, de = motor_step(i, w, np.full((3, 2), 4.0), np.full((3, 2), 0.1), motor)
    np.testing.assert_array_equal(ib, ie)  # broadcasting a scalar: bit for bit
    np.testing.assert_array_equal(wb, we)
    np.testing.assert_array_equal(db, de)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("resistance_ohm", -3.07),
        ("resistance_ohm", 0.0),
        ("inductance_h", math.nan),
        ("inertia_kg_m2", -1.0),
        ("back_emf_v_s", 0.0),
        ("torque_n_m_a", math.inf),
        ("supply_v", -12.0),
        ("damping_n_m_s", -0.01),
    ],
)
def test_bad_parameters_raise_input_error_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(InputError, match=field):
        MotorParams(**{field: value})


def test_zero_damping_is_allowed() -> None:
    motor = MotorParams(damping_n_m_s=0.0)
    # B = 0: the no-load speed is exactly 1 / Ke per volt
    assert motor.speed_gain_rad_s_per_v == pytest.approx(1.0 / KE, rel=1e-15)


@pytest.mark.parametrize("dt", [0.0, -0.01, math.nan, math.inf])
def test_bad_step_raises_input_error(dt: float) -> None:
    with pytest.raises(InputError, match="dt_s"):
        discretise_motor(TABLE2, dt)


@settings(max_examples=300, deadline=None)
@given(
    st.floats(-20.0, 20.0),
    st.floats(-50.0, 50.0),
    st.floats(-12.0, 12.0),
    st.floats(-1.0, 1.0),
    st.sampled_from([0.001, 0.01, 0.05]),
    st.floats(0.5, 2.0),
)
def test_compiled_motor_step_equals_numpy_bit_for_bit(
    current: float, speed: float, volts: float, load: float, dt: float, scale: float
) -> None:
    # the same four products summed in the same order: identical doubles
    motor = discretise_motor(
        MotorParams(resistance_ohm=R_OHM * scale, inertia_kg_m2=J_KG_M2 / scale), dt
    )
    got = motor_step_one(current, speed, volts, load, motor.coefficients)
    ref = motor_step(current, speed, volts, load, motor)
    assert got == tuple(float(v) for v in ref)
