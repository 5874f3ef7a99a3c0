"""Navigation through a building (issue 14): each robot of the team to its own goal.

For the whole team, on the world loop (:mod:`firefleet.sim.loop`), with the kind's own
stages (:func:`navigate_stages`)::

    world            the scenario's map (static), the load step on the motors
    sensors          the range sensors of ``sensors:`` (firefleet.sim.ranging.RangeSensors;
                     other robots are obstacles), none without the key
    link             ideal: each robot hears its teammates' estimated positions
    estimation       by ``localisation``: odometry (dead reckoning), Monte Carlo
                     localisation on the known map from a uniform prior, or grid SLAM
                     (firefleet.estimation.grid); the odometry is kept alongside
    decide           the team navigation controller (firefleet.control.navigation:
                     A* on the inflated map -> smoothed path -> the deliverable's fuzzy
                     follower -> give way -> dynamic window on the sensed obstacles)
                     -> (v, omega) -> wheel references (eqs. 1-4)
    drive            the wheel stack

The run ends at ``duration_s``, or earlier once no robot is under way any more (each
has arrived, or found its goal unreachable): an unreachable goal is reported by its
metrics (``goal_reached`` 0), never waited for.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.models.kinematics import RobotGeometry, body_to_wheels
from firefleet.scenarios.schema import Navigate, Scenario
from firefleet.sim.drive import DriveStack, DriveState
from firefleet.sim.kinds._navigate_metrics import METRIC_NAMES, navigate_metrics
from firefleet.sim.loop import (
    DecideInputs,
    Decider,
    Messages,
    NoSensors,
    Odometry,
    OdometryState,
    Sensors,
    Stages,
    WheelCommand,
    default_stages,
)
from firefleet.sim.registry import TaskKind
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid

__all__ = [
    "KINDS",
    "NavigateParams",
    "NavigateState",
    "Tracked",
    "navigate_decide",
    "navigate_stages",
    "reading_bearings",
    "reading_limits",
    "wander",
]

RANGE_READINGS = ("ultrasonic_range_m", "lidar_range_m", "stereo_scan_m")
"""The range sensors' readings, by the names the sensors stage gives them."""


def _command(scenario: Scenario) -> Navigate:
    cmd = scenario.command
    if not isinstance(cmd, Navigate):
        raise InputError(f"command.kind: expected navigate, got {cmd.kind!r}")
    return cmd


def _grid(scenario: Scenario) -> OccupancyGrid:
    if scenario.world is None:
        raise InputError("world.map: a navigate command needs a map")
    return scenario.world.grid()


# --- stages ------------------------------------------------------------------------------


LOCALISED_SPREAD_M = 0.5
"""A robot counts as localised once its particle cloud's position spread (the RMS
distance of the particles from their mean) falls below this [m]; until then the kind
does not trust the estimate to plan with."""


@dataclass(frozen=True)
class TrackedState:
    """The odometry, the localisation filter's state, and which robots are localised."""

    odometry: OdometryState
    inner: Any
    localised: np.ndarray[Any, np.dtype[np.bool_]]


def _localised(inner: Any, state: Any, n: int) -> np.ndarray[Any, np.dtype[np.bool_]]:
    """Whether each robot's particle cloud is tight (always, without particles)."""
    if inner is None or not hasattr(inner, "particles"):
        return np.ones(n, dtype=bool)
    cloud = np.asarray(inner.particles(state))[..., :2]  # (N, P, 2), NaN-padded
    mean = np.nanmean(cloud, axis=1, keepdims=True)
    spread = np.sqrt(np.nanmean(np.sum((cloud - mean) ** 2, axis=-1), axis=1))
    out: np.ndarray[Any, np.dtype[np.bool_]] = spread < LOCALISED_SPREAD_M
    return out


