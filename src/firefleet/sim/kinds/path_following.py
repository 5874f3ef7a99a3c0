"""Cooperative path following (section 2.6 of the deliverable): each robot its own path.

For each robot of the team (Figure 10), on the world loop (:mod:`firefleet.sim.loop`)::

    estimation       the odometry pose (dead reckoning of the encoder counts)
    decide           trajectory planner: desired point j(t), the same index for every
                     robot, extended past the end (planning.Trajectory, 2.6.3)
                     -> D_rp, x_err, y_err, alpha from the odometry pose (eqs. 9-11),
                     lambda(y_err) added to alpha, Table 1 -> v, omega (2.6.2)
                     -> the stop rule at the path's end (control.path_following.arrival)
                     -> wheel-speed references (eqs. 1-4)
    drive            PID -> DC motors (exact ZOH, load torque) -> true pose (exact arc)
                     -> encoders

The default stages run as one compiled chunk (:mod:`firefleet.sim._kernels`), called
from :func:`_kernel_chunk` only.

Coordination (``command.coordination``): ``closed`` closes the release
of the desired points through the team's progress as each robot hears it over the
link (:mod:`firefleet.control.coordination`: no robot's point runs more than
``lead_segments`` ahead of the slowest progress it has heard); ``clock`` is the
deliverable's open-loop common schedule alone (the default), where a team run equals
its robots run one by one. With every robot on time the two release the same points (the built-in
experiments give the same results bit for bit); they part when a robot falls behind
(``coop-motor-fault``). Each robot's broadcast is the outbox's ``zeta`` [segments] and
``zeta_rate`` [segments/s], (N,); the inbox brings them back either as (N,), heard
alike by everyone one tick later (the ideal link), or as (N, N) rows per receiver with
the ticks they were sent at, ``sent_tick`` (N, N) (:mod:`firefleet.sim.link`), or
their ages ``zeta_age_s`` (N, N) [s] (:mod:`firefleet.net`'s relay).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.control.coordination import coordinated_release, heard_minimum
from firefleet.control.path_following import (
    PathFollowingController,
    arrival,
    controller_inputs,
)
from firefleet.errors import InputError
from firefleet.models.kinematics import RobotGeometry, body_to_wheels
from firefleet.models.motor import discretise_motor
from firefleet.planning.trajectory import Trajectory
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim._kernels import (
    PARALLEL_MIN_ROBOTS,
    PARALLEL_MIN_ROBOTS_ONE_PIECE,
    path_following_chunk,
    path_following_chunk_parallel,
)
from firefleet.sim.link import ages
from firefleet.sim.loop import DecideInputs, Decider, ProgressCallback, WheelCommand, chunk_bounds
from firefleet.sim.registry import Metrics, TaskKind
from firefleet.sim.result import SimResult

__all__ = [
    "CONTROL_SERIES",
    "KINDS",
    "PathFollowingParams",
    "path_following_decide",
    "path_following_metrics",
]


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

LINK_SERIES = ("message_age_max_s", "stale_robots")
"""Per robot (T, N): the oldest progress value the law used [s] (NaN: none heard) and
how many robots it held stale."""

SERIES = ("odometry_pose", "desired_xy_m", *CONTROL_SERIES, *LINK_SERIES)
"""What a run records in ``extra``: the odometry (T, N, 3), the desired points (T, N, 2)
the controller series and the link series."""


def _command(scenario: Scenario) -> PathFollowing:
    cmd = scenario.command
    if not isinstance(cmd, PathFollowing):
        raise InputError(f"command.kind: expected path-following, got {cmd.kind!r}")
    return cmd


def _trajectory(cmd: PathFollowing) -> Trajectory:
    return Trajectory.from_paths(cmd.paths, pieces=cmd.pieces, duration_s=cmd.trajectory_s)


# --- the decision, staged ------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PathFollowingParams:
    """The constants of the team's decision.

    Attributes
    ----------
    controller : PathFollowingController
        The two fuzzy systems.
    trajectory : Trajectory
        The desired points and their release schedule.
    geometry : RobotGeometry
        Nominal geometry, for the wheel references.
    closed : bool
        Closed-loop coordination (else the clock alone).
    lead_segments : int
        The closed law's bound [segments].
    timeout_s : float
        Progress older than this is stale [s].
    """

    controller: PathFollowingController
    trajectory: Trajectory
    geometry: RobotGeometry
    closed: bool = False
    lead_segments: int = 10
    timeout_s: float = 1.0


@dataclass(frozen=True)
class PathFollowingState:
    """The team's decision memory (each (N,)): who has arrived, the indices released, and
    how many ticks each robot's release clock has held (``firefleet.control.coordination``)."""

    arrived: NDArray[np.bool_]
    released: NDArray[np.int64]
    held: NDArray[np.int64]


