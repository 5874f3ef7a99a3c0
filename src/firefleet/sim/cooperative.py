"""The cooperative path-following run: the deliverable's whole hierarchy, every tick.

For each robot of the team (section 2.6, Figure 10)::

    trajectory planner   desired point j(t), the same index for every robot  (2.6.3)
      -> path_following  D_rp, x_err, y_err, alpha from the *odometry* pose (eqs. 9-11),
                         lambda(y_err) added to alpha, Table 1  ->  v, omega (2.6.2)
      -> kinematics      wheel-speed references (eqs. 1-4)
      -> PID             motor voltages from the encoders' measured speeds
      -> DC motors       exact zero-order hold (Table 2), load torque
      -> kinematics      true poses (exact arc)
      -> encoders        counts -> measured speeds, and dead reckoning (odometry)

The loop is one compiled kernel (numba) over steps and robots: at three robots the
per-call overhead of NumPy would dominate (some 150 calls a tick), and at a thousand the
compiled loop is still faster than whole-team array calls. Robots interact only through
the common release schedule, so a team run equals its robots run one by one.
"""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np
from numpy.typing import NDArray

from firefleet.control.fuzzy_kernel import eval_one
from firefleet.control.path_following import PathFollowingController
from firefleet.models.motor import discretise_motor
from firefleet.planning.trajectory import Trajectory
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim.result import SimResult

__all__ = ["CONTROL_SERIES", "simulate_path_following"]

FloatArray = NDArray[np.float64]

CONTROL_SERIES = (
    "v_ref_m_s",
    "omega_ref_rad_s",
    "d_rp_m",
    "x_err_m",
    "y_err_m",
    "alpha_rad",
    "lambda_rad",
    "desired_index",
)
"""Controller quantities recorded each sample, (T, N) each, in this order."""

PARALLEL_MIN_ROBOTS = 64
"""Teams at least this large run their robots on every core (they are independent, so
the result is the same bit for bit); smaller ones on one, where threads cost more than
they bring."""
_CHUNKS = 100
"""The kernel runs in this many pieces, so a progress bar can move."""