@dataclass(frozen=True, eq=False)
class Tracked:
    """An estimation stage that keeps dead reckoning alongside a localisation filter.

    ``pose`` is the filter's estimate (the odometry's without one); ``series`` gives
    ``odometry_pose`` and ``estimated_pose`` (N, 3) each tick, and ``final`` the team's
    ``occupancy`` map (H, W) where the filter maps.

    Attributes
    ----------
    inner : Estimation or None
        The localisation filter (``firefleet.estimation.grid.MclEstimation`` or
        ``GridSlamEstimation``); None: odometry only.
    """

    inner: Any = None

    def init(self, pose: FloatArray, drive: DriveState) -> TrackedState:
        """Odometry and filter at the start."""
        inner = self.inner.init(pose, drive) if self.inner is not None else None
        n = pose.shape[0]
        return TrackedState(Odometry().init(pose, drive), inner, _localised(self.inner, inner, n))

    def step(
        self,
        state: TrackedState,
        drive: DriveState,
        stack: DriveStack,
        readings: Messages,
    ) -> TrackedState:
        """Both moved by the counts since the last tick (the filter also by the scans)."""
        odometry = Odometry().step(state.odometry, drive, stack, readings)
        inner = state.inner
        localised = state.localised
        if self.inner is not None:
            inner = self.inner.step(inner, drive, stack, readings)
            if inner is not state.inner:
                localised = _localised(self.inner, inner, localised.size)
        return TrackedState(odometry, inner, localised)

    def _estimate(self, state: TrackedState) -> FloatArray:
        if self.inner is None:
            return state.odometry.pose
        pose: FloatArray = self.inner.pose(state.inner)
        return pose

    def pose(self, state: TrackedState) -> FloatArray:
        """The filter's estimate, or the odometry (N, 3); NaN for a robot not localised
        yet (its particle cloud wider than :data:`LOCALISED_SPREAD_M`)."""
        return np.where(state.localised[:, None], self._estimate(state), np.nan)

    def series(self, state: TrackedState) -> Messages:
        """``odometry_pose`` and ``estimated_pose`` (N, 3) each, and ``localised`` (N,)."""
        return {
            "odometry_pose": state.odometry.pose,
            "estimated_pose": self._estimate(state),
            "localised": state.localised.astype(float),
        }

    def final(self, state: TrackedState) -> Messages:
        """The team's map (``occupancy``, probability (H, W)) where the filter maps."""
        if self.inner is None or not hasattr(self.inner, "occupancy"):
            return {}
        return {"occupancy": np.asarray(self.inner.occupancy(state.inner), dtype=np.float32)}


def _sensor_params(scenario: Scenario) -> dict[str, Any]:
    """The range sensors of ``sensors:`` as ``firefleet.sim.ranging`` parameters, by the
    name of their reading."""
    spec = scenario.sensors
    if spec is None:
        return {}
    from firefleet.sim.ranging import LidarParams, UltrasonicParams

    out: dict[str, Any] = {}
    if spec.ultrasonic is not None:
        u = spec.ultrasonic
        out["ultrasonic_range_m"] = UltrasonicParams(
            count=u.count, fov_deg=u.fov_deg, max_range_m=u.max_range_m, noise_m=u.noise_m
        )
    if spec.lidar is not None:
        li = spec.lidar
        out["lidar_range_m"] = LidarParams(
            beams=li.beams, fov_deg=li.fov_deg, max_range_m=li.max_range_m, noise_m=li.noise_m
        )
    return out


def _sensors(scenario: Scenario, grid: OccupancyGrid, rng: np.random.Generator) -> Sensors:
    """The range sensors of ``sensors:`` (none without the key)."""
    params = _sensor_params(scenario)
    if not params:
        return NoSensors()
    from firefleet.sim.ranging import RangeSensors

    return RangeSensors(
        grid,
        _command(scenario).robot_radius_m,
        ultrasonic=params.get("ultrasonic_range_m"),
        lidar=params.get("lidar_range_m"),
        dt_s=scenario.dt_s,
        rng=rng,
    )


def _localisation(scenario: Scenario, grid: OccupancyGrid, rng: np.random.Generator) -> Any:
    """The filter of ``localisation`` (None for odometry), on the scan it prefers: the
    lidar where the robots carry one, else the ultrasonic ring."""
    cmd = _command(scenario)
    if cmd.localisation == "odometry":
        return None
    from firefleet.estimation.grid import GridSlamEstimation, MclEstimation

    scanners = _scanners(scenario)  # the schema checks a filter has one
    reading = "lidar_range_m" if "lidar_range_m" in scanners else "ultrasonic_range_m"
    scanner = scanners[reading]
    seed = int(rng.integers(2**31))
    if cmd.localisation == "mcl":
        return MclEstimation(grid, scanner, reading=reading, start="global", seed=seed)
    return GridSlamEstimation(grid, scanner, reading=reading, seed=seed)


def navigate_stages(scenario: Scenario, decider: Decider, rng: np.random.Generator) -> Stages:
    """The navigate kind's stages: the default world and link (:func:`default_stages`:
    the load step, motor faults, the scenario's link), the range sensors on the map, and
    the localisation of ``command.localisation`` beside the odometry (:class:`Tracked`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.kinds.navigate import navigate_stages
    >>> from firefleet.sim.registry import task_kind
    >>> scenario = load_scenario("nav-doorway")
    >>> stages = navigate_stages(scenario, task_kind("navigate").decider, np.random.default_rng(0))
    >>> stages.names()["estimation"]
    'Tracked'
    """
    grid = _grid(scenario)
    return dataclasses.replace(
        default_stages(scenario, decider),  # the world's load and faults, the link
        sensors=_sensors(scenario, grid, rng),
        estimation=Tracked(_localisation(scenario, grid, rng)),
    )


