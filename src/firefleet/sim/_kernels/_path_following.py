"""The fused path-following kernel: the deliverable's whole hierarchy for a team.

See :mod:`firefleet.sim._kernels`.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray, IntArray
from firefleet.control.fuzzy_kernel import eval_one
from firefleet.control.pid import pid_step_one
from firefleet.models.encoder import encoder_step_one
from firefleet.models.kinematics import diff_drive_step_one, wrap_angle_one
from firefleet.models.motor import motor_step_one


@numba.njit(cache=True)
def _path_following_robot(
    i: int,
    k0: int,
    k1: int,
    zmin: float,
    n_steps: int,
    dt: float,
    points: FloatArray,
    spacing: FloatArray,
    period: float,
    pose: FloatArray,
    odom: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    load: FloatArray,
    cpr: float,
    done: FloatArray,
    faults: FloatArray,
    lead: int,
    j_state: IntArray,
    zeta_out: FloatArray,
    rate_out: FloatArray,
    m_kind: IntArray,
    m_par: FloatArray,
    m_in: IntArray,
    m_range: FloatArray,
    m_rmf: IntArray,
    m_rnot: NDArray[np.bool_],
    m_rw: FloatArray,
    m_ror: NDArray[np.bool_],
    m_rout: IntArray,
    m_coef: FloatArray,
    m_mid: FloatArray,
    m_flags: IntArray,
    l_kind: IntArray,
    l_par: FloatArray,
    l_in: IntArray,
    l_range: FloatArray,
    l_rmf: IntArray,
    l_rnot: NDArray[np.bool_],
    l_rw: FloatArray,
    l_ror: NDArray[np.bool_],
    l_rout: IntArray,
    l_coef: FloatArray,
    l_mid: FloatArray,
    l_flags: IntArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    odom_rec: FloatArray,
    wheel_rec: FloatArray,
    ctl_rec: FloatArray,
    desired_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Robot ``i`` of :func:`path_following_chunk` through its steps ``k0 <= k < k1``."""
    pieces = points.shape[1] - 1
    r, axle = geom[0], geom[1]
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
    per_rad = cpr / (2.0 * math.pi) if cpr > 0 else 0.0
    window = history.shape[2] - 1
    count_rad = 2.0 * math.pi / cpr if cpr > 0 else 1.0
    per_count = count_rad / (window * dt)
    tau_on, t_load = load[0], load[1] - 1e-9
    work = np.empty(64 + m_kind.shape[0] + l_kind.shape[0])
    x_main = np.empty(3)
    y_main = np.empty(2)
    x_lam = np.empty(1)
    y_lam = np.empty(1)
    x_end, y_end, h_end = points[i, pieces, 0], points[i, pieces, 1], points[i, pieces, 2]
    cos_end, sin_end = math.cos(h_end), math.sin(h_end)
    # the robot's state, in registers for the chunk
    px, py, pth = pose[i, 0], pose[i, 1], pose[i, 2]
    ox, oy, oth = odom[i, 0], odom[i, 1], odom[i, 2]
    cur_r, spd_r, ang_r, meas_r = wheel[i, 0, 0], wheel[i, 0, 1], wheel[i, 0, 2], wheel[i, 0, 3]
    int_r, der_r, last_r, cnt_r = wheel[i, 0, 4], wheel[i, 0, 5], wheel[i, 0, 6], wheel[i, 0, 7]
    cur_l, spd_l, ang_l, meas_l = wheel[i, 1, 0], wheel[i, 1, 1], wheel[i, 1, 2], wheel[i, 1, 3]
    int_l, der_l, last_l, cnt_l = wheel[i, 1, 4], wheel[i, 1, 5], wheel[i, 1, 6], wheel[i, 1, 7]
    stopped = done[i] > 0.0
    j_prev = j_state[i, 0]
    held = j_state[i, 1]
    n_faults = faults.shape[0]
    j_trig = -1  # the index whose heading's cos and sin are held
    cos_d, sin_d = 1.0, 0.0
    for k in range(k0, k1):
        t = k * dt
        # the robot's release clock: the wall clock less the ticks it has held
        j = math.floor((k - held) * dt / period + 1e-9) + 1
        if zmin == zmin and not stopped and j > j_prev and j > math.floor(zmin) + lead:
            held += 1  # closed loop: the next point would run too far ahead, hold it
            j = j_prev
        j_prev = j
        tau = tau_on if t >= t_load else 0.0
        scale = 1.0
        for f in range(n_faults):
            if faults[f, 0] == i and faults[f, 1] - 1e-9 <= t < faults[f, 2] - 1e-9:
                scale *= faults[f, 3]
        row = rec_index[k]
        # --- high level: the fuzzy controller on the odometry pose (eqs. 9-11)
        if j <= pieces:
            xd, yd, hd = points[i, j, 0], points[i, j, 1], points[i, j, 2]
            if j != j_trig:
                cos_d, sin_d = math.cos(hd), math.sin(hd)
                j_trig = j
        else:  # past the end: on along the end tangent, at the same pace
            beyond = (j - pieces) * spacing[i]
            xd = x_end + beyond * cos_end
            yd = y_end + beyond * sin_end
            cos_d, sin_d = cos_end, sin_end
            j_trig = -1
        dx = xd - ox
        dy = yd - oy
        d_rp = math.sqrt(dx * dx + dy * dy)
        x_err = dx * cos_d + dy * sin_d
        y_err = -math.sin(oth) * dx + math.cos(oth) * dy
        alpha = wrap_angle_one(math.atan2(dy, dx) - oth) if d_rp > 0.0 else 0.0
        x_lam[0] = y_err
        eval_one(
            x_lam,
            l_kind,
            l_par,
            l_in,
            l_range,
            l_rmf,
            l_rnot,
            l_rw,
            l_ror,
            l_rout,
            l_coef,
            l_mid,
            l_flags,
            y_lam,
            work,
        )
        lam_deg = y_lam[0]
        x_main[0] = d_rp
        x_main[1] = x_err
        x_main[2] = min(max(math.degrees(alpha) + lam_deg, -180.0), 180.0)
        eval_one(
            x_main,
            m_kind,
            m_par,
            m_in,
            m_range,
            m_rmf,
            m_rnot,
            m_rw,
            m_ror,
            m_rout,
            m_coef,
            m_mid,
            m_flags,
            y_main,
            work,
        )
        past_end = (x_end - ox) * cos_end + (y_end - oy) * sin_end
        if j >= pieces and past_end <= 0.0:
            stopped = True
        v = 0.0 if stopped else y_main[0]
        omega = 0.0 if stopped else math.radians(y_main[1])
        ref_r = (v + 0.5 * axle * omega) / r
        ref_l = (v - 0.5 * axle * omega) / r
        zeta_out[i] = j - x_err / spacing[i]  # the progress broadcast [segments]
        rate_out[i] = v / spacing[i]  # and its rate [segments/s]
        # --- low level: the wheel-speed PIDs (a motor fault scales what reaches the motor)
        int_r, der_r, volt_r = pid_step_one(int_r, der_r, last_r, ref_r, meas_r, gains, dt)
        last_r = meas_r
        int_l, der_l, volt_l = pid_step_one(int_l, der_l, last_l, ref_l, meas_l, gains, dt)
        last_l = meas_l
        if scale != 1.0:
            volt_r *= scale
            volt_l *= scale
        if row >= 0:
            pose_rec[row, i, 0] = px
            pose_rec[row, i, 1] = py
            pose_rec[row, i, 2] = pth
            odom_rec[row, i, 0] = ox
            odom_rec[row, i, 1] = oy
            odom_rec[row, i, 2] = oth
            wheel_rec[row, i, 0, 0] = spd_r
            wheel_rec[row, i, 0, 1] = meas_r
            wheel_rec[row, i, 0, 2] = ref_r
            wheel_rec[row, i, 0, 3] = cur_r
            wheel_rec[row, i, 0, 4] = volt_r
            wheel_rec[row, i, 0, 5] = tau
            wheel_rec[row, i, 1, 0] = spd_l
            wheel_rec[row, i, 1, 1] = meas_l
            wheel_rec[row, i, 1, 2] = ref_l
            wheel_rec[row, i, 1, 3] = cur_l
            wheel_rec[row, i, 1, 4] = volt_l
            wheel_rec[row, i, 1, 5] = tau
            ctl_rec[row, i, 0] = v
            ctl_rec[row, i, 1] = omega
            ctl_rec[row, i, 2] = d_rp
            ctl_rec[row, i, 3] = x_err
            ctl_rec[row, i, 4] = y_err
            ctl_rec[row, i, 5] = alpha
            ctl_rec[row, i, 6] = math.radians(lam_deg)
            ctl_rec[row, i, 7] = j
            desired_rec[row, i, 0] = xd
            desired_rec[row, i, 1] = yd
        if k == n_steps:
            continue
        # --- plant: motors (exact ZOH), true pose, encoders, odometry
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
        px, py, pth = diff_drive_step_one(px, py, pth, dphi_r, dphi_l, r, axle)
        ox, oy, oth = diff_drive_step_one(
            ox, oy, oth, (count_r - cnt_r) * count_rad, (count_l - cnt_l) * count_rad, r, axle
        )
        cnt_r, cnt_l = count_r, count_l
    pose[i, 0], pose[i, 1], pose[i, 2] = px, py, pth
    odom[i, 0], odom[i, 1], odom[i, 2] = ox, oy, oth
    wheel[i, 0, 0], wheel[i, 0, 1], wheel[i, 0, 2], wheel[i, 0, 3] = cur_r, spd_r, ang_r, meas_r
    wheel[i, 0, 4], wheel[i, 0, 5], wheel[i, 0, 6], wheel[i, 0, 7] = int_r, der_r, last_r, cnt_r
    wheel[i, 1, 0], wheel[i, 1, 1], wheel[i, 1, 2], wheel[i, 1, 3] = cur_l, spd_l, ang_l, meas_l
    wheel[i, 1, 4], wheel[i, 1, 5], wheel[i, 1, 6], wheel[i, 1, 7] = int_l, der_l, last_l, cnt_l
    j_state[i, 0] = j_prev
    j_state[i, 1] = held
    if stopped:
        done[i] = 1.0


