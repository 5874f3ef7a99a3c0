"""The formation runner and its metrics (deliverable section 2.3).

Each tick, for the whole team at once::

    leader path                        c, dc/dt, d2c/dt2          (2,)
    control.formation                  force on each formation point   (N, 2)
    point-mass robots (eq. 5):  + feedforward (B + k_d) dc/dt + M d2c/dt2
        -> models.mass_damper          exact step for the held force
    diff-drive robots:  look-ahead point p = (x, y) + l (cos th, sin th)
        u = dc/dt + f / (B + k_d)      (eq. 5 at its terminal velocity), |u| <= v_max
        v = u . (cos th, sin th),  omega = u . (-sin th, cos th) / l
        -> models.kinematics.body_to_wheels -> sim.drive (the wheel stack: control.pid
        -> models.motor -> models.kinematics.diff_drive_step, models.encoder)

The feedforward makes the formation's dynamics in the leader's frame those of a fixed
leader (the damping acts on the velocity relative to the leader), so the formation
travels with a moving leader. A diff-drive robot's formation point is its look-ahead
point, a point ``l`` ahead of the axle centre (Lawton, Beard and Young, "A decentralized
approach to formation maneuvers", IEEE Trans. Robotics and Automation 19(6), 2003):
its velocity is any u the wheels can give, so the point-mass law carries over.

Stability. Each step holds the force over ``dt_s`` (a sampled controller),
and the exact step of eq. 5 under a held restoring force of stiffness kappa is stable
only for kappa below about ``2 (B + k_d) / dt_s`` (400 N/m at the deliverable's 2 N s/m
and 10 ms; :func:`substeps`). What made teams diverge, measured: with eq. 6 uncapped
(the README's keys) 100 robots drawn up to 14 m from a 10 m circle start with an
attraction of 909 N (r (r^2 - alpha^2)), meet within 0.08 s, and the contact force at
its 1 mm gap floor (4e7 N, stiffness ~3 eta / g^4) and the Coulomb force (2 k_r / r^3
per pair) are far beyond the bound: positions run off to hundreds of km (the same for
20 robots on the 3 m circle, from 280 N at the corners). With the attraction capped,
the first regular law (tangential Coulomb) still kicked robots apart (a 5e4 N contact
at 0.7 s) and left robots 3.5 m inside the circle; the deliverable's law, 3.7 m (a ring
of 100 charges walls late robots out: its field near the ring, ~2 k_r N / (2 pi alpha
delta), beats a 10 N attraction). The remedies: the force's stiffness is bounded every
step (:func:`firefleet.control.formation.stiffness_bound`) and the step divided into
:func:`substeps` when needed; the regular law spaces by angular neighbours (stiffness
2 K_s whatever N); the attraction is capped by default; a team that cannot stand on the
circle is refused; and a run that still leaves every bound stops with
:class:`FormationDivergedError` (no result is written).

A failed robot stops where it is (a point mass is held; a diff-drive robot's wheel
references drop to 0) and leaves the formation: it carries no charge and has no place
on the circle, but its body stays, and the contact and obstacle forces see it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.formation import contact_pairs, formation_force_and_stiffness
from firefleet.errors import InputError
from firefleet.models.kinematics import body_to_wheels
from firefleet.models.mass_damper import MassDamperParams, mass_damper_step
from firefleet.scenarios.schema import Formation, LeaderPath, Scenario
from firefleet.sim._formation_link import Views, outbox, predicted_views, view_forces
from firefleet.sim._formation_metrics import RADIUS_BAND, formation_metrics, spacing_error_deg
from firefleet.sim._link_stage import link_impaired
from firefleet.sim.drive import (
    DriveState,
    discretise_drive,
    drive_init,
    drive_step,
    encoder_phase,
    speed_control,
)
from firefleet.sim.link import LinkModel
from firefleet.sim.result import SimResult

__all__ = [
    "DIVERGENCE_FACTOR",
    "MAX_SUBSTEPS",
    "RADIUS_BAND",
    "FormationDivergedError",
    "formation_metrics",
    "leader_trajectory",
    "simulate_formation",
    "spacing_error_deg",
    "start_positions",
    "substeps",
]

Progress = Callable[[int, int], None]
Law = tuple[FloatArray, float]


_MAX_PLACEMENT_ROUNDS = 10_000

_SKIN_M = 0.5
"""Skin of the contact pairs' Verlet list [m] (rebuilt when a robot moved half of it)."""