def _init(scenario: Scenario) -> tuple[PathFollowingState, PathFollowingParams]:
    cmd = _command(scenario)
    params = PathFollowingParams(
        controller=PathFollowingController.from_command(cmd),
        trajectory=_trajectory(cmd),
        geometry=scenario.robot,
        closed=cmd.coordination == "closed",
        lead_segments=cmd.lead_segments,
        timeout_s=scenario.link.timeout_s if scenario.link is not None else 1.0,
    )
    n = scenario.n_robots
    zeros = np.zeros(n, dtype=np.int64)
    return PathFollowingState(np.zeros(n, dtype=np.bool_), zeros, zeros), params


def _desired_at(traj: Trajectory, j: NDArray[np.int64]) -> FloatArray:
    """Each robot's point ``j[i]`` (N, 3); past the end, the end moved on along its
    heading (as :meth:`Trajectory.desired` does for a common index)."""
    n = traj.pieces
    rows = np.arange(j.size)
    out = np.array(traj.points[rows, np.minimum(j, n)])
    past = j > n
    if np.any(past):
        end = traj.points[rows[past], n]
        beyond = (j[past] - n) * traj.end_spacing_m[past]
        out[past, 0] = end[:, 0] + beyond * np.cos(end[:, 2])
        out[past, 1] = end[:, 1] + beyond * np.sin(end[:, 2])
    return out


def _heard(
    inbox: Mapping[str, FloatArray], n: int, step: int, dt_s: float, timeout_s: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """zmin, age_max, stale (each (N,)) from the inbox; NaN, NaN, 0 if nothing came."""
    if "zeta" not in inbox:
        return np.full(n, np.nan), np.full(n, np.nan), np.zeros(n)
    zeta, rate = np.asarray(inbox["zeta"]), np.asarray(inbox["zeta_rate"])
    if zeta.ndim == 1:  # the ideal link: everyone heard every broadcast of the last tick
        m = zeta.size
        zeta, rate = np.broadcast_to(zeta, (n, m)), np.broadcast_to(rate, (n, m))
        age = np.full((n, m), dt_s)
    else:
        if "sent_tick" in inbox:  # the link model: the tick each value was sent at
            age = ages(np.asarray(inbox["sent_tick"]), step, dt_s)
        else:  # ages as such (firefleet.net's relay: +inf for a robot gone)
            age = np.asarray(inbox["zeta_age_s"])
    return heard_minimum(zeta, rate, age, timeout_s)


def path_following_decide(
    state: PathFollowingState, inputs: DecideInputs, params: PathFollowingParams, dt_s: float
) -> tuple[PathFollowingState, WheelCommand]:
    """The team's decision at a tick: wheel references from the odometry poses.

    Parameters
    ----------
    state : PathFollowingState
        Which robots have stopped at their path's end, and the indices released.
    inputs : DecideInputs
        ``t_s``, ``pose_estimate`` (N, 3), the odometry, and the ``inbox``: the team's
        progress as heard (module notes).
    params : PathFollowingParams
    dt_s : float
        Control period [s] (the age of what the ideal link delivers).

    Returns
    -------
    state : PathFollowingState
    command : WheelCommand
        Wheel references [rad/s] (N, 2); the series of ``SERIES``; the outbox's
        progress broadcast ``zeta``, ``zeta_rate`` (N,).
    """
    pose = inputs.pose_estimate
    if pose is None:
        raise InputError("path following needs a pose estimate (estimation: odometry)")
    traj = params.trajectory
    n = pose.shape[0]
    if params.closed:
        zmin, age_max, stale = _heard(inputs.inbox, n, inputs.step, dt_s, params.timeout_s)
    else:
        zmin, age_max, stale = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n)
    # a robot that has arrived holds no point back (it has stopped for good)
    zmin = np.where(state.arrived, np.nan, zmin)
    j, held = coordinated_release(
        state.released, state.held, inputs.step, dt_s, traj.period_s, zmin, params.lead_segments
    )
    desired = _desired_at(traj, j)
    x = controller_inputs(pose, desired)
    v, omega, lam = params.controller.command(x)
    past_end = arrival(np.zeros(n, dtype=np.bool_), pose, traj.points[:, -1], 0, 0)
    arrived = state.arrived | (past_end & (j >= traj.pieces))
    v = np.where(arrived, 0.0, v)
    omega = np.where(arrived, 0.0, omega)
    spacing = traj.end_spacing_m
    series = {
        "odometry_pose": pose,
        "desired_xy_m": desired[:, :2],
        "v_ref_m_s": v,
        "omega_ref_rad_s": omega,
        "d_rp_m": x[:, 0],
        "x_err_m": x[:, 1],
        "y_err_m": x[:, 2],
        "alpha_rad": x[:, 3],
        "lambda_rad": lam,
        "desired_index": j.astype(np.float64),
        "message_age_max_s": age_max,
        "stale_robots": stale,
    }
    outbox = {"zeta": j - x[:, 1] / spacing, "zeta_rate": v / spacing}
    command = WheelCommand(
        reference_rad_s=body_to_wheels(v, omega, params.geometry), series=series, outbox=outbox
    )
    return PathFollowingState(arrived, j, held), command