@numba.njit(cache=True)
def _heard_minimum_ideal(
    zeta: FloatArray, rate: FloatArray, dt: float
) -> float:  # pragma: no cover - compiled
    """The slowest progress broadcast at the last tick, one tick on (every robot hears
    every broadcast over the ideal link)."""
    zmin: float = zeta[0] + rate[0] * dt
    for m in range(1, zeta.shape[0]):
        zmin = min(zmin, zeta[m] + rate[m] * dt)
    return zmin


@numba.njit(cache=True)
def _next_release(
    k: int, k1: int, dt: float, period: float, j_state: IntArray, done: FloatArray
) -> int:  # pragma: no cover - compiled
    """The end of the run of ticks from ``k`` on in which only tick ``k`` may release a
    point (the law reads the team's progress only there, so the robots are independent
    until the end): ``k + 1`` if some robot's clock is due at ``k``, else the first
    tick at which one falls due (at most ``k1``). Robots that have arrived hold nothing
    and are left out."""
    kk = k1
    for i in range(j_state.shape[0]):
        if done[i] > 0.0:
            continue
        j_prev, held = j_state[i, 0], j_state[i, 1]
        if math.floor((k - held) * dt / period + 1e-9) + 1 > j_prev:
            return min(k + 1, k1)
        t = k + 1
        while t < kk and math.floor((t - held) * dt / period + 1e-9) + 1 <= j_prev:
            t += 1
        kk = min(kk, t)
    return kk


