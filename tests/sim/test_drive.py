"""The wheel stack (sim.drive) against the DC motor's and the robot's analytic solutions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.pid import PidParams
from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams
from firefleet.models.kinematics import RobotGeometry, wrap_angle
from firefleet.models.motor import MotorParams
from firefleet.sim.drive import (
    DriveStack,
    DriveState,
    discretise_drive,
    drive_init,
    drive_step,
    speed_control,
)

DT = 0.01
GEO = RobotGeometry()  # Table 2: r = 0.045 m, L = 0.2 m
MOTOR = MotorParams()  # Table 2
IDEAL = EncoderParams(counts_per_rev=0)
ENC_2048 = EncoderParams(counts_per_rev=2048)


def _stack(
    encoder: EncoderParams = IDEAL,
    *,
    wheel_radius_scale: tuple[float, float] | None = None,
    axle_scale: float = 1.0,
    slip_variance_m: float = 0.0,
) -> DriveStack:
    return discretise_drive(
        GEO,
        MOTOR,
        PidParams(),
        encoder,
        DT,
        wheel_radius_scale=wheel_radius_scale,
        axle_scale=axle_scale,
        slip_variance_m=slip_variance_m,
    )


def _step_response(voltage_v: float, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Speed w(t) [rad/s] and angle phi(t) [rad] of the motor from rest, a voltage step.

    By hand, not through the matrix exponential: the speed obeys
    ``w'' + (R/L + B/J) w' + (R B + Ke Kt)/(L J) w = Kt V / (L J)`` with w(0) = w'(0) = 0,
    so ``w = w_ss + a1 exp(l1 t) + a2 exp(l2 t)`` with the roots l1, l2 of the
    characteristic polynomial, ``a1 + a2 = -w_ss`` and ``l1 a1 + l2 a2 = 0``; phi is its
    integral.
    """
    R, L, J = MOTOR.resistance_ohm, MOTOR.inductance_h, MOTOR.inertia_kg_m2
    B, Ke, Kt = MOTOR.damping_n_m_s, MOTOR.back_emf_v_s, MOTOR.torque_n_m_a
    p, q = R / L + B / J, (R * B + Ke * Kt) / (L * J)
    disc = math.sqrt(p * p / 4.0 - q)  # real: the Table 2 motor is overdamped
    l1, l2 = -p / 2.0 + disc, -p / 2.0 - disc
    w_ss = Kt * voltage_v / (R * B + Ke * Kt)
    a1 = w_ss * l2 / (l1 - l2)
    a2 = -w_ss * l1 / (l1 - l2)
    w = w_ss + a1 * np.exp(l1 * t_s) + a2 * np.exp(l2 * t_s)
    phi = w_ss * t_s + a1 * np.expm1(l1 * t_s) / l1 + a2 * np.expm1(l2 * t_s) / l2
    return w, phi


def _run(
    stack: DriveStack,
    state: DriveState,
    voltage_v: np.ndarray,
    steps: int,
    *,
    load_torque_n_m: float = 0.0,
    rng: np.random.Generator | None = None,
) -> list[DriveState]:
    """The states after 0, 1, ..., steps periods with the voltages (and load) held."""
    states = [state]
    for _ in range(steps):
        states.append(
            drive_step(states[-1], voltage_v, stack, load_torque_n_m=load_torque_n_m, rng=rng)
        )
    return states


def test_constant_voltage_reaches_the_dc_motors_steady_state() -> None:
    stack = _stack()
    v, tau = 6.0, 0.3  # [V], [N m]
    steps = 600  # 6 s: the slow pole (-5.5 rad/s) leaves exp(-33) ~ 5e-15 of the transient
    states = _run(
        stack, drive_init(np.zeros((1, 3)), np.zeros((1, 2)), stack), np.full((1, 2), v), steps
    )
    w = np.array([s.speed_rad_s[0, 0] for s in states])
    # the zero-order hold of a held voltage is exact: every sample is on the analytic
    # curve, to rounding (600 steps of ~1e-16 relative error each)
    w_exact, _ = _step_response(v, np.arange(steps + 1) * DT)
    np.testing.assert_allclose(w, w_exact, rtol=0, atol=1e-9 * w_exact[-1])
    R, B, Ke, Kt = (
        MOTOR.resistance_ohm,
        MOTOR.damping_n_m_s,
        MOTOR.back_emf_v_s,
        MOTOR.torque_n_m_a,
    )
    w_ss = Kt * v / (R * B + Ke * Kt)  # di/dt = dw/dt = 0 in the two equations
    last = states[-1]
    np.testing.assert_allclose(last.speed_rad_s, w_ss, rtol=1e-9)
    np.testing.assert_allclose(last.current_a, B * w_ss / Kt, rtol=1e-9)
    # the ideal encoder's speed is the mean over its 2-period window: w_ss at rest
    np.testing.assert_allclose(last.measured_rad_s, w_ss, rtol=1e-9)
    # with a load torque: J dw/dt = Kt i - B w - tau = 0 and V = R i + Ke w
    loaded = _run(stack, last, np.full((1, 2), v), steps, load_torque_n_m=tau)[-1]
    w_load = (Kt * v - R * tau) / (R * B + Ke * Kt)
    np.testing.assert_allclose(loaded.speed_rad_s, w_load, rtol=1e-9)
    np.testing.assert_allclose(loaded.current_a, (v - Ke * w_load) / R, rtol=1e-9)


