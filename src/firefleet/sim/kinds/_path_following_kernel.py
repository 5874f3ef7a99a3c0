"""The compiled chunk of the path-following run: every stage of a tick, fused.

One numba kernel over ticks and robots performs, for the default stages of the world
loop (static world, no sensors, ideal link, odometry), the same tick sequence as the
staged loop of :mod:`firefleet.sim.loop` with the decision of
:mod:`firefleet.sim.kinds.path_following`::

    desired point        Trajectory.desired (the end-of-path extension included)
    controller           controller_inputs, the two fuzzy systems (command)
    stop rule            control.path_following.arrival
    wheel references     models.kinematics.body_to_wheels
    PID                  control.pid.pid_step (speed_control)
    motors, kinematics,  drive_step: exact ZOH, true pose (exact arc), encoders,
    encoders, odometry   dead reckoning from the counts

At three robots the per-call overhead of NumPy would dominate (some 150 calls a tick),
and at a thousand the compiled loop is still faster than whole-team array calls.
tests/sim/test_loop.py shows the kernel equals the staged loop built
from the public functions, step by step.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from firefleet.control.fuzzy_kernel import eval_one

__all__ = ["run_chunk", "run_chunk_parallel"]

FloatArray = NDArray[np.float64]


@numba.njit(cache=True)
def _wrap(a: float) -> float:  # pragma: no cover - jit
    w = (a + math.pi) % (2.0 * math.pi) - math.pi
    return w - 2.0 * math.pi if w >= math.pi else w


@numba.njit(cache=True)
def _arc(pose: FloatArray, i: int, dr: float, dl: float, r: float, axle: float) -> None:
    """Exact arc step of a differential-drive pose (models.kinematics.diff_drive_step)."""
    ds = r * (dr + dl) / 2.0
    dth = r * (dr - dl) / axle
    half = 0.5 * dth
    sinc = 1.0 - half * half / 6.0 if abs(half) < 1e-4 else math.sin(half) / half
    chord = ds * sinc
    th = pose[i, 2]
    pose[i, 0] += chord * math.cos(th + half)
    pose[i, 1] += chord * math.sin(th + half)
    pose[i, 2] = _wrap(th + dth)


# The two fuzzy systems come in as their FisTables fields, flat: passed as NamedTuples
# the kernel measured 30 % slower (bench/path_following.py), the fields' arrays then
# reached through the tuple on every access.
def _run_py(
    k0: int,
    k1: int,
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
    m_kind: NDArray[np.int64],
    m_par: FloatArray,
    m_in: NDArray[np.int64],
    m_range: FloatArray,
    m_rmf: NDArray[np.int64],
    m_rnot: NDArray[np.bool_],
    m_rw: FloatArray,
    m_ror: NDArray[np.bool_],
    m_rout: NDArray[np.int64],
    m_coef: FloatArray,
    m_mid: FloatArray,
    m_flags: NDArray[np.int64],
    l_kind: NDArray[np.int64],
    l_par: FloatArray,
    l_in: NDArray[np.int64],
    l_range: FloatArray,
    l_rmf: NDArray[np.int64],
    l_rnot: NDArray[np.bool_],
    l_rw: FloatArray,
    l_ror: NDArray[np.bool_],
    l_rout: NDArray[np.int64],
    l_coef: FloatArray,
    l_mid: FloatArray,
    l_flags: NDArray[np.int64],
    rec_index: NDArray[np.int64],
    pose_rec: FloatArray,
    odom_rec: FloatArray,
    wheel_rec: FloatArray,
    ctl_rec: FloatArray,
    desired_rec: FloatArray,
) -> None:  # pragma: no cover - jit
    n = pose.shape[0]
    pieces = points.shape[1] - 1
    r, axle = geom[0], geom[1]
    a00, a01, a10, a11 = motor[0], motor[1], motor[2], motor[3]
    b00, b01, b10, b11 = motor[4], motor[5], motor[6], motor[7]
    c0, c1, d0, d1 = motor[8], motor[9], motor[10], motor[11]
    kp, ki, kd, tf, bw, tt, lim = pid[0], pid[1], pid[2], pid[3], pid[4], pid[5], pid[6]
    per_rad = cpr / (2.0 * math.pi)
    window = history.shape[2] - 1
    speed_scale = (2.0 * math.pi / cpr if cpr > 0 else 1.0) / (window * dt)
    count_rad = 2.0 * math.pi / cpr if cpr > 0 else 1.0
    arrived = np.zeros(n, dtype=np.bool_)
    for q in range(n):
        arrived[q] = done[q] > 0.0
    for i in numba.prange(n):  # robots are independent: each runs the whole chunk in turn
        work = np.empty(64 + m_kind.shape[0] + l_kind.shape[0])
        x_main = np.empty(3)
        y_main = np.empty(2)
        x_lam = np.empty(1)
        y_lam = np.empty(1)
        ref = np.empty(2)
        volt = np.empty(2)
        dphi = np.empty(2)
        dmeas = np.empty(2)
        for k in range(k0, k1):
            t = k * dt
            j = math.floor(t / period + 1e-9) + 1
            tau = load[0] if t >= load[1] - 1e-9 else 0.0
            row = rec_index[k]
            # --- high level: the fuzzy controller on the odometry pose (eqs. 9-11)
            x_end, y_end, h_end = points[i, pieces, 0], points[i, pieces, 1], points[i, pieces, 2]
            if j <= pieces:
                xd, yd, hd = points[i, j, 0], points[i, j, 1], points[i, j, 2]
            else:  # past the end: on along the end tangent, at the same pace
                beyond = (j - pieces) * spacing[i]
                xd = x_end + beyond * math.cos(h_end)
                yd = y_end + beyond * math.sin(h_end)
                hd = h_end
            dx = xd - odom[i, 0]
            dy = yd - odom[i, 1]
            th = odom[i, 2]
            d_rp = math.sqrt(dx * dx + dy * dy)
            x_err = dx * math.cos(hd) + dy * math.sin(hd)
            y_err = -math.sin(th) * dx + math.cos(th) * dy
            alpha = _wrap(math.atan2(dy, dx) - th) if d_rp > 0.0 else 0.0
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
            past_end = (x_end - odom[i, 0]) * math.cos(h_end) + (y_end - odom[i, 1]) * math.sin(
                h_end
            )
            if j >= pieces and past_end <= 0.0:
                arrived[i] = True
                done[i] = 1.0
            v = 0.0 if arrived[i] else y_main[0]
            omega = 0.0 if arrived[i] else math.radians(y_main[1])
            ref[0] = (v + 0.5 * axle * omega) / r
            ref[1] = (v - 0.5 * axle * omega) / r
            # --- low level: PID per wheel (control.pid.pid_step)
            for w in range(2):
                y = wheel[i, w, 3]
                d = (tf * wheel[i, w, 5] - kd * (y - wheel[i, w, 6])) / (tf + dt)
                u = kp * (bw * ref[w] - y) + wheel[i, w, 4] + d
                u_sat = -lim if u < -lim else (lim if u > lim else u)
                wheel[i, w, 4] += dt * (ki * (ref[w] - y) + (u_sat - u) / tt)
                wheel[i, w, 5] = d
                wheel[i, w, 6] = y
                volt[w] = u_sat
            if row >= 0:
                for c in range(3):
                    pose_rec[row, i, c] = pose[i, c]
                    odom_rec[row, i, c] = odom[i, c]
                for w in range(2):
                    wheel_rec[row, i, w, 0] = wheel[i, w, 1]
                    wheel_rec[row, i, w, 1] = wheel[i, w, 3]
                    wheel_rec[row, i, w, 2] = ref[w]
                    wheel_rec[row, i, w, 3] = wheel[i, w, 0]
                    wheel_rec[row, i, w, 4] = volt[w]
                    wheel_rec[row, i, w, 5] = tau
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
            for w in range(2):
                i0, w0, vv = wheel[i, w, 0], wheel[i, w, 1], volt[w]
                wheel[i, w, 0] = a00 * i0 + a01 * w0 + b00 * vv + b01 * tau
                wheel[i, w, 1] = a10 * i0 + a11 * w0 + b10 * vv + b11 * tau
                dphi[w] = c0 * i0 + c1 * w0 + d0 * vv + d1 * tau
                wheel[i, w, 2] += dphi[w]
                count = math.floor(wheel[i, w, 2] * per_rad) if cpr > 0 else wheel[i, w, 2]
                for h in range(window):
                    history[i, w, h] = history[i, w, h + 1]
                history[i, w, window] = count
                wheel[i, w, 3] = (history[i, w, window] - history[i, w, 0]) * speed_scale
                dmeas[w] = (count - wheel[i, w, 7]) * count_rad
                wheel[i, w, 7] = count
            _arc(pose, i, dphi[0], dphi[1], r, axle)
            _arc(odom, i, dmeas[0], dmeas[1], r, axle)


run_chunk = numba.njit(cache=True)(_run_py)
"""The kernel on one core."""
run_chunk_parallel = numba.njit(cache=True, parallel=True)(_run_py)
"""The kernel with its robots spread over every core (same result bit for bit)."""