# The two fuzzy systems come in as their FisTables fields, flat: passed as NamedTuples
# the kernel measured 30 % slower, the fields' arrays then reached through the tuple on
# every access. The serial and the parallel kernel are two functions (not one function
# compiled twice): numba's cache keys an entry on the function's name and line, not on
# parallel=True, so one function compiled both ways would load the other's code.
@numba.njit(cache=True)
def path_following_chunk(
    k0: int,
    k1: int,
    coupled: bool,
    n_steps: int,
    dt: float,
    points: FloatArray,
    spacing: FloatArray,
    period: float,
    pose: FloatArray,
    odom: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    load: FloatArray,
    cpr: float,
    done: FloatArray,
    faults: FloatArray,
    lead: int,
    j_state: IntArray,
    zeta_out: FloatArray,
    rate_out: FloatArray,
    m_kind: IntArray,
    m_par: FloatArray,
    m_in: IntArray,
    m_range: FloatArray,
    m_rmf: IntArray,
    m_rnot: NDArray[np.bool_],
    m_rw: FloatArray,
    m_ror: NDArray[np.bool_],
    m_rout: IntArray,
    m_coef: FloatArray,
    m_mid: FloatArray,
    m_flags: IntArray,
    l_kind: IntArray,
    l_par: FloatArray,
    l_in: IntArray,
    l_range: FloatArray,
    l_rmf: IntArray,
    l_rnot: NDArray[np.bool_],
    l_rw: FloatArray,
    l_ror: NDArray[np.bool_],
    l_rout: IntArray,
    l_coef: FloatArray,
    l_mid: FloatArray,
    l_flags: IntArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    odom_rec: FloatArray,
    wheel_rec: FloatArray,
    ctl_rec: FloatArray,
    desired_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Steps ``k0 <= k < k1`` of a path-following team, in place.

    With ``coupled`` (closed-loop coordination over an ideal link), every robot hears
    every robot's progress broadcast the tick before (``zeta_out`` [segments] and
    ``rate_out`` [segments/s], predicted one tick on) and its next point
    is held while it would run more than ``lead`` segments ahead of the slowest
    (``firefleet.sim.kinds.path_following``); before the first broadcast (k = 0) the
    clock alone releases the points. The law reads the team only at a tick where some
    robot's clock falls due (:func:`_next_release`), so the robots run independently,
    each in its registers, from one such tick to the next. Without it the robots are
    independent: each runs the whole range in its registers.

    Parameters
    ----------
    k0, k1 : int
        The range of steps; step ``n_steps`` only records (no plant step after it).
    coupled : bool
        Whether the closed-loop coordination law holds points back (above).
    n_steps : int
        Steps of the whole run.
    dt : float
        Control period [s].
    points : ndarray, shape (N, P + 1, 3)
        Each robot's desired points x [m], y [m] and the path heading there [rad].
    spacing : ndarray, shape (N,)
        Arc length between points [m]: the pace on along the end tangent past the end.
    period : float
        Time between desired points [s].
    pose, odom : ndarray, shape (N, 3)
        True and dead-reckoned poses (in/out).
    wheel : ndarray, shape (N, 2, 8)
        Per wheel: current [A], speed [rad/s], angle [rad], measured speed [rad/s], PID
        integral [V], filtered derivative [V], last measurement [rad/s], last count
        (in/out).
    history : ndarray, shape (N, 2, window + 1)
        Each encoder's last counts, oldest first (in/out).
    motor : ndarray, shape (12,)
        :attr:`~firefleet.models.motor.DiscreteMotor.coefficients`.
    pid : ndarray, shape (7,)
        :attr:`~firefleet.control.pid.PidParams.gains`.
    geom : ndarray, shape (2,)
        Wheel radius [m], axle length [m].
    load : ndarray, shape (2,)
        Load torque [N m] and its start [s].
    cpr : float
        Encoder counts per revolution (0: ideal).
    done : ndarray, shape (N,)
        1.0 once a robot has reached its path's end (in/out).
    m_kind ... m_flags, l_kind ... l_flags : arrays
        The main and the lambda-correction systems' ``FisTables`` fields, in order.
    rec_index : ndarray of int, shape (n_steps + 1,)
        Row of each step in the records, -1 where not recorded.
    pose_rec, odom_rec : ndarray, shape (T, N, 3)
    wheel_rec : ndarray, shape (T, N, 2, 6)
        Speed, measured speed, reference, current, voltage, load.
    ctl_rec : ndarray, shape (T, N, 8)
        ``sim.kinds.path_following.CONTROL_SERIES``.
    desired_rec : ndarray, shape (T, N, 2)
    """
    n = pose.shape[0]
    k = k0
    while k < k1:
        zmin, kk = math.nan, k1
        if coupled:  # the team is read at each tick where a robot's clock falls due
            zmin = _heard_minimum_ideal(zeta_out, rate_out, dt) if k > 0 else math.nan
            kk = _next_release(k, k1, dt, period, j_state, done)
        for i in range(n):
            _path_following_robot(
                i,
                k,
                kk,
                zmin,
                n_steps,
                dt,
                points,
                spacing,
                period,
                pose,
                odom,
                wheel,
                history,
                motor,
                pid,
                geom,
                load,
                cpr,
                done,
                faults,
                lead,
                j_state,
                zeta_out,
                rate_out,
                m_kind,
                m_par,
                m_in,
                m_range,
                m_rmf,
                m_rnot,
                m_rw,
                m_ror,
                m_rout,
                m_coef,
                m_mid,
                m_flags,
                l_kind,
                l_par,
                l_in,
                l_range,
                l_rmf,
                l_rnot,
                l_rw,
                l_ror,
                l_rout,
                l_coef,
                l_mid,
                l_flags,
                rec_index,
                pose_rec,
                odom_rec,
                wheel_rec,
                ctl_rec,
                desired_rec,
            )
        k = kk


@numba.njit(cache=True, parallel=True)
def path_following_chunk_parallel(
    k0: int,
    k1: int,
    coupled: bool,
    n_steps: int,
    dt: float,
    points: FloatArray,
    spacing: FloatArray,
    period: float,
    pose: FloatArray,
    odom: FloatArray,
    wheel: FloatArray,
    history: FloatArray,
    motor: FloatArray,
    pid: FloatArray,
    geom: FloatArray,
    load: FloatArray,
    cpr: float,
    done: FloatArray,
    faults: FloatArray,
    lead: int,
    j_state: IntArray,
    zeta_out: FloatArray,
    rate_out: FloatArray,
    m_kind: IntArray,
    m_par: FloatArray,
    m_in: IntArray,
    m_range: FloatArray,
    m_rmf: IntArray,
    m_rnot: NDArray[np.bool_],
    m_rw: FloatArray,
    m_ror: NDArray[np.bool_],
    m_rout: IntArray,
    m_coef: FloatArray,
    m_mid: FloatArray,
    m_flags: IntArray,
    l_kind: IntArray,
    l_par: FloatArray,
    l_in: IntArray,
    l_range: FloatArray,
    l_rmf: IntArray,
    l_rnot: NDArray[np.bool_],
    l_rw: FloatArray,
    l_ror: NDArray[np.bool_],
    l_rout: IntArray,
    l_coef: FloatArray,
    l_mid: FloatArray,
    l_flags: IntArray,
    rec_index: IntArray,
    pose_rec: FloatArray,
    odom_rec: FloatArray,
    wheel_rec: FloatArray,
    ctl_rec: FloatArray,
    desired_rec: FloatArray,
) -> None:  # pragma: no cover - compiled
    """:func:`path_following_chunk` with each tick's robots spread over every core (the
    same result bit for bit: the slowest progress is taken before the tick)."""
    n = pose.shape[0]
    k = k0
    while k < k1:
        zmin, kk = math.nan, k1
        if coupled:
            zmin = _heard_minimum_ideal(zeta_out, rate_out, dt) if k > 0 else math.nan
            kk = _next_release(k, k1, dt, period, j_state, done)
        for i in numba.prange(n):
            _path_following_robot(
                i,
                k,
                kk,
                zmin,
                n_steps,
                dt,
                points,
                spacing,
                period,
                pose,
                odom,
                wheel,
                history,
                motor,
                pid,
                geom,
                load,
                cpr,
                done,
                faults,
                lead,
                j_state,
                zeta_out,
                rate_out,
                m_kind,
                m_par,
                m_in,
                m_range,
                m_rmf,
                m_rnot,
                m_rw,
                m_ror,
                m_rout,
                m_coef,
                m_mid,
                m_flags,
                l_kind,
                l_par,
                l_in,
                l_range,
                l_rmf,
                l_rnot,
                l_rw,
                l_ror,
                l_rout,
                l_coef,
                l_mid,
                l_flags,
                rec_index,
                pose_rec,
                odom_rec,
                wheel_rec,
                ctl_rec,
                desired_rec,
            )
        k = kk