# --- the same, fused -----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _Buffers:
    """The compiled loop's state and records, and the scenario for the result."""

    scenario: Scenario
    rec_steps: NDArray[np.int64]
    args: tuple[Any, ...]  # the kernel's arguments after (k0, k1)
    pose_rec: FloatArray
    odom_rec: FloatArray
    wheel_rec: FloatArray
    ctl_rec: FloatArray
    desired_rec: FloatArray
    closed: bool


@functools.cache
def _builtin_controller() -> PathFollowingController:
    """The shipped controller, read once: its ``.fis`` files are part of the package, and
    reading them took 0.7 ms of a 3-robot run's 11 ms."""
    return PathFollowingController.builtin()


def _start(scenario: Scenario, phase: FloatArray, rec_steps: NDArray[np.int64]) -> _Buffers:
    cmd = _command(scenario)
    builtin = not cmd.controller_fis and not cmd.lambda_fis
    ctl = _builtin_controller() if builtin else PathFollowingController.from_command(cmd)
    traj = _trajectory(cmd)
    assert traj.spacing_m is not None  # from_paths sets it
    dt = scenario.dt_s
    n = scenario.n_robots
    enc = scenario.encoder
    cpr = enc.counts_per_rev
    motor = np.array(discretise_motor(scenario.motor, dt).coefficients)
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
    closed = cmd.coordination == "closed"
    faults = np.array(
        [[f.robot - 1, f.start_s, f.end_s, f.voltage_scale] for f in scenario.faults]
    ).reshape(-1, 4)
    n_rec = rec_steps.size
    rec_index = np.full(scenario.n_steps + 1, -1, dtype=np.int64)
    rec_index[rec_steps] = np.arange(n_rec)
    pose_rec = np.empty((n_rec, n, 3))
    odom_rec = np.empty((n_rec, n, 3))
    # speed, measured, ref, current, voltage, load; Fortran order, so that each quantity
    # is one contiguous block the result takes without a copy
    wheel_rec = np.empty((n_rec, n, 2, 6), order="F")
    ctl_rec = np.empty((n_rec, n, len(CONTROL_SERIES)), order="F")
    desired_rec = np.empty((n_rec, n, 2))
    args = (
        scenario.n_steps,
        dt,
        traj.points,
        traj.spacing_m,
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
        faults,
        cmd.lead_segments if closed else 0,
        np.zeros((n, 2), dtype=np.int64),  # the released indices, the ticks held
        np.zeros(n),  # the progress broadcast [segments]
        np.zeros(n),  # and its rate [segments/s]
        *ctl.main_tables,
        *ctl.lambda_tables,
        rec_index,
        pose_rec,
        odom_rec,
        wheel_rec,
        ctl_rec,
        desired_rec,
    )
    return _Buffers(
        scenario, rec_steps, args, pose_rec, odom_rec, wheel_rec, ctl_rec, desired_rec, closed
    )


