"""The fused motor-team kernel: the wheel stack under a step and a load step.

See :mod:`firefleet.sim._kernels`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numba
import numpy as np

from firefleet._typing import FloatArray, IntArray
from firefleet.control.pid import pid_step_one
from firefleet.models.encoder import encoder_init, encoder_step_one
from firefleet.models.kinematics import diff_drive_step_one
from firefleet.models.motor import motor_step_one
from firefleet.sim._kernels._parallel import PARALLEL_MIN_ROBOTS
from firefleet.sim.drive import DriveStack

MOTOR_RECORD = ("speed", "measured", "ref", "current", "voltage", "load")
"""Wheel quantities :func:`motor_team_chunk` records, in the last axis of ``wheel_rec``:
true speed [rad/s], measured speed [rad/s], reference [rad/s] (NaN in open loop),
current [A], voltage [V], load torque [N m]."""


@numba.njit(cache=True)
def _motor_team_robot(
    i: int,
    k0: int,
    k1: int,
    n_steps: int,
    dt: float,
    command: FloatArray,
    pose: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    encoder: FloatArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    wheel_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Robot ``i`` of :func:`motor_team_chunk` through its steps ``k0 <= k < k1``."""
    open_loop = command[0] > 0.0
    level_on, level_start = command[1], command[2] - 1e-9
    load_on, load_start = command[3], command[4] - 1e-9
    coef = (
        motor[0],
        motor[1],
        motor[2],
        motor[3],
        motor[4],
        motor[5],
        motor[6],
        motor[7],
        motor[8],
        motor[9],
        motor[10],
        motor[11],
    )
    gains = (pid[0], pid[1], pid[2], pid[3], pid[4], pid[5], pid[6])
    scale_r, scale_l, radius, axle = geom[0], geom[1], geom[2], geom[3]
    per_rad, per_count = encoder[0], encoder[1]
    window = history.shape[2] - 1
    px, py, pth = pose[i, 0], pose[i, 1], pose[i, 2]
    cur_r, spd_r, ang_r, meas_r = wheel[i, 0, 0], wheel[i, 0, 1], wheel[i, 0, 2], wheel[i, 0, 3]
    int_r, der_r, last_r = wheel[i, 0, 4], wheel[i, 0, 5], wheel[i, 0, 6]
    cur_l, spd_l, ang_l, meas_l = wheel[i, 1, 0], wheel[i, 1, 1], wheel[i, 1, 2], wheel[i, 1, 3]
    int_l, der_l, last_l = wheel[i, 1, 4], wheel[i, 1, 5], wheel[i, 1, 6]
    for k in range(k0, k1):
        t = k * dt
        tau = load_on if t >= load_start else 0.0
        level = level_on if t >= level_start else 0.0
        if open_loop:
            ref = math.nan
            volt_r = level
            volt_l = level
        else:
            ref = level
            int_r, der_r, volt_r = pid_step_one(int_r, der_r, last_r, ref, meas_r, gains, dt)
            last_r = meas_r
            int_l, der_l, volt_l = pid_step_one(int_l, der_l, last_l, ref, meas_l, gains, dt)
            last_l = meas_l
        row = rec_index[k]
        if row >= 0:
            pose_rec[row, i, 0] = px
            pose_rec[row, i, 1] = py
            pose_rec[row, i, 2] = pth
            wheel_rec[row, i, 0, 0] = spd_r
            wheel_rec[row, i, 0, 1] = meas_r
            wheel_rec[row, i, 0, 2] = ref
            wheel_rec[row, i, 0, 3] = cur_r
            wheel_rec[row, i, 0, 4] = volt_r
            wheel_rec[row, i, 0, 5] = tau
            wheel_rec[row, i, 1, 0] = spd_l
            wheel_rec[row, i, 1, 1] = meas_l
            wheel_rec[row, i, 1, 2] = ref
            wheel_rec[row, i, 1, 3] = cur_l
            wheel_rec[row, i, 1, 4] = volt_l
            wheel_rec[row, i, 1, 5] = tau
        if k == n_steps:
            continue
        cur_r, spd_r, dphi_r = motor_step_one(cur_r, spd_r, volt_r, tau, coef)
        cur_l, spd_l, dphi_l = motor_step_one(cur_l, spd_l, volt_l, tau, coef)
        ang_r, count_r, meas_r = encoder_step_one(
            ang_r, dphi_r, history[i, 0, 1], per_rad, per_count
        )
        ang_l, count_l, meas_l = encoder_step_one(
            ang_l, dphi_l, history[i, 1, 1], per_rad, per_count
        )
        for h in range(window):
            history[i, 0, h] = history[i, 0, h + 1]
            history[i, 1, h] = history[i, 1, h + 1]
        history[i, 0, window] = count_r
        history[i, 1, window] = count_l
        px, py, pth = diff_drive_step_one(
            px, py, pth, dphi_r * scale_r, dphi_l * scale_l, radius, axle
        )
    pose[i, 0], pose[i, 1], pose[i, 2] = px, py, pth
    wheel[i, 0, 0], wheel[i, 0, 1], wheel[i, 0, 2], wheel[i, 0, 3] = cur_r, spd_r, ang_r, meas_r
    wheel[i, 0, 4], wheel[i, 0, 5], wheel[i, 0, 6] = int_r, der_r, last_r
    wheel[i, 1, 0], wheel[i, 1, 1], wheel[i, 1, 2], wheel[i, 1, 3] = cur_l, spd_l, ang_l, meas_l
    wheel[i, 1, 4], wheel[i, 1, 5], wheel[i, 1, 6] = int_l, der_l, last_l


