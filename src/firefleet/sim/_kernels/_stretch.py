"""The quiet stretch: the ticks of the staged loop where only the wheels turn, in one call.

Between the events of a staged run (a world step, a sensor scan, a camera frame, a
decision that changes), a tick of :func:`firefleet.sim.loop.run_staged` does the same
few things every time: the odometry integrates the encoders' counts
(:class:`~firefleet.sim.loop.Odometry`), the decision holds its command, the PIDs give
the voltages (:func:`~firefleet.sim.drive.speed_control`), the world's voltage scale and
load torque apply, and the wheel stack steps (:func:`~firefleet.sim.drive.drive_step`,
without slip). :func:`drive_stretch` runs ``m`` such ticks of a team at once from the
compiled scalar steps the other kernels use (:mod:`firefleet.sim._kernels`), and keeps
each tick's true poses for the stages that look at them (a mission's contact test).
tests/sim/test_loop_stretch.py shows a run with it equals the tick-by-tick loop bit for
bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from firefleet._typing import FloatArray
from firefleet.control.pid import PidState, pid_step_one
from firefleet.models.encoder import EncoderState, encoder_step_one
from firefleet.models.kinematics import diff_drive_step_one
from firefleet.models.motor import motor_step_one
from firefleet.sim.drive import DriveStack, DriveState

__all__ = [
    "StretchConstants",
    "drive_stretch",
    "drive_tick",
    "odometry_arc",
    "stretch_constants",
    "stretch_drive",
]


@dataclass(frozen=True, eq=False)
class StretchConstants:
    """The wheel stack's numbers as :func:`drive_stretch` takes them, for a team of N."""

    motor: FloatArray
    pid: FloatArray
    true_geom: FloatArray
    nominal_geom: FloatArray
    encoder: FloatArray
    ones: FloatArray
    no_odom: FloatArray
    no_counts: FloatArray


def stretch_constants(stack: DriveStack, n_robots: int | None = None) -> StretchConstants:
    """:class:`StretchConstants` of ``stack`` (``n_robots``: the team's size; None: 1)."""
    scale = stack.wheel_radius_scale or (1.0, 1.0)
    enc = stack.encoder
    n = 1 if n_robots is None else n_robots
    return StretchConstants(
        motor=np.array(stack.motor.coefficients, dtype=np.float64),
        pid=np.array(stack.pid.gains, dtype=np.float64),
        true_geom=np.array(
            [
                scale[0],
                scale[1],
                stack.true_geometry.wheel_radius_m,
                stack.true_geometry.axle_length_m,
            ]
        ),
        nominal_geom=np.array(
            [stack.geometry.wheel_radius_m, stack.geometry.axle_length_m, stack.count_angle_rad]
        ),
        encoder=np.array([enc.counts_per_rad, enc.speed_per_count(stack.dt_s)]),
        ones=np.ones(n),
        no_odom=np.zeros((n, 3)),
        no_counts=np.zeros((n, 2)),
    )