def simulate_path_following(
    scenario: Scenario,
    rec_steps: NDArray[np.int64],
    progress: object = None,
    *,
    controller: PathFollowingController | None = None,
) -> SimResult:
    """Run a ``path-following`` scenario.

    Parameters
    ----------
    scenario : Scenario
        With a :class:`~firefleet.scenarios.schema.PathFollowing` command.
    rec_steps : ndarray of int
        Steps to record (ascending, the last one included).
    progress : callable, optional
        ``progress(done, total)``.
    controller : PathFollowingController, optional
        The fuzzy systems; the command's (the built-in ones by default).

    Returns
    -------
    SimResult
        ``extra`` holds the controller series (``CONTROL_SERIES``), ``odometry_pose``
        (T, N, 3) and ``desired_xy_m`` (T, N, 2).
    """
    cmd = scenario.command
    assert isinstance(cmd, PathFollowing)
    ctl = controller if controller is not None else PathFollowingController.from_command(cmd)
    traj = Trajectory.from_paths(cmd.paths, pieces=cmd.pieces, duration_s=cmd.trajectory_s)
    spacing = np.array([p.length_m / cmd.pieces for p in cmd.paths])
    rng = np.random.default_rng(scenario.seed)
    dt = scenario.dt_s
    n = scenario.n_robots
    n_steps = scenario.n_steps
    enc = scenario.encoder
    cpr = enc.counts_per_rev
    phase = rng.uniform(0.0, 2.0 * math.pi / cpr if cpr else 0.0, size=(n, 2))
    disc = discretise_motor(scenario.motor, dt)
    motor = np.r_[disc.ad.ravel(), disc.bd.ravel(), disc.c_ad, disc.c_bd]
    g = scenario.speed_pid
    pid = np.array(
        [
            g.kp,
            g.ki,
            g.kd,
            g.derivative_filter_s,
            g.setpoint_weight,
            g.tracking_time_s,
            g.output_limit,
        ]
    )
    geom = np.array([scenario.robot.wheel_radius_m, scenario.robot.axle_length_m])
    load = np.array([scenario.load.torque_n_m, scenario.load.start_s])

    # state: true pose, odometry pose, per wheel: current, speed, angle, measured speed,
    # PID integral, filtered derivative, last measurement, last count
    pose = scenario.initial_poses.copy()
    odom = pose.copy()
    wheel = np.zeros((n, 2, 8))
    wheel[:, :, 2] = phase
    per_rad = cpr / (2.0 * math.pi) if cpr else 0.0
    first = np.floor(phase * per_rad) if cpr else phase
    wheel[:, :, 7] = first
    history = np.repeat(first[:, :, None], enc.window_steps + 1, axis=2)

    done = np.zeros(n)  # 1 once a robot has reached its path's end (it then stays)
    n_rec = rec_steps.size
    pose_rec = np.empty((n_rec, n, 3))
    odom_rec = np.empty((n_rec, n, 3))
    wheel_rec = np.empty((n_rec, n, 2, 6))  # speed, measured, ref, current, voltage, load
    ctl_rec = np.empty((n_rec, n, len(CONTROL_SERIES)))
    desired_rec = np.empty((n_rec, n, 2))
    rec_index = np.full(n_steps + 1, -1, dtype=np.int64)
    rec_index[rec_steps] = np.arange(n_rec)

    bounds = np.unique(np.linspace(0, n_steps + 1, _CHUNKS + 1).astype(np.int64))
    for k0, k1 in itertools.pairwise(bounds):
        kernel = _run_parallel if n >= PARALLEL_MIN_ROBOTS else _run
        kernel(
            int(k0),
            int(k1),
            n_steps,
            dt,
            traj.points,
            spacing,
            traj.period_s,
            pose,
            odom,
            wheel,
            history,
            motor,
            pid,
            geom,
            load,
            float(cpr),
            done,
            *ctl.main_tables,
            *ctl.lambda_tables,
            rec_index,
            pose_rec,
            odom_rec,
            wheel_rec,
            ctl_rec,
            desired_rec,
        )
        if callable(progress):
            progress(min(int(k1), n_steps), n_steps)

    return SimResult(
        scenario=scenario,
        t=np.asarray(rec_steps * dt, dtype=np.float64),
        pose=pose_rec,
        wheel_speed_rad_s=wheel_rec[..., 0].copy(),
        wheel_speed_measured_rad_s=wheel_rec[..., 1].copy(),
        wheel_speed_ref_rad_s=wheel_rec[..., 2].copy(),
        current_a=wheel_rec[..., 3].copy(),
        voltage_v=wheel_rec[..., 4].copy(),
        load_torque_n_m=wheel_rec[..., 5].copy(),
        extra={
            "odometry_pose": odom_rec,
            "desired_xy_m": desired_rec,
            **{name: ctl_rec[:, :, i].copy() for i, name in enumerate(CONTROL_SERIES)},
        },
    )


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


_run = numba.njit(cache=True)(_run_py)
_run_parallel = numba.njit(cache=True, parallel=True)(_run_py)


_MOVING_M_S = 0.01
"""A robot is under way once its commanded speed exceeds this [m/s]."""
_CAPTURE_M = 0.05
"""A robot has caught its path once it comes this close to it [m]."""