# --- the decision --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class NavigateParams:
    """The constants of the team's decision.

    Attributes
    ----------
    navigation : NavigationParams
        The navigation controller's (firefleet.control.navigation).
    geometry : RobotGeometry
        Nominal geometry, for the wheel references.
    bearings_rad : dict of str to ndarray
        Each range reading's beam bearings relative to the heading [rad], (B,).
    period_s : float
        The navigation controller runs every ``period_s`` (10 Hz, a lidar's scan rate);
        the wheel references hold in between.
    """

    navigation: Any
    geometry: RobotGeometry
    bearings_rad: dict[str, FloatArray]
    grid: OccupancyGrid
    goals_m: FloatArray
    period_s: float = 0.1
    wander_speed_m_s: float = 0.2


@dataclass(frozen=True, eq=False)
class NavigateState:
    """The navigation controller's state and the command it holds until its next run."""

    navigation: Any
    v_m_s: FloatArray
    omega_rad_s: FloatArray
    next_s: float
    planned: bool = True


_UNDER_WAY = ("moving", "waiting")
"""Navigation statuses of a robot still on its way (the others are final)."""


def _scanners(scenario: Scenario) -> dict[str, Any]:
    """The beams of each range reading as the filters take them
    (``firefleet.estimation.grid.Scanner``), the sensors' own bearings."""
    params = _sensor_params(scenario)
    if not params:
        return {}
    from firefleet.estimation.grid import Scanner

    return {name: Scanner(p.bearings_rad, p.max_range_m) for name, p in params.items()}


def reading_bearings(scenario: Scenario) -> dict[str, FloatArray]:
    """Each range reading's beam bearings relative to the heading [rad], (B,), by name.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.kinds.navigate import reading_bearings
    >>> {k: v.shape for k, v in reading_bearings(load_scenario("nav-mcl-office")).items()}
    {'ultrasonic_range_m': (8,)}
    """
    return {name: np.asarray(s.bearings_rad) for name, s in _scanners(scenario).items()}


def reading_limits(scenario: Scenario) -> dict[str, float]:
    """Each range reading's maximum range [m], by name."""
    return {name: float(s.max_range_m) for name, s in _scanners(scenario).items()}


def _init(scenario: Scenario) -> tuple[Any, NavigateParams]:
    from firefleet.control.navigation import NavigationParams, navigation_init

    cmd = _command(scenario)
    nav = NavigationParams(robot_radius_m=cmd.robot_radius_m, goal_tolerance_m=cmd.goal_tolerance_m)
    state = navigation_init(_grid(scenario), scenario.initial_poses, np.array(cmd.goals_m), nav)
    zero = np.zeros(scenario.n_robots)
    grid = _grid(scenario)
    goals = np.array(cmd.goals_m, dtype=float)
    params = NavigateParams(nav, scenario.robot, reading_bearings(scenario), grid, goals)
    return NavigateState(state, zero, zero, 0.0, planned=cmd.localisation != "mcl"), params


def wander(
    ranges_m: FloatArray, bearings_rad: FloatArray, speed_m_s: float
) -> tuple[FloatArray, FloatArray]:
    """A robot that does not know where it is yet explores: it turns toward its most
    open bearing and drives at ``speed_m_s`` scaled down by the free distance ahead
    (stopping 0.5 m from an obstacle in its forward sector of +-45 degrees).

    Parameters
    ----------
    ranges_m : ndarray, shape (N, B)
        Range readings [m] (``inf`` for no return).
    bearings_rad : ndarray, shape (B,)
        Their bearings from the heading [rad].
    speed_m_s : float
        Cruising speed [m/s].

    Returns
    -------
    v_m_s, omega_rad_s : ndarray, shape (N,)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.kinds.navigate import wander
    >>> b = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2])
    >>> v, w = wander(np.array([[0.4, 3.0, 1.0, 1.0]]), b, 0.2)  # a wall ahead, open left
    >>> float(v[0]), float(w[0]) > 0
    (0.0, True)
    """
    r = np.where(np.isfinite(ranges_m), ranges_m, 10.0)
    wrapped = np.angle(np.exp(1j * bearings_rad))
    ahead = np.abs(wrapped) <= np.pi / 4
    front = r[:, ahead].min(axis=1) if np.any(ahead) else np.full(r.shape[0], 10.0)
    best = wrapped[np.argmax(r - 0.2 * np.abs(wrapped), axis=1)]
    omega = np.clip(1.5 * best, -1.0, 1.0)
    v = speed_m_s * np.clip((front - 0.5) / 1.0, 0.0, 1.0) * np.cos(np.clip(best, -1.5, 1.5))
    return np.maximum(v, 0.0), omega