@numba.njit(cache=True)
def motor_team_chunk(
    k0: int,
    k1: int,
    n_steps: int,
    dt: float,
    command: FloatArray,
    pose: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    encoder: FloatArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    wheel_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Steps ``k0 <= k < k1`` of a team's wheel stacks under step commands, in place.

    Each step, as :func:`firefleet.sim.drive.speed_control` then (after recording)
    :func:`firefleet.sim.drive.drive_step` without slip: PID (closed loop) or the voltage
    itself (open loop), motors, true pose (true wheel radii and axle), encoders.

    Parameters
    ----------
    k0, k1 : int
        The range of steps; step ``n_steps`` only records.
    n_steps : int
        Steps of the whole run.
    dt : float
        Control period [s].
    command : ndarray, shape (5,)
        Open loop (1.0: the level is a voltage) or closed loop (0.0: a wheel-speed
        reference); the level [V or rad/s] and its start [s]; the load torque [N m] and
        its start [s]. Each is on from ``k dt >= start - 1e-9``.
    pose : ndarray, shape (N, 3)
        True poses (in/out).
    wheel : ndarray, shape (N, 2, 7)
        Per wheel: current [A], speed [rad/s], angle [rad], measured speed [rad/s], PID
        integral [V], filtered derivative [V], last measurement [rad/s] (in/out).
    history : ndarray, shape (N, 2, window + 1)
        Each encoder's last counts, oldest first (in/out).
    motor : ndarray, shape (12,)
        :attr:`~firefleet.models.motor.DiscreteMotor.coefficients`.
    pid : ndarray, shape (7,)
        :attr:`~firefleet.control.pid.PidParams.gains`.
    geom : ndarray, shape (4,)
        True wheel radius over nominal, right and left; wheel radius [m]; true axle [m].
    encoder : ndarray, shape (2,)
        :attr:`~firefleet.models.encoder.EncoderParams.counts_per_rad` and
        :meth:`~firefleet.models.encoder.EncoderParams.speed_per_count`.
    rec_index : ndarray of int, shape (n_steps + 1,)
        Row of each step in the records, -1 where not recorded.
    pose_rec : ndarray, shape (T, N, 3)
    wheel_rec : ndarray, shape (T, N, 2, 6)
        :data:`MOTOR_RECORD`.
    """
    for i in range(pose.shape[0]):  # robots are independent
        _motor_team_robot(
            i,
            k0,
            k1,
            n_steps,
            dt,
            command,
            pose,
            wheel,
            history,
            motor,
            pid,
            geom,
            encoder,
            rec_index,
            pose_rec,
            wheel_rec,
        )


@numba.njit(cache=True, parallel=True)
def motor_team_chunk_parallel(
    k0: int,
    k1: int,
    n_steps: int,
    dt: float,
    command: FloatArray,
    pose: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    encoder: FloatArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    wheel_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """:func:`motor_team_chunk` with the robots spread over every core (the same result
    bit for bit)."""
    for i in numba.prange(pose.shape[0]):  # robots are independent
        _motor_team_robot(
            i,
            k0,
            k1,
            n_steps,
            dt,
            command,
            pose,
            wheel,
            history,
            motor,
            pid,
            geom,
            encoder,
            rec_index,
            pose_rec,
            wheel_rec,
        )


def run_motor_team(
    stack: DriveStack,
    pose: FloatArray,
    encoder_phase_rad: FloatArray,
    *,
    open_loop: bool,
    level: float,
    level_start_s: float,
    load_torque_n_m: float,
    load_start_s: float,
    n_steps: int,
    rec_steps: IntArray,
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, FloatArray]:
    """Run a team's wheel stacks under a step command and a load step (compiled).

    The same run as :func:`firefleet.sim.drive.drive_init`, then each step
    :func:`~firefleet.sim.drive.speed_control` (closed loop) and
    :func:`~firefleet.sim.drive.drive_step` (no slip), recorded before the plant step.

    Parameters
    ----------
    stack : DriveStack
        The wheel stack (its ``slip_variance_m`` is not used: no slip).
    pose : ndarray, shape (N, 3)
        Start poses x [m], y [m], theta [rad].
    encoder_phase_rad : ndarray, shape (N, 2)
        Each wheel's angle from its encoder's zero [rad].
    open_loop : bool
        True: ``level`` is the voltage [V] of every motor; False: the wheel-speed
        reference [rad/s] of every PID.
    level, level_start_s : float
        The step's value and start [s].
    load_torque_n_m, load_start_s : float
        The load step on every motor [N m] and its start [s].
    n_steps : int
        Steps of the run (``n_steps + 1`` states, the last only recorded).
    rec_steps : ndarray of int
        Steps to record, ascending.
    progress : callable, optional
        ``progress(done, total)`` about a hundred times; without it the run is one call.

    Returns
    -------
    dict of str to ndarray
        ``"pose"`` (T, N, 3), and each of :data:`MOTOR_RECORD` (T, N, 2).
    """
    n = pose.shape[0]
    enc = stack.encoder
    scale = stack.wheel_radius_scale or (1.0, 1.0)
    wheel = np.zeros((n, 2, 7))
    wheel[:, :, 2] = encoder_phase_rad
    history = np.ascontiguousarray(np.moveaxis(encoder_init(encoder_phase_rad, enc).history, 0, -1))
    command = np.array(
        [1.0 if open_loop else 0.0, level, level_start_s, load_torque_n_m, load_start_s]
    )
    geom = np.array(
        [
            scale[0],
            scale[1],
            stack.true_geometry.wheel_radius_m,
            stack.true_geometry.axle_length_m,
        ]
    )
    encoder = np.array([enc.counts_per_rad, enc.speed_per_count(stack.dt_s)])
    n_rec = rec_steps.size
    rec_index = np.full(n_steps + 1, -1, dtype=np.int64)
    rec_index[rec_steps] = np.arange(n_rec)
    pose_rec = np.empty((n_rec, n, 3))
    wheel_rec = np.empty((n_rec, n, 2, len(MOTOR_RECORD)))
    state = np.array(pose, dtype=np.float64)
    kernel = motor_team_chunk_parallel if n >= PARALLEL_MIN_ROBOTS else motor_team_chunk
    chunks = 100 if progress is not None else 1
    bounds = np.unique(np.linspace(0, n_steps + 1, chunks + 1).astype(np.int64))
    for k0, k1 in itertools.pairwise(bounds):
        kernel(
            int(k0),
            int(k1),
            n_steps,
            stack.dt_s,
            command,
            state,
            wheel,
            history,
            np.array(stack.motor.coefficients),
            np.array(stack.pid.gains),
            geom,
            encoder,
            rec_index,
            pose_rec,
            wheel_rec,
        )
        if progress is not None:
            progress(min(int(k1), n_steps), n_steps)
    out = {"pose": pose_rec}
    for c, name in enumerate(MOTOR_RECORD):
        out[name] = wheel_rec[..., c].copy()
    return out
