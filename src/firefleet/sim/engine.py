"""The simulator: a fixed-step loop over the whole team.

Each tick, for N robots at once (batch-first arrays, no per-robot Python objects)::

    command (voltage, or wheel-speed reference)        (N, 2)
      -> control.pid       voltages from the encoder's measured speeds   (N, 2)
      -> models.motor      exact zero-order hold: currents, speeds, angles turned
      -> models.kinematics poses                                        (N, 3)
      -> models.encoder    counts and measured speeds                   (N, 2)

(the wheel stack of :mod:`firefleet.sim.drive`, shared with the formation runner and the
SLAM drive of :mod:`firefleet.sim.world`).

Randomness (the encoders' unknown initial phase) comes from one
``numpy.random.Generator`` seeded with the scenario's ``seed``: same seed, same arrays,
bit for bit.

Two backends run the same arithmetic in the same order. ``"array"`` steps the whole team
with NumPy (:mod:`firefleet.sim.drive`, on the models' public step functions).
``"scalar"`` steps each wheel with Python floats: for a handful of robots NumPy's
per-call overhead (about 1 us, some 100 calls a step) dominates, and plain floats run
the 10 s single-robot loop about 15 times faster.
``"auto"`` takes the scalar one up to ``SCALAR_MAX_ROBOTS`` robots. The two agree to
rounding (tests/sim/test_engine.py), so a result does not depend on the team size.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.models.motor import discretise_motor
from firefleet.scenarios.schema import (
    Formation,
    PathFollowing,
    Scenario,
    VoltageStep,
    WheelSpeedStep,
)
from firefleet.sim.cooperative import simulate_path_following
from firefleet.sim.drive import (
    discretise_drive,
    drive_init,
    drive_step,
    encoder_phase,
    speed_control,
)
from firefleet.sim.formation import simulate_formation
from firefleet.sim.result import SimResult

__all__ = ["SCALAR_MAX_ROBOTS", "ProgressCallback", "simulate"]

SCALAR_MAX_ROBOTS = 8
"""Largest team the ``"auto"`` backend steps with Python floats (measured crossover ~16)."""

ProgressCallback = Callable[[int, int], None]
"""Called as ``progress(steps_done, steps_total)`` about a hundred times a run."""


def simulate(
    scenario: Scenario,
    *,
    seed: int | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    backend: Literal["auto", "array", "scalar"] = "auto",
) -> SimResult:
    """Run a scenario.

    Parameters
    ----------
    scenario : Scenario
        The experiment.
    seed : int, optional
        Overrides ``scenario.seed``.
    record_every : int
        Record every k-th step (and the last); 1 records them all.
    progress : callable, optional
        ``progress(done, total)``, for a progress bar.
    backend : {"auto", "array", "scalar"}
        How to step the team (same arithmetic either way, see the module notes).

    Returns
    -------
    SimResult
        The recorded run; its ``scenario`` carries the seed used.
    """
    if seed is not None:
        if seed < 0:
            raise InputError(f"seed must be >= 0, got {seed}")
        scenario = dataclasses.replace(scenario, seed=seed)
    if record_every < 1:
        raise InputError(f"record_every must be >= 1, got {record_every}")
    if backend not in ("auto", "array", "scalar"):
        raise InputError(f"backend must be 'auto', 'array' or 'scalar', got {backend!r}")
    n_steps = scenario.n_steps
    rec_steps = np.unique(np.r_[np.arange(0, n_steps + 1, record_every), n_steps])
    cmd = scenario.command
    if isinstance(cmd, VoltageStep | WheelSpeedStep):
        return _simulate_motors(scenario, rec_steps, progress, backend)
    if isinstance(cmd, PathFollowing):
        return simulate_path_following(scenario, rec_steps, progress)
    if isinstance(cmd, Formation):
        return simulate_formation(scenario, rec_steps, progress)
    raise InputError(f"no simulator for a {cmd.kind} scenario")


def _simulate_motors(
    scenario: Scenario,
    rec_steps: NDArray[np.int64],
    progress: ProgressCallback | None,
    backend: Literal["auto", "array", "scalar"],
) -> SimResult:
    """A voltage-step or wheel-speed-step run: every wheel gets the same command."""
    assert isinstance(scenario.command, VoltageStep | WheelSpeedStep)
    rng = np.random.default_rng(scenario.seed)
    dt = scenario.dt_s
    n_steps = scenario.n_steps
    n = scenario.n_robots
    enc_params = scenario.encoder
    phase = encoder_phase(enc_params, n, rng)
    if backend == "scalar" or (backend == "auto" and n <= SCALAR_MAX_ROBOTS):
        return _simulate_scalar(scenario, phase, rec_steps, progress)

    stack = discretise_drive(scenario.robot, scenario.motor, scenario.speed_pid, enc_params, dt)
    cmd = scenario.command
    assert isinstance(cmd, VoltageStep | WheelSpeedStep)  # the dispatch in simulate()
    open_loop = isinstance(cmd, VoltageStep)
    step_value = cmd.voltage_v if isinstance(cmd, VoltageStep) else cmd.speed_rad_s
    drive = drive_init(scenario.initial_poses, phase, stack)

    n_rec = rec_steps.size
    t_rec = np.asarray(rec_steps * dt, dtype=np.float64)
    rec = {
        name: np.empty((n_rec, n, 2))
        for name in ("speed", "measured", "ref", "current", "voltage", "load")
    }
    pose_rec = np.empty((n_rec, n, 3))
    row = 0
    report_every = max(1, n_steps // 100)

    for k in range(n_steps + 1):
        t = k * dt
        load = np.full(
            (n, 2), scenario.load.torque_n_m if t >= scenario.load.start_s - 1e-9 else 0.0
        )
        level = step_value if t >= cmd.start_s - 1e-9 else 0.0
        if open_loop:
            ref = np.full((n, 2), np.nan)
            voltage = np.full((n, 2), level)
        else:
            ref = np.full((n, 2), level)
            drive, voltage = speed_control(drive, ref, stack)
        if row < n_rec and rec_steps[row] == k:
            pose_rec[row] = drive.pose
            rec["speed"][row] = drive.speed_rad_s
            rec["measured"][row] = drive.measured_rad_s
            rec["ref"][row] = ref
            rec["current"][row] = drive.current_a
            rec["voltage"][row] = voltage
            rec["load"][row] = load
            row += 1
        if k == n_steps:
            break
        drive = drive_step(drive, voltage, stack, load_torque_n_m=load)
        if progress is not None and (k + 1) % report_every == 0:
            progress(k + 1, n_steps)
    if progress is not None:
        progress(n_steps, n_steps)

    return SimResult(
        scenario=scenario,
        t=t_rec,
        pose=pose_rec,
        wheel_speed_rad_s=rec["speed"],
        wheel_speed_measured_rad_s=rec["measured"],
        wheel_speed_ref_rad_s=rec["ref"],
        current_a=rec["current"],
        voltage_v=rec["voltage"],
        load_torque_n_m=rec["load"],
    )


def _simulate_scalar(
    scenario: Scenario,
    phase: NDArray[np.float64],
    rec_steps: NDArray[np.int64],
    progress: ProgressCallback | None,
) -> SimResult:
    """The ``"scalar"`` backend: :func:`simulate` with Python floats, wheel by wheel.

    Mirrors, operation for operation, ``pid_step``, ``motor_step``, ``diff_drive_step``
    and ``encoder_step`` as the array backend calls them (through
    :func:`firefleet.sim.drive.speed_control` and :func:`firefleet.sim.drive.drive_step`).
    """
    assert isinstance(scenario.command, VoltageStep | WheelSpeedStep)
    dt = scenario.dt_s
    n_steps = scenario.n_steps
    n = scenario.n_robots
    disc = discretise_motor(scenario.motor, dt)
    a00, a01, a10, a11 = (float(v) for v in disc.ad.ravel())
    b00, b01, b10, b11 = (float(v) for v in disc.bd.ravel())
    c0, c1 = (float(v) for v in disc.c_ad)
    d0, d1 = (float(v) for v in disc.c_bd)
    enc = scenario.encoder
    cpr, window = enc.counts_per_rev, enc.window_steps
    per_rad = cpr / (2.0 * np.pi) if cpr else 0.0
    speed_scale = (2.0 * np.pi / cpr if cpr else 1.0) / (window * dt)
    g = scenario.speed_pid
    kp, ki, kd, tf, b = g.kp, g.ki, g.kd, g.derivative_filter_s, g.setpoint_weight
    tt, lim = g.tracking_time_s, g.output_limit
    radius, axle = scenario.robot.wheel_radius_m, scenario.robot.axle_length_m
    cmd = scenario.command
    assert isinstance(cmd, VoltageStep | WheelSpeedStep)  # the dispatch in simulate()
    open_loop = isinstance(cmd, VoltageStep)
    step_value = cmd.voltage_v if isinstance(cmd, VoltageStep) else cmd.speed_rad_s
    load_value, load_start = scenario.load.torque_n_m, scenario.load.start_s
    floor, sin, cos, pi, two_pi = math.floor, math.sin, math.cos, math.pi, 2.0 * math.pi

    wheels = range(2 * n)
    angle = [float(a) for a in phase.ravel()]
    history = [[float(floor(a * per_rad)) if cpr else a] * (window + 1) for a in angle]
    current = [0.0] * (2 * n)
    speed = [0.0] * (2 * n)
    measured = [0.0] * (2 * n)
    integral = [0.0] * (2 * n)
    deriv = [0.0] * (2 * n)
    last_y = [0.0] * (2 * n)
    voltage = [0.0] * (2 * n)
    ref = [math.nan] * (2 * n)
    pose = [float(v) for v in scenario.initial_poses.ravel()]

    n_rec = rec_steps.size
    rec = np.empty((n_rec, 6, 2 * n))  # speed, measured, ref, current, voltage, load
    pose_rec = np.empty((n_rec, 3 * n))
    record = set(rec_steps.tolist())
    row = 0
    report_every = max(1, n_steps // 100)
    for k in range(n_steps + 1):
        t = k * dt
        load = load_value if t >= load_start - 1e-9 else 0.0
        level = step_value if t >= cmd.start_s - 1e-9 else 0.0
        for j in wheels:
            if open_loop:
                voltage[j] = level
            else:
                y = measured[j]
                ref[j] = level
                d = (tf * deriv[j] - kd * (y - last_y[j])) / (tf + dt)
                u = kp * (b * level - y) + integral[j] + d
                u_sat = -lim if u < -lim else (lim if u > lim else u)
                integral[j] = integral[j] + dt * (ki * (level - y) + (u_sat - u) / tt)
                deriv[j] = d
                last_y[j] = y
                voltage[j] = u_sat
        if k in record:
            rec[row] = (speed, measured, ref, current, voltage, [load] * (2 * n))
            pose_rec[row] = pose
            row += 1
        if k == n_steps:
            break
        dphi = [0.0] * (2 * n)
        for j in wheels:
            i0, w0, v = current[j], speed[j], voltage[j]
            current[j] = a00 * i0 + a01 * w0 + b00 * v + b01 * load
            speed[j] = a10 * i0 + a11 * w0 + b10 * v + b11 * load
            dphi[j] = c0 * i0 + c1 * w0 + d0 * v + d1 * load
            angle[j] = angle[j] + dphi[j]
            h = history[j]
            h.pop(0)
            h.append(float(floor(angle[j] * per_rad)) if cpr else angle[j])
            measured[j] = (h[-1] - h[0]) * speed_scale
        for q in range(n):
            x, yy, th = pose[3 * q], pose[3 * q + 1], pose[3 * q + 2]
            dr, dl = dphi[2 * q], dphi[2 * q + 1]
            ds = radius * (dr + dl) / 2.0
            dth = radius * (dr - dl) / axle
            half = 0.5 * dth
            sinc = 1.0 - half * half / 6.0 if abs(half) < 1e-4 else sin(half) / half
            chord = ds * sinc
            wrapped = (th + dth + pi) % two_pi - pi
            pose[3 * q] = x + chord * cos(th + half)
            pose[3 * q + 1] = yy + chord * sin(th + half)
            pose[3 * q + 2] = wrapped - two_pi if wrapped >= pi else wrapped
        if progress is not None and (k + 1) % report_every == 0:
            progress(k + 1, n_steps)
    if progress is not None:
        progress(n_steps, n_steps)
    wheels_rec = rec.reshape(n_rec, 6, n, 2)
    return SimResult(
        scenario=scenario,
        t=np.asarray(rec_steps * dt, dtype=np.float64),
        pose=pose_rec.reshape(n_rec, n, 3),
        wheel_speed_rad_s=wheels_rec[:, 0].copy(),
        wheel_speed_measured_rad_s=wheels_rec[:, 1].copy(),
        wheel_speed_ref_rad_s=wheels_rec[:, 2].copy(),
        current_a=wheels_rec[:, 3].copy(),
        voltage_v=wheels_rec[:, 4].copy(),
        load_torque_n_m=wheels_rec[:, 5].copy(),
    )
