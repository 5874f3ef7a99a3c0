"""Spring-mass-damper robot (deliverable eq. 5) against its analytic solution and solve_ivp."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from firefleet.errors import InputError
from firefleet.models.mass_damper import MassDamperParams, mass_damper_step

M_KG, B_NSM, KD_NSM = 2.5, 0.8, 1.7
PARAMS = MassDamperParams(mass_kg=M_KG, damping_n_s_m=B_NSM, kd_n_s_m=KD_NSM)


def test_time_constant_is_m_over_b_plus_kd() -> None:
    assert PARAMS.time_constant_s == pytest.approx(M_KG / (B_NSM + KD_NSM), rel=1e-15)


def test_constant_force_matches_the_analytic_solution() -> None:
    dt, n = 0.01, 800
    s0 = np.array([[0.5, -1.0, 2.0, -0.7]])
    f = np.array([[3.0, 1.5]])
    tau = M_KG / (B_NSM + KD_NSM)
    v_inf = f[0] / (B_NSM + KD_NSM)
    v0, p0 = s0[0, 2:], s0[0, :2]
    state = s0.copy()
    for k in range(1, n + 1):
        state = mass_damper_step(state, f, dt, PARAMS)
        t = k * dt
        decay = math.exp(-t / tau)
        x = p0 + v_inf * t + (v0 - v_inf) * tau * (1.0 - decay)
        v = v_inf + (v0 - v_inf) * decay
        # 800 exact steps: only accumulated rounding on values < 10, far below 1e-10
        np.testing.assert_allclose(state[0, :2], x, rtol=0, atol=1e-10)
        np.testing.assert_allclose(state[0, 2:], v, rtol=0, atol=1e-10)


def test_terminal_velocity_is_force_over_total_damping() -> None:
    state = np.array([[0.0, 0.0, -4.0, 9.0]])
    f = np.array([[2.0, -5.0]])
    for _ in range(100):
        state = mass_damper_step(state, f, 0.5, PARAMS)
    # 50 s = 50 time constants: the transient exp(-50) ~ 2e-22 is gone; rounding 1e-12
    np.testing.assert_allclose(state[0, 2:], f[0] / (B_NSM + KD_NSM), rtol=1e-12, atol=0)


def test_matches_solve_ivp_of_eq_5() -> None:
    s0 = [1.0, 2.0, -0.5, 0.25]
    f = (0.9, -2.2)
    dt, n = 0.05, 60

    def rhs(_t: float, s: NDArray[np.float64]) -> list[float]:
        # eq. 5 as printed: M x'' + B x' = f_x - k_d x'
        return [
            s[2],
            s[3],
            (f[0] - B_NSM * s[2] - KD_NSM * s[2]) / M_KG,
            (f[1] - B_NSM * s[3] - KD_NSM * s[3]) / M_KG,
        ]

    t_eval = np.arange(1, n + 1) * dt
    sol = solve_ivp(rhs, (0.0, n * dt), s0, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=t_eval)
    assert sol.success
    state = np.array([s0])
    out = []
    for _ in range(n):
        state = mass_damper_step(state, np.array([f]), dt, PARAMS)
        out.append(state[0].copy())
    # solve_ivp at rtol 1e-10 over 3 s on values < 3: global error far below 1e-8
    np.testing.assert_allclose(np.array(out), sol.y.T, rtol=0, atol=1e-8)


def test_many_small_steps_equal_one_big_step() -> None:
    s0 = np.array([[0.1, 0.2, 1.5, -2.5], [-3.0, 4.0, 0.0, 0.0]])
    f = np.array([[1.0, -0.5], [-2.0, 3.0]])
    small = s0.copy()
    for _ in range(100):
        small = mass_damper_step(small, f, 0.01, PARAMS)
    big = mass_damper_step(s0, f, 1.0, PARAMS)
    # the exact discretisation composes: exp(-0.01/tau)^100 = exp(-1/tau); rounding 1e-12
    np.testing.assert_allclose(small, big, rtol=0, atol=1e-12)


def test_batch_equals_loop_of_single_robots() -> None:
    rng = np.random.default_rng(8)
    s = rng.uniform(-5, 5, (9, 4))
    f = rng.uniform(-3, 3, (9, 2))
    batch = mass_damper_step(s, f, 0.02, PARAMS)
    single = np.concatenate(
        [mass_damper_step(s[i : i + 1], f[i : i + 1], 0.02, PARAMS) for i in range(9)]
    )
    # the same elementwise arithmetic (one scalar exp): bit for bit
    np.testing.assert_array_equal(batch, single)


def test_axes_are_independent() -> None:
    s0 = np.array([[0.0, 0.0, 1.0, 0.0]])
    out = mass_damper_step(s0, np.array([[0.0, 0.0]]), 0.3, PARAMS)
    # no force and no y-velocity: y stays exactly 0 (0 * anything)
    assert out[0, 1] == 0.0
    assert out[0, 3] == 0.0
    # free coasting: vx decays by exp(-dt/tau) (1e-15 relative, one exp)
    assert out[0, 2] == pytest.approx(math.exp(-0.3 * (B_NSM + KD_NSM) / M_KG), rel=1e-15)


@pytest.mark.parametrize(
    ("name", "state", "force"),
    [
        ("state", np.zeros((2, 3)), np.zeros((2, 2))),
        ("force_n", np.zeros((2, 4)), np.zeros((3, 2))),
    ],
)
def test_wrong_shapes_raise_input_error(
    name: str, state: NDArray[np.float64], force: NDArray[np.float64]
) -> None:
    with pytest.raises(InputError, match=name):
        mass_damper_step(state, force, 0.01, PARAMS)


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("mass_kg", {"mass_kg": 0.0}),
        ("mass_kg", {"mass_kg": -1.0}),
        ("damping_n_s_m", {"damping_n_s_m": -0.1}),
        ("kd_n_s_m", {"kd_n_s_m": -0.1}),
        ("kd_n_s_m", {"damping_n_s_m": 0.0, "kd_n_s_m": 0.0}),
    ],
)
def test_bad_params_raise_input_error(field: str, kwargs: dict[str, float]) -> None:
    with pytest.raises(InputError, match=field):
        MassDamperParams(**kwargs)