def _kernel_chunk(buffers: _Buffers, k0: int, k1: int, *, one_piece: bool = False) -> None:
    """Ticks ``k0 .. k1 - 1`` of the compiled loop: the one call of the kernel.

    Robots run on every core from ``PARALLEL_MIN_ROBOTS`` robots (one whole run from
    ``PARALLEL_MIN_ROBOTS_ONE_PIECE``); the result is the same bit for bit. Closed-loop
    coordination couples the robots: the kernel then goes tick by tick."""
    n = buffers.scenario.n_robots
    whole = one_piece and not buffers.closed  # a coupled team goes tick by tick anyway
    parallel = n >= (PARALLEL_MIN_ROBOTS_ONE_PIECE if whole else PARALLEL_MIN_ROBOTS)
    kernel = path_following_chunk_parallel if parallel else path_following_chunk
    kernel(k0, k1, buffers.closed, *buffers.args)


def _fused_run(
    scenario: Scenario,
    phase: FloatArray,
    rec_steps: NDArray[np.int64],
    progress: ProgressCallback | None,
) -> SimResult:
    """The default stages' run, compiled: the kernel in chunks of ticks when a progress
    bar is to move, else in one piece."""
    buffers = _start(scenario, phase, rec_steps)
    n_steps = scenario.n_steps
    if progress is None:
        _kernel_chunk(buffers, 0, n_steps + 1, one_piece=True)
        return _finish(buffers)
    for k0, k1 in itertools.pairwise(chunk_bounds(n_steps)):
        _kernel_chunk(buffers, int(k0), int(k1))
        if progress is not None:
            progress(min(int(k1), n_steps), n_steps)
    return _finish(buffers)


def _finish(buffers: _Buffers) -> SimResult:
    wheel_rec, ctl_rec = buffers.wheel_rec, buffers.ctl_rec
    return SimResult(
        scenario=buffers.scenario,
        t=np.asarray(buffers.rec_steps * buffers.scenario.dt_s, dtype=np.float64),
        pose=buffers.pose_rec,
        wheel_speed_rad_s=wheel_rec[..., 0],
        wheel_speed_measured_rad_s=wheel_rec[..., 1],
        wheel_speed_ref_rad_s=wheel_rec[..., 2],
        current_a=wheel_rec[..., 3],
        voltage_v=wheel_rec[..., 4],
        load_torque_n_m=wheel_rec[..., 5],
        extra={
            "odometry_pose": buffers.odom_rec,
            "desired_xy_m": buffers.desired_rec,
            **{name: ctl_rec[:, :, i] for i, name in enumerate(CONTROL_SERIES)},
            **_ideal_link_series(buffers),
        },
    )


def _ideal_link_series(buffers: _Buffers) -> dict[str, FloatArray]:
    """The link series of a fused run: over the ideal link every robot hears every
    broadcast one tick old (none at tick 0); nothing is heard on the clock alone."""
    shape = buffers.ctl_rec.shape[:2]
    age = np.full(shape, buffers.scenario.dt_s if buffers.closed else np.nan)
    age[buffers.rec_steps == 0] = np.nan
    return {"message_age_max_s": age, "stale_robots": np.zeros(shape)}


# --- metrics and figures -------------------------------------------------------------------


_MOVING_M_S = 0.01
"""A robot is under way once its commanded speed exceeds this [m/s]."""
_CAPTURE_M = 0.05
"""A robot has caught its path once it comes this close to it [m]."""


def _peaks(series: FloatArray) -> list[float]:
    """Largest |value| of each robot's column (T, N), over the ticks that hold one: a
    robot's series is NaN until the plant hears its first command (``firefleet team``
    in real time, a robot process late for its first ticks); NaN for a column of none.

    Examples
    --------
    >>> _peaks(np.array([[np.nan, np.nan], [0.5, np.nan], [-2.0, np.nan]]))
    [2.0, nan]
    """
    a = np.abs(np.asarray(series, dtype=float))
    peak = np.where(np.isnan(a), -np.inf, a).max(axis=0)
    return [float(v) if v > -np.inf else math.nan for v in peak]