@numba.njit(cache=True)
def odometry_arc(
    pose: FloatArray, counts_before: FloatArray, counts: FloatArray, nominal_geom: FloatArray
) -> FloatArray:  # pragma: no cover - compiled
    """The odometry's poses (N, 3) moved by the count differences (N, 2): the step of
    :class:`~firefleet.sim.loop.Odometry` (``nominal_geom`` as :func:`drive_stretch`
    takes it), the same arithmetic as each tick of :func:`drive_stretch`."""
    out = np.empty_like(pose)
    n_radius, n_axle, per_count = nominal_geom[0], nominal_geom[1], nominal_geom[2]
    for i in range(pose.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = diff_drive_step_one(
            pose[i, 0],
            pose[i, 1],
            pose[i, 2],
            (counts[i, 0] - counts_before[i, 0]) * per_count,
            (counts[i, 1] - counts_before[i, 1]) * per_count,
            n_radius,
            n_axle,
        )
    return out


@numba.njit(cache=True)
def drive_stretch(
    m: int,
    dt: float,
    reference: FloatArray,
    volt_scale: FloatArray,
    load: FloatArray,
    pose: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    odom: FloatArray,
    odom_counts: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    true_geom: FloatArray,
    nominal_geom: FloatArray,
    encoder: FloatArray,
    poses_out: FloatArray,
    with_odometry: bool,
    volt_out: FloatArray,
) -> None:  # pragma: no cover - compiled
    """``m`` quiet ticks of a team, in place (module notes).

    Each tick, per robot: the odometry moved by the counts since its last update (the
    count differences times ``nominal_geom[2]``, an arc with the nominal radius and
    axle), the true pose kept in ``poses_out``, the PID on the held ``reference``, the
    voltage times ``volt_scale``, the motors under ``load``, the encoders, the true
    pose's arc (the turned angles times the true radius scale).

    Parameters
    ----------
    m : int
        Ticks to run.
    dt : float
        The tick [s].
    reference : ndarray, shape (N, 2)
        Wheel speed references held over the stretch [rad/s].
    volt_scale : ndarray, shape (N,)
        Fraction of the PIDs' voltage each robot's motors get (1.0: all of it).
    load : ndarray, shape (N, 2)
        Load torque on each motor [N m].
    pose : ndarray, shape (N, 3)
        True poses (in/out).
    wheel : ndarray, shape (7, N, 2)
        Per wheel: current [A], speed [rad/s], angle [rad], measured speed [rad/s], PID
        integral [V], filtered derivative [V], last measurement [rad/s] (in/out).
    history : ndarray, shape (window + 1, N, 2)
        Each encoder's last counts, oldest first (in/out; EncoderState's layout).
    odom : ndarray, shape (N, 3)
        Dead-reckoned poses (in/out).
    odom_counts : ndarray, shape (N, 2)
        The counts ``odom`` integrates up to (in/out).
    motor : ndarray, shape (12,)
        :attr:`~firefleet.models.motor.DiscreteMotor.coefficients`.
    pid : ndarray, shape (7,)
        :attr:`~firefleet.control.pid.PidParams.gains`.
    true_geom : ndarray, shape (4,)
        True wheel radius over nominal, right and left; wheel radius [m]; true axle [m].
    nominal_geom : ndarray, shape (3,)
        Nominal wheel radius [m], nominal axle [m], wheel angle per count [rad].
    encoder : ndarray, shape (2,)
        Counts per radian and speed per count (as :func:`encoder_step_one` takes them).
    poses_out : ndarray, shape (m, N, 3)
        The true poses at the start of each tick (out).
    with_odometry : bool
        Whether each tick begins with the odometry's update (False: ``odom`` and
        ``odom_counts`` are left alone).
    volt_out : ndarray, shape (N, 2)
        The voltages of the last tick (out).
    """
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
    scale_r, scale_l, radius, axle = true_geom[0], true_geom[1], true_geom[2], true_geom[3]
    n_radius, n_axle, per_count = nominal_geom[0], nominal_geom[1], nominal_geom[2]
    per_rad, speed_per_count = encoder[0], encoder[1]
    window = history.shape[0] - 1
    for i in range(pose.shape[0]):
        px, py, pth = pose[i, 0], pose[i, 1], pose[i, 2]
        ox, oy, oth = odom[i, 0], odom[i, 1], odom[i, 2]
        cur_r, spd_r, ang_r, meas_r = wheel[0, i, 0], wheel[1, i, 0], wheel[2, i, 0], wheel[3, i, 0]
        int_r, der_r, last_r = wheel[4, i, 0], wheel[5, i, 0], wheel[6, i, 0]
        cur_l, spd_l, ang_l, meas_l = wheel[0, i, 1], wheel[1, i, 1], wheel[2, i, 1], wheel[3, i, 1]
        int_l, der_l, last_l = wheel[4, i, 1], wheel[5, i, 1], wheel[6, i, 1]
        ref_r, ref_l = reference[i, 0], reference[i, 1]
        vs = volt_scale[i]
        tau_r, tau_l = load[i, 0], load[i, 1]
        for j in range(m):
            if with_odometry:  # the estimation stage: the counts since its last update
                c_r, c_l = history[window, i, 0], history[window, i, 1]
                ox, oy, oth = diff_drive_step_one(
                    ox,
                    oy,
                    oth,
                    (c_r - odom_counts[i, 0]) * per_count,
                    (c_l - odom_counts[i, 1]) * per_count,
                    n_radius,
                    n_axle,
                )
                odom_counts[i, 0], odom_counts[i, 1] = c_r, c_l
            poses_out[j, i, 0], poses_out[j, i, 1], poses_out[j, i, 2] = px, py, pth
            # speed_control, the fault's scale, drive_step
            int_r, der_r, volt_r = pid_step_one(int_r, der_r, last_r, ref_r, meas_r, gains, dt)
            last_r = meas_r
            int_l, der_l, volt_l = pid_step_one(int_l, der_l, last_l, ref_l, meas_l, gains, dt)
            last_l = meas_l
            volt_r = volt_r * vs
            volt_l = volt_l * vs
            volt_out[i, 0], volt_out[i, 1] = volt_r, volt_l
            cur_r, spd_r, dphi_r = motor_step_one(cur_r, spd_r, volt_r, tau_r, coef)
            cur_l, spd_l, dphi_l = motor_step_one(cur_l, spd_l, volt_l, tau_l, coef)
            ang_r, count_r, meas_r = encoder_step_one(
                ang_r, dphi_r, history[1, i, 0], per_rad, speed_per_count
            )
            ang_l, count_l, meas_l = encoder_step_one(
                ang_l, dphi_l, history[1, i, 1], per_rad, speed_per_count
            )
            for h in range(window):
                history[h, i, 0] = history[h + 1, i, 0]
                history[h, i, 1] = history[h + 1, i, 1]
            history[window, i, 0] = count_r
            history[window, i, 1] = count_l
            px, py, pth = diff_drive_step_one(
                px, py, pth, dphi_r * scale_r, dphi_l * scale_l, radius, axle
            )
        pose[i, 0], pose[i, 1], pose[i, 2] = px, py, pth
        if with_odometry:
            odom[i, 0], odom[i, 1], odom[i, 2] = ox, oy, oth
        wheel[0, i, 0], wheel[1, i, 0], wheel[2, i, 0], wheel[3, i, 0] = cur_r, spd_r, ang_r, meas_r
        wheel[4, i, 0], wheel[5, i, 0], wheel[6, i, 0] = int_r, der_r, last_r
        wheel[0, i, 1], wheel[1, i, 1], wheel[2, i, 1], wheel[3, i, 1] = cur_l, spd_l, ang_l, meas_l
        wheel[4, i, 1], wheel[5, i, 1], wheel[6, i, 1] = int_l, der_l, last_l


def drive_tick(
    drive: DriveState,
    stack: DriveStack,
    reference_rad_s: FloatArray,
    voltage_scale: FloatArray | None,
    load_torque_n_m: FloatArray,
    consts: StretchConstants | None = None,
) -> tuple[DriveState, FloatArray]:
    """One tick's :func:`~firefleet.sim.drive.speed_control`, the fault's voltage scale
    and :func:`~firefleet.sim.drive.drive_step` (no slip, no odometry in the drive), in
    one compiled call (:func:`drive_stretch` of one tick without the odometry);
    ``consts``: :func:`stretch_constants` (made once per run), None: made here.

    Returns
    -------
    drive : DriveState
        After the tick.
    voltage_v : ndarray, shape (N, 2)
        The voltages held over the tick (scaled) [V].
    """
    out, _, _, _, voltage = _run(
        1, drive, stack, reference_rad_s, voltage_scale, load_torque_n_m, None, None, consts
    )
    return out, voltage


def stretch_drive(
    m: int,
    drive: DriveState,
    stack: DriveStack,
    reference_rad_s: FloatArray,
    voltage_scale: FloatArray | None,
    load_torque_n_m: FloatArray,
    odometry_pose: FloatArray,
    odometry_counts: FloatArray,
    consts: StretchConstants | None = None,
) -> tuple[DriveState, FloatArray, FloatArray, FloatArray]:
    """``m`` quiet ticks (:func:`drive_stretch`) on the loop's arrays.

    Parameters
    ----------
    m : int
        Ticks (>= 1).
    drive : DriveState
        The team's wheel stacks before the first (``drive.odometry`` None).
    stack : DriveStack
    reference_rad_s : ndarray, shape (N, 2)
        The held wheel speed references [rad/s].
    voltage_scale : ndarray, shape (N,), or None
        The world's voltage scale (None: all of the voltage).
    load_torque_n_m : ndarray, shape (N, 2)
    odometry_pose : ndarray, shape (N, 3)
    odometry_counts : ndarray, shape (N, 2)
        The odometry's pose and the counts it integrates up to.
    consts : StretchConstants, optional
        :func:`stretch_constants` of ``stack`` and the team (made once per run).

    Returns
    -------
    drive : DriveState
        After the ``m`` ticks.
    odometry_pose, odometry_counts : ndarray
        The odometry after its update at each tick of the stretch (the counts: the
        encoders' before the last drive step).
    poses : ndarray, shape (m, N, 3)
        The true poses at the start of each tick.
    """
    out, odom, counts, poses, _ = _run(
        m,
        drive,
        stack,
        reference_rad_s,
        voltage_scale,
        load_torque_n_m,
        odometry_pose,
        odometry_counts,
        consts,
    )
    assert odom is not None
    assert counts is not None
    return out, odom, counts, poses


def _run(
    m: int,
    drive: DriveState,
    stack: DriveStack,
    reference_rad_s: FloatArray,
    voltage_scale: FloatArray | None,
    load_torque_n_m: FloatArray,
    odometry_pose: FloatArray | None,
    odometry_counts: FloatArray | None,
    consts: StretchConstants | None,
) -> tuple[DriveState, FloatArray | None, FloatArray | None, FloatArray, FloatArray]:
    """:func:`drive_stretch` on the loop's arrays (the odometry when given)."""
    n = drive.pose.shape[0]
    c = stretch_constants(stack, n) if consts is None else consts
    wheel = np.array(
        [
            drive.current_a,
            drive.speed_rad_s,
            drive.encoder.angle_rad,
            drive.measured_rad_s,
            drive.pid.integral,
            drive.pid.derivative,
            drive.pid.last_measurement,
        ],
        dtype=np.float64,
    )
    history = np.array(drive.encoder.history, dtype=np.float64)
    pose = np.array(drive.pose, dtype=np.float64)
    with_odometry = odometry_pose is not None and odometry_counts is not None
    odom = np.array(odometry_pose, dtype=np.float64) if with_odometry else c.no_odom
    counts = np.array(odometry_counts, dtype=np.float64) if with_odometry else c.no_counts
    voltage = np.empty((n, 2))
    poses = np.empty((m, n, 3))
    reference = np.asarray(reference_rad_s, dtype=np.float64)
    if reference.shape != (n, 2) or not reference.flags.c_contiguous:
        reference = np.ascontiguousarray(np.broadcast_to(reference, (n, 2)))
    load = np.asarray(load_torque_n_m, dtype=np.float64)
    if load.shape != (n, 2) or not load.flags.c_contiguous:
        load = np.ascontiguousarray(np.broadcast_to(load, (n, 2)))
    drive_stretch(
        m,
        stack.dt_s,
        reference,
        c.ones if voltage_scale is None else np.asarray(voltage_scale, dtype=np.float64),
        load,
        pose,
        wheel,
        history,
        odom,
        counts,
        c.motor,
        c.pid,
        c.true_geom,
        c.nominal_geom,
        c.encoder,
        poses,
        with_odometry,
        voltage,
    )
    new = DriveState(
        pose=pose,
        current_a=wheel[0],
        speed_rad_s=wheel[1],
        measured_rad_s=wheel[3],
        pid=PidState(integral=wheel[4], derivative=wheel[5], last_measurement=wheel[6]),
        encoder=EncoderState(angle_rad=wheel[2], history=history),
        odometry=None,
    )
    if not with_odometry:
        return new, None, None, poses, voltage
    return new, odom, counts, poses, voltage