def test_straight_drive_dead_reckons_the_analytic_distance_within_one_count() -> None:
    stack = _stack(ENC_2048)
    v, steps = 6.0, 300
    phase = np.full((1, 2), 0.3 * stack.count_angle_rad)  # same phase: both wheels count alike
    start = drive_init(np.zeros((1, 3)), phase, stack, odometry=True)
    states = _run(stack, start, np.full((1, 2), v), steps)
    _, phi = _step_response(v, np.arange(steps + 1) * DT)
    distance = GEO.wheel_radius_m * phi
    pose = np.array([s.pose[0] for s in states])
    odo = np.array([s.odometry[0] for s in states if s.odometry is not None])
    # the true pose: r phi along x, exactly (the angle turned per step is exact)
    np.testing.assert_allclose(pose[:, 0], distance, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(pose[:, 1:], 0.0)
    # dead reckoning from counts floor(2048 angle / 2 pi): the count difference is
    # within one count of 2048 phi / 2 pi, so the distance is within one count's travel
    one_count_m = GEO.wheel_radius_m * stack.count_angle_rad  # 0.14 mm
    assert np.abs(odo[:, 0] - distance).max() < one_count_m
    np.testing.assert_array_equal(odo[:, 1:], 0.0)
    assert distance[-1] > 0.8  # a real drive: some 5,800 counts


def test_turn_in_place_gives_the_analytic_heading() -> None:
    stack = _stack()
    v, steps = 6.0, 200
    volts = np.array([[v, -v]])  # right forward, left backward
    states = _run(stack, drive_init(np.zeros((1, 3)), np.zeros((1, 2)), stack), volts, steps)
    _, phi = _step_response(v, np.arange(steps + 1) * DT)
    # theta = integral of (v_R - v_L) / L with v = r w: r (phi_R - phi_L) / L = 2 r phi / L
    heading = 2.0 * GEO.wheel_radius_m * phi / GEO.axle_length_m  # 5.9 rad at 2 s
    pose = np.array([s.pose[0] for s in states])
    np.testing.assert_allclose(wrap_angle(pose[:, 2] - heading), 0.0, atol=1e-9 * heading[-1])
    # the two wheels' angles are exact negatives (a linear motor): no translation at all
    np.testing.assert_array_equal(pose[:, :2], 0.0)


def test_true_geometry_moves_the_robot_and_the_nominal_one_the_odometry() -> None:
    v, steps = 6.0, 150
    _, phi = _step_response(v, np.arange(steps + 1) * DT)
    r, L = GEO.wheel_radius_m, GEO.axle_length_m
    # wheels 2 % larger than nominal: the robot goes 2 % further than its odometry says
    big = _stack(wheel_radius_scale=(1.02, 1.02))
    start = drive_init(np.zeros((1, 3)), np.zeros((1, 2)), big, odometry=True)
    last = _run(big, start, np.full((1, 2), v), steps)[-1]
    assert last.odometry is not None
    np.testing.assert_allclose(last.pose[0, 0], 1.02 * r * phi[-1], rtol=1e-9)
    np.testing.assert_allclose(last.odometry[0, 0], r * phi[-1], rtol=1e-9)
    # an axle 25 % longer than nominal: the robot turns 1 / 1.25 of what its odometry says
    wide = _stack(axle_scale=1.25)
    start = drive_init(np.zeros((1, 3)), np.zeros((1, 2)), wide, odometry=True)
    last = _run(wide, start, np.array([[v, -v]]), steps)[-1]
    assert last.odometry is not None
    turn = 2.0 * r * phi[-1] / L  # 4.2 rad at 1.5 s
    np.testing.assert_allclose(last.pose[0, 2], wrap_angle(turn / 1.25), rtol=1e-9)
    np.testing.assert_allclose(last.odometry[0, 2], wrap_angle(turn), rtol=1e-9)


def test_a_team_equals_its_robots_run_one_by_one() -> None:
    # everything in the stack is per robot: a batch of 4 robots with different starts,
    # encoder phases, references and loads must equal four one-robot runs, bit for bit
    stack = _stack(ENC_2048, wheel_radius_scale=(1.01, 0.99), axle_scale=1.05)
    rng = np.random.default_rng(3)
    n = 4
    poses = np.column_stack([rng.uniform(-5, 5, (n, 2)), rng.uniform(-3, 3, n)])
    phase = rng.uniform(0.0, stack.count_angle_rad, (n, 2))
    refs = rng.uniform(-8.0, 8.0, (n, 2))  # [rad/s]
    loads = rng.uniform(0.0, 0.4, (n, 2))  # [N m]

    def run(sel: slice) -> list[tuple[np.ndarray, ...]]:
        state = drive_init(poses[sel], phase[sel], stack, odometry=True)
        out: list[tuple[np.ndarray, ...]] = []
        for _ in range(150):
            state, volts = speed_control(state, refs[sel], stack)
            state = drive_step(state, volts, stack, load_torque_n_m=loads[sel])
            assert state.odometry is not None
            out.append(
                (
                    state.pose,
                    state.odometry,
                    state.current_a,
                    state.speed_rad_s,
                    state.measured_rad_s,
                    volts,
                )
            )
        return out

    team = run(slice(None))
    for i in range(n):
        for got, alone in zip(team, run(slice(i, i + 1)), strict=True):
            for a, b in zip(got, alone, strict=True):
                np.testing.assert_array_equal(a[i : i + 1], b)
    # and the PIDs reach their references through the stack 1.5 s after the step (they
    # settle in < 0.5 s): within the 2 % band plus one quantum of the encoder's measured
    # speed (0.15 rad/s at 2048 counts over 20 ms), which the loop chases
    np.testing.assert_allclose(team[-1][3], refs, rtol=0.02, atol=0.15)


def test_wheel_slip_spreads_the_heading_as_its_variance_says() -> None:
    # straight drive, equal wheels: the heading is only the slip, sum (e_R - e_L) / L,
    # e ~ N(0, k^2 travel) per wheel and step, so theta ~ N(0, 2 k^2 d / L^2) at distance d
    k2 = 1e-5  # [m]
    stack = _stack(slip_variance_m=k2)
    n, steps = 4000, 100
    states = _run(
        stack,
        drive_init(np.zeros((n, 3)), np.zeros((n, 2)), stack),
        np.full((n, 2), 6.0),
        steps,
        rng=np.random.default_rng(11),
    )
    _, phi = _step_response(6.0, np.arange(steps + 1) * DT)
    d = GEO.wheel_radius_m * phi[-1]  # each wheel's travel [m] (no radius error)
    var = 2.0 * k2 * d / GEO.axle_length_m**2
    theta = states[-1].pose[:, 2]
    # 4,000 samples: the sample variance's relative standard error is sqrt(2 / n) = 2.2 %,
    # the mean's is sqrt(var / n); 15 % and 5 standard errors are about 7 and 5 sigma
    assert np.var(theta) == pytest.approx(var, rel=0.15)
    assert abs(theta.mean()) < 5.0 * math.sqrt(var / n)


def test_bad_stack_and_state_are_named() -> None:
    with pytest.raises(InputError, match="wheel_radius_scale"):
        _stack(wheel_radius_scale=(1.0, 0.0))
    with pytest.raises(InputError, match="axle_scale"):
        _stack(axle_scale=-1.0)
    with pytest.raises(InputError, match="slip_variance_m"):
        _stack(slip_variance_m=-1e-6)
    stack = _stack()
    with pytest.raises(InputError, match="pose"):
        drive_init(np.zeros((2, 2)), np.zeros((2, 2)), stack)
    with pytest.raises(InputError, match="encoder_phase_rad"):
        drive_init(np.zeros((2, 3)), np.zeros((1, 2)), stack)
