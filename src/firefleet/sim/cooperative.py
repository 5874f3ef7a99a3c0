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

import functools
import itertools
import math

import numpy as np
from numpy.typing import NDArray

from firefleet.control.path_following import PathFollowingController
from firefleet.models.motor import discretise_motor
from firefleet.planning.trajectory import Trajectory
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim._kernels import (
    PARALLEL_MIN_ROBOTS,
    PARALLEL_MIN_ROBOTS_ONE_PIECE,
    path_following_chunk,
    path_following_chunk_parallel,
)
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

_CHUNKS = 100
"""With a progress callback the kernel runs in this many pieces, so a progress bar can
move; without one, in one piece."""


@functools.cache
def _builtin_controller() -> PathFollowingController:
    """The shipped controller, read once: its ``.fis`` files are part of the package, and
    reading them took 0.7 ms of a 3-robot run's 11 ms."""
    return PathFollowingController.builtin()


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
    if controller is not None:
        ctl = controller
    elif not cmd.controller_fis and not cmd.lambda_fis:
        ctl = _builtin_controller()
    else:
        ctl = PathFollowingController.from_command(cmd)
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
    motor = np.array(disc.coefficients)
    pid = np.array(scenario.speed_pid.gains)
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
    # in Fortran order each recorded series is one contiguous block, returned without a
    # copy: speed, measured, ref, current, voltage, load
    wheel_rec = np.empty((n_rec, n, 2, 6), order="F")
    ctl_rec = np.empty((n_rec, n, len(CONTROL_SERIES)), order="F")
    desired_rec = np.empty((n_rec, n, 2))
    rec_index = np.full(n_steps + 1, -1, dtype=np.int64)
    rec_index[rec_steps] = np.arange(n_rec)

    chunks = _CHUNKS if callable(progress) else 1
    bounds = np.unique(np.linspace(0, n_steps + 1, chunks + 1).astype(np.int64))
    for k0, k1 in itertools.pairwise(bounds):
        parallel = n >= (PARALLEL_MIN_ROBOTS_ONE_PIECE if chunks == 1 else PARALLEL_MIN_ROBOTS)
        kernel = path_following_chunk_parallel if parallel else path_following_chunk
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
        wheel_speed_rad_s=wheel_rec[..., 0],
        wheel_speed_measured_rad_s=wheel_rec[..., 1],
        wheel_speed_ref_rad_s=wheel_rec[..., 2],
        current_a=wheel_rec[..., 3],
        voltage_v=wheel_rec[..., 4],
        load_torque_n_m=wheel_rec[..., 5],
        extra={
            "odometry_pose": odom_rec,
            "desired_xy_m": desired_rec,
            **{name: ctl_rec[..., i] for i, name in enumerate(CONTROL_SERIES)},
        },
    )


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