def navigate_decide(
    state: NavigateState, inputs: DecideInputs, params: NavigateParams, dt_s: float
) -> tuple[NavigateState, WheelCommand]:
    """The team's decision at a tick: the navigation controller's (v, omega) as wheel
    references, from the pose estimate, the range readings and the teammates' positions.

    Parameters
    ----------
    state : NavigateState
        The navigation controller's state and the command it holds.
    inputs : DecideInputs
        ``pose_estimate`` (N, 3), the range readings, and the inbox's ``xy_m`` (N, 2):
        the positions the team broadcast at the last tick.
    params : NavigateParams
    dt_s : float
        Control period [s].

    Returns
    -------
    state : NavigateState
    command : WheelCommand
        Wheel references (N, 2) [rad/s]; ``done`` once no robot is under way.
    """
    from firefleet.control.navigation import NavigationInputs, navigation_init, navigation_step

    pose = inputs.pose_estimate
    if pose is None:
        raise InputError("navigate needs a pose estimate")
    lost = np.isnan(pose[:, 0])
    if not state.planned:  # global localisation: explore until every robot is localised
        if np.any(lost):
            if inputs.t_s >= state.next_s - 1e-9:
                name = next(iter(params.bearings_rad))
                v, omega = wander(
                    np.asarray(inputs.readings[name]),
                    params.bearings_rad[name],
                    params.wander_speed_m_s,
                )
                v, omega = np.where(lost, v, 0.0), np.where(lost, omega, 0.0)
                state = NavigateState(
                    state.navigation, v, omega, state.next_s + params.period_s, False
                )
            return state, _wheel_command(state, inputs, params, pose, ("waiting",) * pose.shape[0])
        nav = navigation_init(params.grid, pose, params.goals_m, params.navigation)
        zero = np.zeros(pose.shape[0])
        state = NavigateState(nav, zero, zero, inputs.t_s, True)
    heard = np.asarray(inputs.inbox.get("xy_m", pose[:, :2]))
    teammates = np.where(np.isfinite(heard), heard, pose[:, :2])  # none heard: our own
    ranges = {
        name: (inputs.readings[name], bearings)
        for name, bearings in params.bearings_rad.items()
        if name in inputs.readings
    }
    if inputs.t_s >= state.next_s - 1e-9:
        nav_inputs = NavigationInputs(
            pose=pose, ranges=ranges, teammates_xy_m=teammates, t_s=inputs.t_s
        )
        nav, v, omega = navigation_step(
            state.navigation, nav_inputs, params.navigation, params.period_s
        )
        state = NavigateState(nav, v, omega, state.next_s + params.period_s)
    return state, _wheel_command(state, inputs, params, pose, tuple(state.navigation.status))


def _wheel_command(
    state: NavigateState,
    inputs: DecideInputs,
    params: NavigateParams,
    pose: FloatArray,
    status: tuple[str, ...],
) -> WheelCommand:
    """The held (v, omega) as wheel references, with the series to record."""
    v, omega = state.v_m_s, state.omega_rad_s
    series: dict[str, FloatArray] = {
        "v_ref_m_s": np.asarray(v, dtype=float),
        "omega_ref_rad_s": np.asarray(omega, dtype=float),
        "status": np.array([float(_STATUS_CODE[s]) for s in status]),
    }
    for name in RANGE_READINGS:
        if name in inputs.readings:
            series[name] = np.asarray(inputs.readings[name], dtype=np.float32)
    return WheelCommand(
        reference_rad_s=body_to_wheels(np.asarray(v), np.asarray(omega), params.geometry),
        series=series,
        outbox={"xy_m": pose[:, :2].copy()},
        done=not any(s in _UNDER_WAY for s in status),
    )


_STATUS_CODE = {
    "moving": 0,
    "waiting": 1,
    "arrived": 2,
    "unreachable": 3,
    "start_blocked": 4,
    "goal_blocked": 5,
}
"""The navigation statuses as recorded in the ``status`` series (T, N)."""


def _figures(result: SimResult, metrics: dict[str, Any]) -> dict[str, bytes]:
    from firefleet.report.navigation import figures

    return figures(result)


KINDS = (
    TaskKind(
        name="navigate",
        metric_names=METRIC_NAMES,
        metrics=navigate_metrics,
        figures=_figures,
        decider=Decider(
            init=_init,
            decide=navigate_decide,
            series=("v_ref_m_s", "omega_ref_rad_s", "status", *RANGE_READINGS),
            uses_estimate=True,
        ),
        stages=navigate_stages,
    ),
)
"""The navigate kind."""
