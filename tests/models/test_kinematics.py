"""Kinematics of deliverable section 2.2 (eqs. 1-4) against analytic cases and solve_ivp."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from firefleet.errors import InputError
from firefleet.models.kinematics import (
    RobotGeometry,
    arc_step_one,
    body_to_wheels,
    diff_drive_step,
    diff_drive_step_one,
    unicycle_step,
    wheels_to_body,
    wrap_angle,
    wrap_angle_one,
)

# Table 2 of the deliverable: wheel radius r = 0.045 m, axle length L = 0.2 m.
TABLE2 = RobotGeometry(wheel_radius_m=0.045, axle_length_m=0.2)


def _angle_diff(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """a - b on the circle, in [-pi, pi] (independent of wrap_angle)."""
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    return np.asarray(np.arctan2(np.sin(d), np.cos(d)), dtype=np.float64)


def test_drive_straight_along_x_advances_v_t() -> None:
    v, dt, n = 0.37, 0.01, 1000
    pose = np.array([[1.0, -2.0, 0.0]])
    for _ in range(n):
        pose = unicycle_step(pose, v, 0.0, dt)
    # 1000 additions of v*dt to x ~ 4.7 m: rounding is at most 1000 ulp(4.7) ~ 1e-12 m
    np.testing.assert_allclose(pose[0, 0], 1.0 + v * n * dt, rtol=0, atol=1e-12)
    # with theta = 0 and omega = 0, y and theta are untouched: exact
    assert pose[0, 1] == -2.0
    assert pose[0, 2] == 0.0


def test_drive_straight_at_heading_follows_the_line() -> None:
    v, dt, n, th = 0.5, 0.02, 500, 2.3
    pose = np.array([[0.5, 0.25, th]])
    for _ in range(n):
        pose = unicycle_step(pose, v, 0.0, dt)
    t = n * dt
    # 500 steps of rounding on coordinates ~ 5 m: well below 1e-12 m
    np.testing.assert_allclose(
        pose[0, :2], [0.5 + v * t * math.cos(th), 0.25 + v * t * math.sin(th)], rtol=0, atol=1e-12
    )
    assert pose[0, 2] == th  # wrap of an angle already in [-pi, pi) with dtheta = 0: exact


def test_turn_in_place_keeps_position_and_turns_omega_t() -> None:
    omega, dt, n = -1.7, 0.01, 1234
    pose0 = np.array([[3.0, -4.0, 0.4]])
    pose = pose0.copy()
    thetas = []
    for _ in range(n):
        pose = unicycle_step(pose, 0.0, omega, dt)
        thetas.append(pose[0, 2])
    # v = 0 gives ds = 0, so the chord is exactly 0: x, y unchanged bit for bit
    assert pose[0, 0] == 3.0
    assert pose[0, 1] == -4.0
    t = np.arange(1, n + 1) * dt
    # n wrapped additions of omega*dt: accumulated rounding < n * ulp(pi) ~ 6e-13 rad
    np.testing.assert_allclose(_angle_diff(np.array(thetas), 0.4 + omega * t), 0.0, atol=1e-11)
    assert np.all(np.array(thetas) >= -np.pi)
    assert np.all(np.array(thetas) < np.pi)


@pytest.mark.parametrize(("v", "omega"), [(0.3, 0.7), (0.8, -2.5), (-0.4, 1.1)])
def test_circle_radius_centre_and_period(v: float, omega: float) -> None:
    n = 1000
    period = 2.0 * math.pi / abs(omega)
    dt = period / n
    x0, y0, th0 = 1.5, -0.5, 0.9
    radius = v / omega  # signed radius: centre on the left for radius > 0
    cx, cy = x0 - radius * math.sin(th0), y0 + radius * math.cos(th0)
    pose = np.array([[x0, y0, th0]])
    xs, ys, ths = [], [], []
    for _ in range(n):
        pose = unicycle_step(pose, v, omega, dt)
        xs.append(pose[0, 0])
        ys.append(pose[0, 1])
        ths.append(pose[0, 2])
    x, y = np.array(xs), np.array(ys)
    t = np.arange(1, n + 1) * dt
    # the brief's bound: each step is an exact arc, so the radius drifts only by rounding
    np.testing.assert_allclose(np.hypot(x - cx, y - cy), abs(radius), rtol=0, atol=1e-9)
    # analytic position on the circle, x = cx + r sin(th), y = cy - r cos(th) (same 1e-9 m)
    th = th0 + omega * t
    np.testing.assert_allclose(x, cx + radius * np.sin(th), rtol=0, atol=1e-9)
    np.testing.assert_allclose(y, cy - radius * np.cos(th), rtol=0, atol=1e-9)
    # after exactly one period the robot is back at the start (same 1e-9 m / rad)
    np.testing.assert_allclose(pose[0, :2], [x0, y0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(_angle_diff(pose[0, 2], th0), 0.0, atol=1e-9)


def test_body_to_wheels_matches_eqs_3_and_4_by_hand() -> None:
    # eq. 3: v_R = (2 v + omega L) / (2 R); eq. 4: v_L = (2 v - omega L) / (2 R)
    # with v = 0.5, omega = 1.2, R = 0.045, L = 0.2:
    # v_R = (1.0 + 0.24) / 0.09 = 124 / 9, v_L = (1.0 - 0.24) / 0.09 = 76 / 9
    wheels = body_to_wheels(np.array([0.5]), np.array([1.2]), TABLE2)
    assert wheels.shape == (1, 2)
    # a handful of float operations on numbers ~ 14: a few ulp, 1e-12 relative is ample
    np.testing.assert_allclose(wheels[0], [124.0 / 9.0, 76.0 / 9.0], rtol=1e-12, atol=0)


def test_wheels_to_body_matches_eq_1_by_hand() -> None:
    # eq. 1: xdot = R/2 (v_R + v_L) cos(theta), thetadot = R/L (v_R - v_L)
    # v_R = 10, v_L = 6: v = 0.045 / 2 * 16 = 0.36 m/s, omega = 0.045 / 0.2 * 4 = 0.9 rad/s
    v, omega = wheels_to_body(np.array([[10.0, 6.0]]), TABLE2)
    # a few float operations: 1e-14 absolute on values < 1
    np.testing.assert_allclose(v, [0.36], rtol=0, atol=1e-14)
    np.testing.assert_allclose(omega, [0.9], rtol=0, atol=1e-14)


def test_body_wheels_round_trip() -> None:
    rng = np.random.default_rng(1)
    v = rng.uniform(-2.0, 2.0, 50)
    omega = rng.uniform(-5.0, 5.0, 50)
    geom = RobotGeometry(wheel_radius_m=0.07, axle_length_m=0.31)
    v2, omega2 = wheels_to_body(body_to_wheels(v, omega, geom), geom)
    # two linear maps that are exact inverses: only rounding, < 1e-13 on values < 5
    np.testing.assert_allclose(v2, v, rtol=0, atol=1e-13)
    np.testing.assert_allclose(omega2, omega, rtol=0, atol=1e-13)


def test_diff_drive_step_equals_unicycle_step() -> None:
    rng = np.random.default_rng(2)
    n, dt = 20, 0.05
    pose = np.column_stack(
        [rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    wheel = rng.uniform(-20.0, 20.0, (n, 2))
    wheel[0] = [7.0, 7.0]  # straight
    wheel[1] = [5.0, -5.0]  # in place
    r, L = TABLE2.wheel_radius_m, TABLE2.axle_length_m
    v = r * (wheel[:, 0] + wheel[:, 1]) / 2.0  # eq. 1, written out
    omega = r * (wheel[:, 0] - wheel[:, 1]) / L
    a = diff_drive_step(pose, wheel * dt, TABLE2)
    b = unicycle_step(pose, v, omega, dt)
    # same arc computed from differently rounded ds, dtheta: a few ulp of 5 m / pi rad
    np.testing.assert_allclose(a[:, :2], b[:, :2], rtol=0, atol=1e-14)
    np.testing.assert_allclose(_angle_diff(a[:, 2], b[:, 2]), 0.0, atol=1e-14)


def _eq2_rhs(v: float, omega: float) -> Callable[[float, NDArray[np.float64]], list[float]]:
    def rhs(_t: float, s: NDArray[np.float64]) -> list[float]:
        return [v * math.cos(s[2]), v * math.sin(s[2]), omega]

    return rhs


@pytest.mark.parametrize("omega", [0.0, 1e-5, 3e-4, 0.5, -2.0, 7.0])
def test_unicycle_step_matches_solve_ivp(omega: float) -> None:
    v, dt, n = 0.6, 0.1, 30
    x0 = [0.2, -0.3, 2.9]
    sol = solve_ivp(
        _eq2_rhs(v, omega),
        (0.0, n * dt),
        x0,
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        t_eval=np.arange(1, n + 1) * dt,
    )
    assert sol.success
    pose = np.array([x0])
    out = []
    for _ in range(n):
        pose = unicycle_step(pose, v, omega, dt)
        out.append(pose[0].copy())
    got = np.array(out)
    # solve_ivp at rtol 1e-10 on a 3 s run with |x| < 2 m: global error well below 1e-8 m
    np.testing.assert_allclose(got[:, :2], sol.y[:2].T, rtol=0, atol=1e-8)
    np.testing.assert_allclose(_angle_diff(got[:, 2], sol.y[2]), 0.0, atol=1e-8)


def test_unicycle_batch_equals_loop_of_single_robots() -> None:
    rng = np.random.default_rng(3)
    n = 37  # odd, > 32: exercises numpy's vector loops and their scalar tails
    pose = np.column_stack(
        [rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    v = rng.uniform(-1, 1, n)
    omega = rng.uniform(-3, 3, n)
    omega[:3] = [0.0, 1e-6, -1e-6]  # straight and Taylor-branch robots in the batch
    batch = pose.copy()
    single = pose.copy()
    for _ in range(20):
        batch = unicycle_step(batch, v, omega, 0.05)
        single = np.concatenate(
            [
                unicycle_step(single[i : i + 1], v[i : i + 1], omega[i : i + 1], 0.05)
                for i in range(n)
            ]
        )
    # bit for bit but for numpy's SIMD sin/cos, which may differ by 1 ulp from the scalar
    # path; 20 steps of that on values < 10: 1e-15 relative plus 1e-14 absolute
    np.testing.assert_allclose(batch, single, rtol=1e-15, atol=1e-14)


def test_diff_drive_batch_equals_loop_of_single_robots() -> None:
    rng = np.random.default_rng(4)
    n = 37
    pose = np.column_stack(
        [rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    dphi = rng.uniform(-0.5, 0.5, (n, 2))
    batch = diff_drive_step(pose, dphi, TABLE2)
    single = np.concatenate(
        [diff_drive_step(pose[i : i + 1], dphi[i : i + 1], TABLE2) for i in range(n)]
    )
    # one step: at most 1 ulp from SIMD vs scalar sin/cos, < 1e-15 relative + 2e-15 m
    np.testing.assert_allclose(batch, single, rtol=1e-15, atol=2e-15)


def test_wrap_angle_range_and_congruence() -> None:
    a = np.concatenate(
        [
            np.linspace(-50.0, 50.0, 100_001),
            np.pi * np.arange(-20, 21),  # odd multiples of pi land on the boundary
            [0.0, 1e-300, -1e-300],
        ]
    )
    w = wrap_angle(a)
    assert np.all(w >= -np.pi)
    assert np.all(w < np.pi)
    # w - a is a whole number of turns; rounding of a ~ 50 rad: < 1e-13 turns
    turns = (w - a) / (2.0 * np.pi)
    np.testing.assert_allclose(turns, np.round(turns), rtol=0, atol=1e-13)
    # odd multiples of pi map to -pi, the closed end of [-pi, pi)
    assert wrap_angle(np.pi) == -np.pi
    assert wrap_angle(-np.pi) == -np.pi
    assert wrap_angle(0.5) == 0.5


def test_wrap_angle_half_open_range_at_float_edges() -> None:
    # the documented range is [-pi, pi); the doubles just outside it must wrap inside too
    edges = np.array(
        [
            np.nextafter(-np.pi, -np.inf),
            np.nextafter(np.pi, np.inf),
            np.nextafter(np.pi, 0.0),
            np.nextafter(-np.pi, 0.0),
            -3.0 * np.pi,
            np.nextafter(-3.0 * np.pi, -np.inf),
        ]
    )
    w = wrap_angle(edges)
    outside = (w < -np.pi) | (w >= np.pi)
    assert not outside.any(), f"wrap_angle({edges[outside]!r}) = {w[outside]!r}"


def test_pose_of_wrong_shape_raises_input_error() -> None:
    with pytest.raises(InputError, match="pose"):
        unicycle_step(np.zeros((4, 2)), 0.1, 0.1, 0.01)
    with pytest.raises(InputError, match="pose"):
        diff_drive_step(np.zeros((4, 2)), np.zeros((4, 2)), TABLE2)
    with pytest.raises(InputError, match="pose"):
        unicycle_step(np.zeros(3), 0.1, 0.1, 0.01)
    assert issubclass(InputError, ValueError)


def test_dphi_of_wrong_length_raises_input_error() -> None:
    with pytest.raises(InputError, match="dphi_rad"):
        diff_drive_step(np.zeros((4, 3)), np.zeros((3, 2)), TABLE2)
    with pytest.raises(InputError, match="dphi_rad"):
        diff_drive_step(np.zeros((4, 3)), np.zeros((4, 3)), TABLE2)


def test_wheel_speeds_of_wrong_shape_and_non_finite_pose_raise() -> None:
    with pytest.raises(InputError, match="wheel_rad_s"):
        wheels_to_body(np.zeros((2, 3)), TABLE2)
    with pytest.raises(InputError, match="pose"):
        unicycle_step(np.array([[0.0, np.nan, 0.0]]), 0.1, 0.1, 0.01)


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("wheel_radius_m", {"wheel_radius_m": -0.045}),
        ("wheel_radius_m", {"wheel_radius_m": 0.0}),
        ("axle_length_m", {"axle_length_m": math.nan}),
    ],
)
def test_bad_geometry_raises_input_error(field: str, kwargs: dict[str, float]) -> None:
    with pytest.raises(InputError, match=field):
        RobotGeometry(**kwargs)


# ---------------------------------------------- compiled scalar forms = NumPy reference


@settings(max_examples=300, deadline=None)
@given(st.floats(-1e6, 1e6))
def test_compiled_wrap_equals_numpy_bit_for_bit(angle: float) -> None:
    # the same operations (the compiled form skips a modulo that would change nothing)
    assert wrap_angle_one(angle) == float(wrap_angle(angle))


@pytest.mark.parametrize(
    "angle",
    [math.pi, -math.pi, 3 * math.pi, -3 * math.pi, math.nextafter(-math.pi, -4.0), 0.0, -0.0],
)
def test_compiled_wrap_on_the_boundaries(angle: float) -> None:
    assert wrap_angle_one(angle) == float(wrap_angle(angle))
    assert -math.pi <= wrap_angle_one(angle) < math.pi


def _ulp_tolerance(x: float, chord: float) -> float:
    """x + chord * cos(.): one ulp of libm vs NumPy's vectorised cos (or sin) in the
    product, then one rounding of the sum: 2 ulp of |x| + |chord|."""
    return 2.0 * math.ulp(abs(x) + abs(chord))


@settings(max_examples=300, deadline=None)
@given(
    st.floats(-100.0, 100.0),
    st.floats(-100.0, 100.0),
    st.floats(-math.pi, math.pi, exclude_max=True),
    st.floats(-2.0, 2.0) | st.floats(-2e-4, 2e-4),
    st.floats(-2.0, 2.0) | st.floats(-2e-4, 2e-4),
)
def test_compiled_diff_drive_step_equals_numpy(
    x: float, y: float, theta: float, dphi_r: float, dphi_l: float
) -> None:
    got = diff_drive_step_one(x, y, theta, dphi_r, dphi_l, 0.045, 0.2)
    ref = diff_drive_step(np.array([[x, y, theta]]), np.array([[dphi_r, dphi_l]]), TABLE2)[0]
    # heading: no sin/cos on the way, bit for bit
    assert got[2] == ref[2]
    # x, y: the same operations, but NumPy's vectorised sin/cos may differ from the C
    # library's in the last bit on some CPUs (on the x86-64 this was written on, 200,000
    # random steps agreed bit for bit); the bound is 2 ulp (see _ulp_tolerance)
    chord = abs(0.045 * (dphi_r + dphi_l) / 2.0) * 1.01
    assert abs(got[0] - ref[0]) <= _ulp_tolerance(x, chord)
    assert abs(got[1] - ref[1]) <= _ulp_tolerance(y, chord)


def test_compiled_arc_step_takes_the_taylor_branch_as_numpy_does() -> None:
    # |dtheta / 2| just below and above 1e-4: both branches, a straight line, a spin
    for dtheta in (0.0, 1.9999e-4, -1.9999e-4, 2.0001e-4, -2.0001e-4, 1.0):
        for ds in (0.0, 0.3, -0.2):
            got = arc_step_one(1.0, -2.0, 0.5, ds, dtheta)
            ref = unicycle_step(np.array([[1.0, -2.0, 0.5]]), ds, dtheta, 1.0)[0]
            assert got[2] == ref[2]
            np.testing.assert_allclose(got[:2], ref[:2], rtol=0, atol=_ulp_tolerance(2.0, 0.3))