def path_following_metrics(result: SimResult) -> Metrics:
    """Metrics of a path-following run, on the true poses (per robot: a list).

    ``path_lengths_m``; ``wait_time_s`` (until the commanded speed first exceeds
    1 cm/s: a robot ahead of its path waits, 2.6.2.4); ``capture_time_s`` (first time
    within 5 cm of the path); ``cross_track_rms_m`` (distance to the path, whole run)
    and ``cross_track_rms_after_capture_m`` / ``cross_track_max_after_capture_m`` (from
    capture on); ``final_position_error_m`` (end pose to path end); ``arrival_time_s``
    (first time within ``arrival_radius_m`` of the path's end) and, for the team,
    ``arrival_spread_s``; ``mean_speed_m_s`` (distance driven / time under way until
    arrival); ``longest_path_speed_margin_m_s`` (mean speed of the robot on the longest
    path minus the fastest other's; NaN for one robot); ``omega_peak_rad_s`` and
    ``y_err_peak_m`` (largest commanded |omega| and |y_err| of each robot: the initial
    peaks of Figures 34 and 35); ``longest_path_omega_peak_margin_rad_s`` (the smallest
    omega peak of the other robots minus the longest path's: > 0 when the others turn
    harder, Figure 34) and ``longest_path_y_err_peak_margin_m`` (the longest path's y_err
    peak minus the largest other's: > 0 when it is the largest, Figure 35), NaN for one
    robot; ``sync_distance_m`` (arc length
    from which on every robot's progress along its path, as a share of its length,
    stays within one piece of every other's: the formation of Figures 32 and 36,
    measured on the paths' average length; NaN for one robot); ``odometry_drift_m``
    (distance between dead reckoning and the true pose at the end); ``peak_current_a``;
    ``max_voltage_v``; ``messages_sent``, ``messages_lost``, ``message_age_max_s``
    (:func:`_link_metrics`). Times are NaN where the event never happens.
    """
    cmd = _command(result.scenario)
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
    out: Metrics = {"path_lengths_m": lengths}
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
    omega_peak = _peaks(result.extra["omega_ref_rad_s"])
    y_peak = _peaks(result.extra["y_err_m"])
    out["omega_peak_rad_s"] = omega_peak
    out["y_err_peak_m"] = y_peak
    other_omega = [w for i, w in enumerate(omega_peak) if i != longest]
    other_y = [y for i, y in enumerate(y_peak) if i != longest]
    out["longest_path_omega_peak_margin_rad_s"] = (
        min(other_omega) - omega_peak[longest] if other_omega else math.nan
    )
    out["longest_path_y_err_peak_margin_m"] = (
        y_peak[longest] - max(other_y) if other_y else math.nan
    )
    out["sync_distance_m"] = _sync_distance(progress, cmd.pieces, float(np.mean(lengths)))
    odom = result.extra["odometry_pose"]
    out["odometry_drift_m"] = [float(v) for v in np.hypot(*(odom[-1, :, :2] - xy[-1]).T)]
    out["peak_current_a"] = float(np.abs(result.current_a).max())
    out["max_voltage_v"] = float(np.abs(result.voltage_v).max())
    out.update(_link_metrics(result, cmd))
    return out


def _link_metrics(result: SimResult, cmd: PathFollowing) -> Metrics:
    """``messages_sent`` and ``messages_lost`` (per directed pair, the link's counters;
    over the ideal link every robot hears every other at every tick after the first,
    none lost; nothing on the clock alone) and ``message_age_max_s`` (the oldest value
    the law used; NaN if none)."""
    extra = result.extra
    n = result.pose.shape[1]
    if "messages_sent" in extra:
        sent, lost = float(extra["messages_sent"][-1]), float(extra["messages_lost"][-1])
    else:
        steps = result.scenario.n_steps if cmd.coordination == "closed" else 0
        sent, lost = float(n * (n - 1) * steps), 0.0
    age = extra["message_age_max_s"]
    age_max = float(np.nanmax(age)) if np.any(np.isfinite(age)) else math.nan
    return {"messages_sent": sent, "messages_lost": lost, "message_age_max_s": age_max}


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


def _figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    from firefleet.report.path_following import figures

    return figures(result)


KINDS = (
    TaskKind(
        name="path-following",
        metric_names=(
            "path_lengths_m",
            "wait_time_s",
            "capture_time_s",
            "cross_track_rms_m",
            "cross_track_rms_after_capture_m",
            "cross_track_max_after_capture_m",
            "final_position_error_m",
            "arrival_time_s",
            "arrival_spread_s",
            "mean_speed_m_s",
            "longest_path_speed_margin_m_s",
            "omega_peak_rad_s",
            "y_err_peak_m",
            "longest_path_omega_peak_margin_rad_s",
            "longest_path_y_err_peak_margin_m",
            "sync_distance_m",
            "odometry_drift_m",
            "peak_current_a",
            "max_voltage_v",
            "messages_sent",
            "messages_lost",
            "message_age_max_s",
        ),
        metrics=path_following_metrics,
        figures=_figures,
        decider=Decider(
            init=_init, decide=path_following_decide, series=SERIES, uses_estimate=True
        ),
        fused=_fused_run,
    ),
)
"""The path-following kind."""