MAX_SUBSTEPS = 10_000
"""Most sub-steps one step of ``dt_s`` may be divided into (a stiffer force: an error)."""

DIVERGENCE_FACTOR = 100.0
"""A robot farther from the leader than this times (alpha + the farthest start from the
leader + a body radius) has diverged: the run stops with :class:`FormationDivergedError`."""


class FormationDivergedError(InputError):
    """The formation's forces or positions grew without bound: no results are written.

    An :class:`~firefleet.errors.InputError` (the command line prints its one-line
    message and exits with status 2): the scenario's gains, radius or time step cannot
    give a bounded run.
    """


def _command(scenario: Scenario) -> Formation:
    cmd = scenario.command
    if not isinstance(cmd, Formation):
        raise InputError(f"not a formation scenario: command kind {cmd.kind!r}")
    return cmd


def leader_trajectory(
    path: LeaderPath, t_s: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The virtual leader's position, velocity and acceleration at times ``t_s``.

    The leader waits at the first waypoint until ``start_s``, then runs along the
    polyline with a trapezoidal speed profile (``accel_m_s2`` up to ``speed_m_s``,
    cruise, ``accel_m_s2`` down to rest at the last waypoint; a triangle if the path is
    too short to reach the speed).

    Parameters
    ----------
    path : LeaderPath
    t_s : ndarray, shape (T,)
        Times [s].

    Returns
    -------
    xy_m, v_m_s, a_m_s2 : ndarray, shape (T, 2)
        Position [m], velocity [m/s] and acceleration [m/s^2]. The turn at a corner
        is instantaneous: the velocity changes direction in one step, with no
        acceleration reported, so point-mass robots swing out at a corner (their
        feedforward cannot give a velocity step); diff-drive robots, whose formation
        point follows a velocity command, take it in their stride.
    """
    t = np.asarray(t_s, dtype=np.float64)
    pts = np.array(path.waypoints_m, dtype=np.float64).reshape(-1, 2)
    seg = np.diff(pts, axis=0)
    seg_len = np.sqrt((seg * seg).sum(axis=1))
    keep = seg_len > 0
    seg, seg_len, starts = seg[keep], seg_len[keep], pts[:-1][keep]
    total = float(seg_len.sum())
    xy = np.repeat(pts[:1], t.size, axis=0)
    vel = np.zeros((t.size, 2))
    acc = np.zeros((t.size, 2))
    if total == 0.0 or path.speed_m_s == 0.0:
        return xy, vel, acc
    a = path.accel_m_s2
    v = min(path.speed_m_s, math.sqrt(a * total))  # peak speed (triangle if short)
    t_acc = v / a
    d_acc = 0.5 * v * t_acc
    t_cruise = (total - 2.0 * d_acc) / v
    tau = np.clip(t - path.start_s, 0.0, None)
    t_end = 2.0 * t_acc + t_cruise
    tau = np.minimum(tau, t_end)
    up = tau < t_acc
    down = tau > t_acc + t_cruise
    td = tau - t_acc - t_cruise
    s = np.where(
        up,
        0.5 * a * tau * tau,
        np.where(
            down, d_acc + v * t_cruise + v * td - 0.5 * a * td * td, d_acc + v * (tau - t_acc)
        ),
    )
    sdot = np.where(up, a * tau, np.where(down, v - a * td, v))
    sddot = np.where(up, a, np.where(down, -a, 0.0))
    moving = (t > path.start_s) & (t - path.start_s < t_end)
    sdot = np.where(moving, sdot, 0.0)
    sddot = np.where(moving, sddot, 0.0)
    s = np.clip(s, 0.0, total)
    cum = np.r_[0.0, np.cumsum(seg_len)]
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, seg_len.size - 1)
    u = seg / seg_len[:, None]
    xy = starts[i] + u[i] * (s - cum[i])[:, None]
    vel = u[i] * sdot[:, None]
    acc = u[i] * sddot[:, None]
    return xy, vel, acc


def start_positions(scenario: Scenario, rng: np.random.Generator) -> FloatArray:
    """Start poses (N, 3): the scenario's, or drawn about the leader with ``scatter_m``.

    With ``scatter_m > 0`` the x, y of each robot are drawn uniformly in the square of
    half-width ``scatter_m`` about the leader's start, redrawing (all at once) the
    robots that overlap another robot or an obstacle (bodies closer than
    ``contact_range_m``), until none does; headings stay the poses'.

    Raises
    ------
    InputError
        If the robots cannot be placed (a square too small for the team).
    """
    cmd = _command(scenario)
    poses = scenario.initial_poses
    if cmd.scatter_m == 0:
        return poses
    n = poses.shape[0]
    centre = np.array(cmd.leader.waypoints_m[0], dtype=np.float64)
    sep = 2.0 * cmd.robot_radius_m + cmd.contact_range_m
    obs = np.array([(o.x_m, o.y_m) for o in cmd.obstacles], dtype=np.float64).reshape(-1, 2)
    obs_r = np.array([o.radius_m for o in cmd.obstacles], dtype=np.float64)
    xy = centre + rng.uniform(-cmd.scatter_m, cmd.scatter_m, size=(n, 2))
    for _ in range(_MAX_PLACEMENT_ROUNDS):
        d = np.sqrt(((xy[:, None, :] - xy[None, :, :]) ** 2).sum(axis=2))
        np.fill_diagonal(d, np.inf)
        # of each too-close pair, redraw the later robot
        bad = np.triu(d < sep).any(axis=0)
        if obs.shape[0]:
            do = np.sqrt(((xy[:, None, :] - obs[None, :, :]) ** 2).sum(axis=2))
            bad |= (do - obs_r[None, :] < cmd.robot_radius_m + cmd.contact_range_m).any(axis=1)
        if not bad.any():
            out = poses.copy()
            out[:, :2] = xy
            return out
        xy[bad] = centre + rng.uniform(-cmd.scatter_m, cmd.scatter_m, size=(int(bad.sum()), 2))
    raise InputError(
        f"command.scatter_m = {cmd.scatter_m} m: cannot place {n} robots "
        f"{sep:g} m apart in the square"
    )


def substeps(stiffness_n_m: float, damping_n_s_m: float, dt_s: float) -> int:
    """Sub-steps of a ``dt_s`` step that keep the held-force point-mass step stable.

    The exact step of eq. 5 under a force held over a step ``h`` (zero-order hold),
    applied to a restoring force of stiffness ``kappa``, is stable for ``kappa`` below
    ``c (1 - e) / (tau (1 - e) - e h)`` (``e = exp(-h / tau)``, ``tau = M / c``; the
    determinant of its 2 x 2 transition matrix below 1), which is ``2 c / h`` to first
    order: 400 N/m for the deliverable's ``c = B + k_d = 2 N s/m`` and ``h = 10 ms``.
    Dividing the step into ``n = ceil(kappa h / c)`` keeps ``kappa`` below half of it.

    Parameters
    ----------
    stiffness_n_m : float
        A bound on the force's stiffness [N/m]
        (:func:`firefleet.control.formation.stiffness_bound`).
    damping_n_s_m : float
        c = B + k_d [N s/m].
    dt_s : float
        The step [s].

    Returns
    -------
    int
        n >= 1.

    Raises
    ------
    FormationDivergedError
        If the stiffness is not finite or needs more than :data:`MAX_SUBSTEPS`.

    Examples
    --------
    >>> substeps(18.0, 2.0, 0.01), substeps(200.0, 2.0, 0.01), substeps(1000.0, 2.0, 0.01)
    (1, 1, 5)
    """
    need = stiffness_n_m * dt_s / damping_n_s_m
    if not need <= MAX_SUBSTEPS:  # also NaN
        raise FormationDivergedError(
            f"the formation force's stiffness reached {stiffness_n_m:.3g} N/m: a "
            f"{dt_s} s step would need more than {MAX_SUBSTEPS:,} sub-steps to stay "
            "stable (robots too close, or attraction_gain * alpha_m^2 too large)"
        )
    return max(1, math.ceil(need))


def simulate_formation(
    scenario: Scenario, rec_steps: NDArray[np.int64], progress: Progress | None
) -> SimResult:
    """Run a formation scenario (see the module notes).

    Parameters
    ----------
    scenario : Scenario
        With a :class:`~firefleet.scenarios.schema.Formation` command.
    rec_steps : ndarray of int, shape (T,)
        The steps to record, increasing, from 0 to ``scenario.n_steps``.
    progress : callable, optional
        ``progress(done, total)``, about a hundred times a run.

    Returns
    -------
    SimResult
        ``pose`` (T, N, 3) (a point mass's heading is its direction of motion), wheel
        arrays (T, N, 2) for diff-drive robots and (T, N, 0) for point masses, and in
        ``extra``: ``leader_xy_m`` (T, 2) [m], ``formation_xy_m`` (T, N, 2) (the points
        the law moves: the robot itself, or its look-ahead point), ``robot_active``
        (T, N) (1 while in the team, 0 after a failure) and ``substeps`` (T,) (the
        sub-steps the step from that sample took, :func:`substeps`; 1 for diff-drive
        robots).

    Raises
    ------
    InputError
        For a team that does not fit the command (see ``Formation.check_team``).
    FormationDivergedError
        If a robot ends farther than :data:`DIVERGENCE_FACTOR` times the formation's
        size from the leader, or the force is not finite or too stiff for
        :data:`MAX_SUBSTEPS`: nothing is returned.
    """
    cmd = _command(scenario)
    cmd.check_team(scenario.n_robots, scenario.duration_s)
    rng = np.random.default_rng(scenario.seed)
    pose = start_positions(scenario, rng)
    n, dt, n_steps = scenario.n_robots, scenario.dt_s, scenario.n_steps
    params = cmd.formation_params
    steps_t = np.arange(n_steps + 1, dtype=np.float64) * dt
    leader, leader_v, leader_a = leader_trajectory(cmd.leader, steps_t)
    obstacles = None
    if cmd.obstacles:
        obstacles = (
            np.array([(o.x_m, o.y_m) for o in cmd.obstacles], dtype=np.float64),
            np.array([o.radius_m for o in cmd.obstacles], dtype=np.float64),
        )
    damping = cmd.damping_n_s_m + cmd.kd_n_s_m
    failed = np.zeros(n, dtype=bool)
    fail_step = n_steps + 1
    if cmd.failure is not None:
        failed[cmd.failure.robot - 1] = True
        fail_step = math.ceil(cmd.failure.time_s / dt - 1e-9)
    diff_drive = cmd.robot_model == "diff-drive"
    look = cmd.look_ahead_m if diff_drive else 0.0
    body = cmd.body_radius_m
    start_far = float(np.sqrt(((pose[:, :2] - leader[0]) ** 2).sum(axis=1)).max())
    far_m = DIVERGENCE_FACTOR * (cmd.alpha_m + start_far + body)

    def contact_reach(n_team: int) -> float:
        # the regular polygon's bodies are side - 2 R apart: a contact range beyond that
        # would push the robots off the circle at the polygon itself
        if n_team < 2:
            return cmd.contact_range_m
        side = 2.0 * cmd.alpha_m * math.sin(math.pi / n_team)
        return min(cmd.contact_range_m, max(side - 2.0 * body, 1e-3))

    n_rec = rec_steps.size
    n_wheels = 2 if diff_drive else 0
    rec_pose = np.empty((n_rec, n, 3))
    rec_point = np.empty((n_rec, n, 2))
    rec_active = np.empty((n_rec, n))
    rec_substeps = np.empty(n_rec)
    wheels = {
        k: np.empty((n_rec, n, n_wheels))
        for k in ("speed", "measured", "ref", "current", "voltage", "load")
    }
    report_every = max(1, n_steps // 100)

    md = MassDamperParams(
        mass_kg=cmd.mass_kg, damping_n_s_m=cmd.damping_n_s_m, kd_n_s_m=cmd.kd_n_s_m
    )
    state = np.concatenate([pose[:, :2], np.zeros((n, 2))], axis=1)
    # the diff-drive wheel stack (its state only for diff-drive robots)
    enc = scenario.encoder
    stack = discretise_drive(scenario.robot, scenario.motor, scenario.speed_pid, enc, dt)
    drive: DriveState | None = None
    if diff_drive:
        drive = drive_init(pose, encoder_phase(enc, n, rng), stack)
    w_max = cmd.max_speed_m_s / scenario.robot.wheel_radius_m
    zero_load = np.zeros((n, 2))

    # the neighbours over an impaired link (sim._formation_link); ideal: the true points
    link = None
    if link_impaired(scenario):
        link = LinkModel.from_spec(scenario.link, seed=scenario.seed)
    link_state = (link or LinkModel.from_spec(None)).init(n, dt)
    timeout_s = link.params.timeout_s if link is not None else math.inf
    sent: dict[str, FloatArray] = {}
    last_point: FloatArray | None = None
    inbox: dict[str, FloatArray] = {}
    link_rec = {key: np.zeros((n_rec, n)) for key in ("message_age_max_s", "stale_robots")}
    count_rec = {key: np.zeros(n_rec) for key in ("messages_sent", "messages_lost")}

    # the regular law's contact pairs: a Verlet list, rebuilt when a robot moved _SKIN_M / 2
    built_at: list[FloatArray] = []
    built_pairs: list[NDArray[np.intp]] = []

    def candidates(point: FloatArray, reach: float) -> NDArray[np.intp] | None:
        if cmd.law != "regular":
            return None
        if built_at:
            moved = point - built_at[0]
            if float((moved * moved).sum(axis=1).max()) < (0.5 * _SKIN_M) ** 2:
                return built_pairs[0]
        built_at[:] = [point.copy()]
        built_pairs[:] = [contact_pairs(point, 2.0 * body + reach + _SKIN_M)]
        return built_pairs[0]

    def law(
        point: FloatArray, centre: FloatArray, active: BoolArray, views: Views | None = None
    ) -> tuple[FloatArray, float]:
        reach = contact_reach(int(active.sum()))

        def at(pos: FloatArray, act: BoolArray, pairs: NDArray[np.intp] | None) -> Law:
            return formation_force_and_stiffness(
                pos,
                centre,
                params,
                law=cmd.law,
                active=act,
                obstacles=obstacles,
                body_radius_m=body,
                contact_range_m=reach,
                pairs=pairs,
            )

        if views is None:
            force, stiff = at(point, active, candidates(point, reach))
        else:  # each robot's law on its own view of the team
            force, stiff = view_forces(views, active, lambda pos, act, row: at(pos, act, None))
        if not np.isfinite(force).all():
            raise FormationDivergedError(
                f"the formation force is not finite at t = {k * dt:.3f} s: the run "
                "diverged (a smaller dt_s or smaller gains)"
            )
        return force, stiff

    row = 0
    all_in = np.ones(n, dtype=bool)
    for k in range(n_steps + 1):
        active = ~failed if k >= fail_step else all_in
        heading = pose[:, 2]
        if diff_drive:
            point = pose[:, :2] + look * np.stack([np.cos(heading), np.sin(heading)], axis=1)
        else:
            point = state[:, :2]
        gone = point - leader[k]
        far2 = float((gone * gone).sum(axis=1).max())
        if not far2 <= far_m * far_m:  # also NaN
            far = math.sqrt(far2)
            raise FormationDivergedError(
                f"the formation diverged at t = {k * dt:.3f} s: a robot is {far:.3g} m from "
                f"the leader, more than {DIVERGENCE_FACTOR:g} x (alpha_m + its farthest "
                f"start + a body radius) = {far_m:.3g} m"
            )
        views = None
        if link is not None:
            inbox, link_state = link.exchange(link_state, sent, k * dt, pose)
            views = predicted_views(inbox, point, k, dt, timeout_s)
            if diff_drive:  # the point's velocity, from its last tick
                vel = np.zeros_like(point) if last_point is None else (point - last_point) / dt
                last_point = point
            else:
                vel = state[:, 2:]
            sent = outbox(point, vel)
        force, stiff = law(point, leader[k], active, views)
        n_sub = 1
        if diff_drive:
            u = leader_v[k] + force / damping
            speed_u = np.sqrt((u * u).sum(axis=1))
            u *= np.minimum(1.0, cmd.max_speed_m_s / np.maximum(speed_u, 1e-300))[:, None]
            c, s = np.cos(heading), np.sin(heading)
            v = c * u[:, 0] + s * u[:, 1]
            omega = (-s * u[:, 0] + c * u[:, 1]) / look
            ref = body_to_wheels(v, omega, scenario.robot)
            # keep the turn: scale both wheels down together to the speed limit
            peak = np.abs(ref).max(axis=1)
            ref *= np.minimum(1.0, w_max / np.maximum(peak, 1e-300))[:, None]
            ref[~active] = 0.0
            assert drive is not None
            drive, voltage = speed_control(drive, ref, stack)
        else:
            n_sub = substeps(stiff, damping, dt)
        if row < n_rec and rec_steps[row] == k:
            rec_pose[row] = pose
            rec_point[row] = point
            rec_active[row] = active
            rec_substeps[row] = n_sub
            if views is not None:
                assert link is not None
                _, fresh, age = views
                used = fresh & ~np.eye(n, dtype=bool)
                oldest = np.where(used, age, -np.inf).max(axis=1)
                link_rec["message_age_max_s"][row] = np.where(used.any(axis=1), oldest, np.nan)
                link_rec["stale_robots"][row] = (~fresh).sum(axis=1)
                counts = link.counters(link_state)
                for key in count_rec:
                    count_rec[key][row] = counts[key]
            if diff_drive:
                assert drive is not None
                for key, arr in (
                    ("speed", drive.speed_rad_s),
                    ("measured", drive.measured_rad_s),
                    ("ref", ref),
                    ("current", drive.current_a),
                    ("voltage", voltage),
                    ("load", zero_load),
                ):
                    wheels[key][row] = arr
            row += 1
        if k == n_steps:
            break
        if diff_drive:
            assert drive is not None
            drive = drive_step(drive, voltage, stack, load_torque_n_m=zero_load)
            pose = drive.pose
        else:
            feed = damping * leader_v[k] + cmd.mass_kg * leader_a[k]
            held = state[~active] if active is not all_in else None
            h = dt / n_sub
            for j in range(n_sub):
                if j > 0:  # the force at the sub-step, the leader moved on linearly
                    centre = leader[k] + (j / n_sub) * (leader[k + 1] - leader[k])
                    if views is not None:
                        views = predicted_views(inbox, state[:, :2], k, dt, timeout_s, j * h)
                    force, _ = law(state[:, :2], centre, active, views)
                force[active] += feed
                state = mass_damper_step(state, force, h, md)
            if held is not None:  # a failed point mass is held where it stopped
                state[~active] = np.concatenate([held[:, :2], np.zeros((held.shape[0], 2))], axis=1)
            vx, vy = state[:, 2], state[:, 3]
            moving = vx * vx + vy * vy > 1e-12
            pose = np.column_stack([state[:, :2], np.where(moving, np.arctan2(vy, vx), pose[:, 2])])
        if progress is not None and (k + 1) % report_every == 0:
            progress(k + 1, n_steps)
    if progress is not None:
        progress(n_steps, n_steps)

    return SimResult(
        scenario=scenario,
        t=np.asarray(rec_steps * dt, dtype=np.float64),
        pose=rec_pose,
        wheel_speed_rad_s=wheels["speed"],
        wheel_speed_measured_rad_s=wheels["measured"],
        wheel_speed_ref_rad_s=wheels["ref"],
        current_a=wheels["current"],
        voltage_v=wheels["voltage"],
        load_torque_n_m=wheels["load"],
        extra={
            "leader_xy_m": leader[rec_steps],
            "formation_xy_m": rec_point,
            "robot_active": rec_active,
            "substeps": rec_substeps,
            **(link_rec if link is not None else {}),
            **(count_rec if link is not None else {}),
        },
    )