def path_following_metrics(result: SimResult) -> dict[str, float | list[float]]:
    """Metrics of a path-following run, on the true poses (per robot: a list).

    ``path_lengths_m``; ``wait_time_s`` (until the commanded speed first exceeds
    1 cm/s: a robot ahead of its path waits, 2.6.2.4); ``capture_time_s`` (first time
    within 5 cm of the path); ``cross_track_rms_m`` (distance to the path, whole run)
    and ``cross_track_rms_after_capture_m`` / ``cross_track_max_after_capture_m`` (from
    capture on); ``final_position_error_m`` (end pose to path end); ``arrival_time_s``
    (first time within ``arrival_radius_m`` of the path's end) and, for the team,
    ``arrival_spread_s``; ``mean_speed_m_s`` (distance driven / time under way until
    arrival); ``longest_path_speed_margin_m_s`` (mean speed of the robot on the longest
    path minus the fastest other's; NaN for one robot); ``sync_distance_m`` (arc length
    from which on every robot's progress along its path, as a share of its length,
    stays within one piece of every other's: the formation of Figures 32 and 36,
    measured on the paths' average length; NaN for one robot); ``odometry_drift_m``
    (distance between dead reckoning and the true pose at the end); ``peak_current_a``;
    ``max_voltage_v``. Times are NaN where the event never happens.
    """
    cmd = result.scenario.command
    assert isinstance(cmd, PathFollowing)
    t = result.t
    xy = result.pose[:, :, :2]
    n = xy.shape[1]
    lengths = [p.length_m for p in cmd.paths]
    dist = np.empty((t.size, n))
    progress = np.empty((t.size, n))
    for i, path in enumerate(cmd.paths):
        dist[:, i], s = path.distance(xy[:, i])
        progress[:, i] = s / lengths[i]
    v_ref = result.extra["v_ref_m_s"]
    out: dict[str, float | list[float]] = {"path_lengths_m": lengths}
    wait, capture, rms_after, max_after, arrival, speed = [], [], [], [], [], []
    for i, path in enumerate(cmd.paths):
        moving = np.nonzero(v_ref[:, i] > _MOVING_M_S)[0]
        t_move = float(t[moving[0]]) if moving.size else math.nan
        wait.append(t_move)
        caught = np.nonzero(dist[:, i] <= _CAPTURE_M)[0]
        k_cap = int(caught[0]) if caught.size else t.size
        capture.append(float(t[k_cap]) if caught.size else math.nan)
        after = dist[k_cap:, i]
        rms_after.append(float(np.sqrt(np.mean(after**2))) if after.size else math.nan)
        max_after.append(float(after.max()) if after.size else math.nan)
        end = np.array([path.x_end_m, float(path.y(path.x_end_m))])
        near = np.nonzero(np.hypot(*(xy[:, i] - end).T) <= cmd.arrival_radius_m)[0]
        k_arr = int(near[0]) if near.size else t.size - 1
        arrival.append(float(t[k_arr]) if near.size else math.nan)
        driven = float(np.sum(np.hypot(*np.diff(xy[: k_arr + 1, i], axis=0).T)))
        under_way = t[k_arr] - (t_move if math.isfinite(t_move) else 0.0)
        speed.append(float(driven / under_way) if under_way > 0 else math.nan)
    out["wait_time_s"] = wait
    out["capture_time_s"] = capture
    out["cross_track_rms_m"] = [float(v) for v in np.sqrt(np.mean(dist**2, axis=0))]
    out["cross_track_rms_after_capture_m"] = rms_after
    out["cross_track_max_after_capture_m"] = max_after
    ends = np.array([[p.x_end_m, float(p.y(p.x_end_m))] for p in cmd.paths])
    out["final_position_error_m"] = [float(v) for v in np.hypot(*(xy[-1] - ends).T)]
    out["arrival_time_s"] = arrival
    out["arrival_spread_s"] = float(np.max(arrival) - np.min(arrival)) if n > 1 else 0.0
    out["mean_speed_m_s"] = speed
    longest = int(np.argmax(lengths))
    others = [s for i, s in enumerate(speed) if i != longest]
    out["longest_path_speed_margin_m_s"] = speed[longest] - max(others) if others else math.nan
    out["sync_distance_m"] = _sync_distance(progress, cmd.pieces, float(np.mean(lengths)))
    odom = result.extra["odometry_pose"]
    out["odometry_drift_m"] = [float(v) for v in np.hypot(*(odom[-1, :, :2] - xy[-1]).T)]
    out["peak_current_a"] = float(np.abs(result.current_a).max())
    out["max_voltage_v"] = float(np.abs(result.voltage_v).max())
    return out


def _sync_distance(progress: FloatArray, pieces: int, length_m: float) -> float:
    """Arc length (on a path of ``length_m``) from which every robot's progress stays
    within one piece (``1 / pieces`` of its path) of every other's; NaN for one robot
    or if the team never synchronises."""
    if progress.shape[1] < 2:
        return math.nan
    spread = progress.max(axis=1) - progress.min(axis=1)
    apart = np.nonzero(spread > 1.0 / pieces)[0]
    if apart.size == 0:
        return float(progress[0].mean() * length_m)
    k = int(apart[-1]) + 1
    if k >= progress.shape[0]:
        return math.nan
    return float(progress[k].mean() * length_m)
